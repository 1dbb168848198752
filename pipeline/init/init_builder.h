#pragma once
/// mc-init's work without the files: from InitParams to the particle tet mesh (every tet vertex
/// is a particle), its rest volumes, boundary UVs and quality figures.
#include <functional>
#include <string>
#include <vector>

#include "pipeline/init/cgal_mesher.h"
#include "pipeline/init/init_params.h"
#include "pipeline/init/tet_mesh_ops.h"
#include "pipeline/io/mesh_io.h"
#include "sim/core/tet_mesh.h"

namespace mudcrack {

/// The tet edge length used when /init/edge_length is 0: 0.6 h [m].
/// @note Why 0.6 h: MPM codes use about 8 particles per grid cell (fewer lets the material
/// tear numerically between particles; many more costs time without visible detail). A Mesh_3
/// mesh with mean edge L has about one vertex per 0.55 L^3 on the bunny (a regular tet is
/// L^3 / 8.5, ~6 tets per vertex, plus a denser surface layer), so L = 0.6 h gives
/// h^3 / (0.55 * 0.216 h^3) = 8.4 in the bulk; measured on the 0.2 m^3 bunny at h = 0.05:
/// 16.2K particles, 10 per cell (h/2 would give 16 per cell).
/// @param h the simulation grid spacing [m]
Real default_edge_length(Real h);

/// Mesh_3 options for a shot: edge_length (or default_edge_length(h)) and the seed.
/// @param h the simulation grid spacing [m]; > 0 (the shot spec refuses others)
MesherOptions mesher_options(const InitParams& params, Real h);

/// The mesh source's surface: loaded (load_input_surface), scaled, translated, and with
/// fit_to_ground shifted so its lowest point is at y = 0. Not yet checked.
InputSurface load_placed_surface(const MeshSource& source);

/// Everything mc-init produces, in memory.
struct InitResult {
    TetMesh mesh;               // rest positions, tets, outward boundary, boundary UVs
    std::vector<Real> volume0;  // particle rest volumes [m^3], (n_particles)
    MeshQuality quality;
    // volume enclosed by the input surface (mesh source) [m^3]; 0 otherwise
    Real surface_volume = 0;
    // target edge length given to Mesh_3 (mesh source) [m]; 0 otherwise
    Real edge_length = 0;
    std::string uv_method;       // "transferred" (from the input's UVs) or "box projection"
    std::vector<Real> strength;  // p0 multipliers (params.strength_field), else empty
};

/// Called with a mesh source's bounds (lowest, highest corner [m]) once its surface is read,
/// placed and checked, before it is tetrahedralized: the shot's keys that depend on the body's
/// size are checked against them there (mc-init), as the loader checks a box's.
using SurfaceBoundsCheck = std::function<void(const Vec3& lo, const Vec3& hi)>;

/// Builds the source of `params`: a box lattice, a heightfield lattice, or a checked and
/// tetrahedralized surface (Mesh_3 with `mesher`; `check_bounds`, when given, sees its bounds
/// first). Then drops unused vertices, extracts the boundary, assigns UVs, computes rest volumes
/// and quality. Throws InputError for a bad source (bad mesh: what is wrong and where),
/// RuntimeError if the mesh comes out inverted.
InitResult build_init(const InitParams& params, const MesherOptions& mesher,
                      const SurfaceBoundsCheck& check_bounds = {});

/// build_init with mesher_options(params, h). @param h the simulation grid spacing [m]; > 0
InitResult build_init(const InitParams& params, Real h);

/// Finishes a tet mesh from any source (exposed for tests): drop unused vertices, boundary,
/// projected UVs (or transferred from `uv_source` if it has UVs), rest volumes, quality.
InitResult finish_tet_mesh(TetMesh mesh, const InputSurface* uv_source);

}  // namespace mudcrack
