#pragma once
/// Measures of the surfacing's meshes as an artist sees them in a close-up (docs/physics.md
/// §5.7): how many pieces and chips, whether each piece is closed, how rough the crack walls are,
/// how much wall there is per metre of crack on the top, and how far vertices jump from frame to
/// frame beyond what their particles moved.
#include <cstdint>
#include <vector>

#include "sim/core/particle_frame.h"
#include "sim/core/tri_mesh.h"
#include "sim/core/types.h"
#include "surfacing/core_surface.h"
#include "surfacing/core_topology.h"

namespace mudcrack {

struct MeshPieces {
    int32_t pieces = 0;                 // distinct face_fragment ids over both meshes
    int32_t chips = 0;                  // pieces under 2 h across (piece_width of their vertices)
    double chip_triangle_fraction = 0;  // share of all triangles that belong to chips
    int32_t open_pieces = 0;            // pieces with an edge not shared by exactly two triangles
    int64_t open_edges = 0;             // such edges, over all pieces
    int64_t hole_edges = 0;             // of those, edges of an odd number of triangles: a hole's
                                        // rim (an even number is sheets that touch, such as the
                                        // two sides of a crack not yet open)
    double crack_roughness_deg = 0;     // area-weighted mean angle between neighbouring crack
                                        // triangles' normals [degrees]
    double crack_area = 0;              // crack-wall area, one side of each crack [m^2]
    double top_crack_length = 0;        // crack line on the top (rims where walls meet up-facing
                                        // skin), one side of each crack [m]
    double crack_area_per_metre = 0;    // crack_area / top_crack_length [m^2/m]
};

/// Pieces are the faces' face_fragment ids (a mesh without them is one piece); a piece's
/// triangles are joined through vertices at identical positions, in both meshes. A chip is a
/// piece whose vertices are under 2 cell across (their second principal width, piece_width).
/// @param cell the shot's /sim/h [m]
MeshPieces measure_mesh_pieces(const TriMesh& boundary, const TriMesh& crack, Real cell);

struct SurfaceMotion {
    int64_t vertices_compared = 0;  // vertices with the same weld key and piece in both frames
    double jump_max_cells = 0;      // largest move beyond its particles' moves, in cells of h
    double jump_p99_cells = 0;      // its 99th percentile
    int64_t piece_changes = 0;      // particles that moved from one piece to another that both
                                    // exist in both frames (a stable piece keeps its particles)
};

/// How the surfacing of frame b moved from frame a (consecutive frames): each vertex present in
/// both (same weld key, same piece) jumps by how far its move lies from every blend of the moves
/// of the particles it follows (the convex hull of their moves). Those are the owners of its rest
/// point in its weld class under a's settled cuts (SurfacedFrame::edge_settled): its class, and
/// while a fresh crack parts, the class it had before the cut. So a crack that opens as its
/// particles part does not count, nor a side that eases from where its old class was welded at
/// the plates mode's open_speed while its particles tear apart faster; a vertex that snaps from
/// where its class was welded before to where it is welded now, or that smoothing moves away from
/// its particles, does.
/// @param piece_a, piece_b the piece of each particle in a and b (SurfacedFrame::particle_piece)
SurfaceMotion measure_surface_motion(const CoreTopology& topo, const SurfacedFrame& a,
                                     const ParticleFrame& frame_a, const SurfacedFrame& b,
                                     const ParticleFrame& frame_b, Real cell);

}  // namespace mudcrack
