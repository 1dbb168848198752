#pragma once
/// Source-independent work on the init tet mesh: dropping unused vertices, extracting the
/// outward boundary, checking orientation, and measuring quality.
#include <cstdint>
#include <vector>

#include "sim/core/tet_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Removes vertices referenced by no tet and renumbers the rest 0..n-1 in their old order, so
/// particle ids are contiguous. Boundary faces are renumbered too.
void drop_unused_vertices(TetMesh& mesh);

/// Faces that belong to exactly one tet, wound counter-clockwise seen from outside (their
/// normal points away from the tet). Tets must be positively oriented. Sorted by vertex ids, so
/// the result does not depend on tet order.
std::vector<Tri> extract_boundary_faces(const std::vector<Tet>& tets);

/// Number of tets whose signed volume is <= min_volume [m^3].
int64_t count_non_positive_tets(const TetMesh& mesh, Real min_volume = 0);

/// Sum of the tets' signed volumes [m^3].
Real total_tet_volume(const TetMesh& mesh);

/// The six interior dihedral angles of tet (a,b,c,d) [deg], at edges ab, ac, ad, bc, bd, cd.
std::array<Real, 6> dihedral_angles_deg(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// What the log and the manifest report about an init mesh.
struct MeshQuality {
    int64_t particles = 0;
    int64_t tets = 0;
    int64_t boundary_faces = 0;
    Real min_dihedral_deg = 0;  // smallest dihedral angle over all tets [deg]
    Real max_dihedral_deg = 0;  // largest dihedral angle over all tets [deg]
    Real mean_edge_length = 0;  // mean over the tets' edges (interior edges counted per tet) [m]
    Real tet_volume = 0;        // sum of tet volumes = sum of particle volumes [m^3]
    Vec3 bbox_min = Vec3::Zero();
    Vec3 bbox_max = Vec3::Zero();
};

/// Counts, dihedral angle range, mean edge length, volume and bounding box of `mesh`.
MeshQuality measure_quality(const TetMesh& mesh);

}  // namespace mudcrack
