#pragma once
/// Welding of core-vertex copies across intact edges (docs/physics.md §5.3 step 4), as lookup
/// tables. A rest point is owned by the corners of its simplex; the copies of two owners are welded
/// when the edge between them is unbroken, transitively. Because every owner pair of a simplex is
/// one of its edges, welding is local to the simplex: a union-find over at most 4 owners and 6
/// edges, tabulated once for every broken-edge mask.
#include <array>
#include <cstdint>

namespace mudcrack {

/// Owner pairs of a triangle's edges, for owners sorted by particle id: bit k of a face mask.
constexpr std::array<std::array<int, 2>, 3> kFaceEdgeOwners = {{{0, 1}, {0, 2}, {1, 2}}};

/// rep[j]: the smallest owner slot welded to owner slot j (the class representative).
using WeldReps = std::array<int8_t, 4>;

/// Weld classes of a tet centroid's 4 owners (tet corner order) for a mask of broken local
/// edges (bit k = kTetEdgeCorners[k] broken).
const WeldReps& tet_weld_reps(unsigned broken_mask);
/// Weld classes of a face centroid's 3 owners (sorted by particle id) for a mask of broken
/// edges (bit k = kFaceEdgeOwners[k] broken).
const WeldReps& face_weld_reps(unsigned broken_mask);

}  // namespace mudcrack
