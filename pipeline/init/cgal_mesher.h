#pragma once
/// Tetrahedralization of a closed triangle surface with CGAL Mesh_3. The CGAL code lives in
/// cgal_mesher.cpp only (one ~80 s, ~3 GB translation unit); this header is CGAL-free.
#include "pipeline/io/mesh_io.h"
#include "sim/core/tet_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Sizing and behaviour of the Mesh_3 run. Sizes are given relative to the target edge length
/// because CGAL's criteria bound radii, not edges: the ratios below were calibrated (see
/// tools/bench_init.sh) so that the mean tet edge comes out close to `edge_length`.
struct MesherOptions {
    Real edge_length = 0.025;  // target tet edge length [m]
    /// CGAL facet_size (radius of the surface Delaunay balls) / edge_length. An equilateral
    /// triangle of edge L has circumradius L/sqrt(3) = 0.577 L; refinement stops below the
    /// bound, so the bound sits higher: 0.7 and 0.75 below give a mean edge of 0.99 L on the
    /// bunny (0.6 and 0.65 gave 0.86 L).
    Real facet_size_ratio = 0.7;
    /// CGAL cell_size (tet circumradius bound) / edge_length. A regular tet of edge L has
    /// circumradius sqrt(6)/4 L = 0.61 L.
    Real cell_size_ratio = 0.75;
    /// CGAL facet_distance (max distance from a boundary facet's circumcenter to the input
    /// surface) / edge_length: the knob that decides how much volume the chords cut off. The
    /// bunny at the default sizing loses 0.2 % of its volume at 0.05 (0.3 % at 0.1).
    Real facet_distance_ratio = 0.05;
    Real facet_angle = 25;            // minimum boundary facet angle [deg]
    Real cell_radius_edge_ratio = 3;  // tet circumradius / shortest edge bound
    /// Sharp edges (dihedral angle of adjacent faces below 180 - feature_angle degrees) are
    /// detected and protected so boxes keep their corners; 0 turns feature detection off.
    Real feature_angle = 60;  // [deg]
    /// Parallel_tag (TBB): faster on several cores, but CGAL's concurrent refinement depends
    /// on thread scheduling, so two runs may give different meshes. Sequential_tag with the
    /// seed below is reproducible bit for bit.
    bool parallel = false;
    unsigned seed = 1;  // CGAL's default generator is reset to this, the domain's to seed - 1
    /// Sliver perturbation and exudation (Mesh_3's optimisers). Off by default: slivers only
    /// give a few particles a tiny share of volume, which MPM does not mind, and removing them
    /// costs more than the meshing itself (see tools/bench_init.sh).
    bool perturb = false;
    bool exude = false;
    Real optimizer_time_limit = 0;  // [s] per optimiser; 0 = until done
};

/// Tetrahedralizes the interior of a closed, outward-oriented, self-intersection-free surface
/// (check it first with check_input_surface). Returns the tets of the complex, positively
/// oriented, over the vertices they use only (ids 0..n-1); boundary and UVs are left empty.
/// Throws RuntimeError if CGAL produced no tets (e.g. edge_length far larger than the object).
/// @note options.edge_length must be > 0 (checked): mesher_options never gives less.
TetMesh tetrahedralize_surface(const InputSurface& surface, const MesherOptions& options);

}  // namespace mudcrack
