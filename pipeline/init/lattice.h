#pragma once
/// Procedural tet meshes on lattices: the box slab (regular or jittered) and the column-mapped
/// lattice under a heightfield. Cells are split into 6 tets with the Kuhn (Freudenthal) split,
/// which conforms across neighbouring cells, so particle counts are exact: prod(n_i + 1).
#include <string>
#include <vector>

#include "pipeline/init/init_params.h"
#include "sim/core/tet_mesh.h"

namespace mudcrack {

/// Sources refuse to make more particles than this (a typo in a spacing or edge length should
/// be an error message, not an out-of-memory kill): 50 million.
constexpr double kMaxInitParticles = 5e7;

/// A particle count, computed in double so that a typo cannot overflow it, as a whole number
/// ("2710806301") for messages.
std::string count_text(double count);

/// Cells per axis of a box of the given extent: round(extent / spacing), at least 1. The
/// spacing is then stretched per axis to extent / cells so the box stays exact.
/// @note A double, whole-valued: a spacing far below the extent gives more cells than an int
/// holds, and callers compare the count with kMaxInitParticles before they index with it.
double lattice_cells(Real extent, Real spacing);

/// Lattice vertex id of (i, j, k) on an (nx+1) x (ny+1) x (nz+1) lattice, x fastest.
inline int32_t lattice_index(int i, int j, int k, int nx, int ny) {
    return static_cast<int32_t>(i + (nx + 1) * (j + (ny + 1) * k));
}

/// The 6 Kuhn tets of every cell of an nx x ny x nz lattice, positively oriented for a lattice
/// mapped by an orientation-preserving map (x right, y up, z towards the viewer).
std::vector<Tet> kuhn_tets(int nx, int ny, int nz);

/// A box slab: regular lattice, or jittered (interior points moved by up to
/// jitter * spacing, seeded; a move that would leave an incident tet with less than a fifth of
/// its rest volume is re-drawn, and after a few tries the point stays put, so every tet stays
/// positive). With Footprint::Ellipse only the columns of cells whose centre lies in the ellipse
/// inscribed in the box's x-z rectangle are kept, and the rim's points are moved onto the
/// ellipse along the ray from its centre, each rim column as one, as far as the same rule allows
/// (by eighths); unused points are dropped. Throws ShotValueError naming /source/box/... keys
/// for an empty box or bad spacing.
TetMesh make_box_tets(const BoxSource& box, unsigned seed);

/// The column-mapped lattice over the rectangle [x0, x0 + sx] x [z0, z0 + sz] in XZ: columns
/// on a regular (nx+1) x (nz+1) grid, each with ny+1 points spread evenly from y = 0 to its
/// top height, top[i + (nx+1) k] (must be > 0) [m]. Split into Kuhn tets. Throws RuntimeError
/// if a tet is not positive.
TetMesh make_column_lattice_tets(Real x0, Real z0, Real sx, Real sz, int nx, int ny, int nz,
                                 const std::vector<Real>& top);

}  // namespace mudcrack
