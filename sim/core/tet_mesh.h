#pragma once
/// The rest-space tetrahedral mesh made by mc-init: every vertex is an MPM particle (its index
/// is the particle id). Read by the simulation (rest volumes) and the surfacing (particle cores).
#include <Eigen/Geometry>  // cross() in signed_tet_volume
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

struct TetMesh {
    std::vector<Vec3> X;                           // rest positions [m], (n_vertices)
    std::vector<Tet> tets;                         // positively oriented corners, (n_tets)
    std::vector<Tri> boundary;                     // boundary faces, outward (CCW), (n_boundary)
    std::vector<std::array<Vec2, 3>> boundary_uv;  // per-corner UVs of `boundary`, (n_boundary)
};

/// Signed volume of tet (a,b,c,d): positive when (b-a, c-a, d-a) is right-handed [m^3].
inline Real signed_tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    return (b - a).dot((c - a).cross(d - a)) / Real(6);
}

/// Rest volume per particle: a quarter of each incident tet's volume, so the particle volumes
/// sum to the mesh volume exactly [m^3], (n_vertices).
std::vector<Real> particle_rest_volumes(const TetMesh& mesh);

}  // namespace mudcrack
