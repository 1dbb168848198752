#pragma once
/// Per-frame particle-core surfacing (Tu et al. 2023 Section 6; docs/physics.md §5.3): extrapolate
/// the core-vertex copies with Eq. 13, weld them across intact edges, and emit the boundary
/// skin and the crack faces of broken edges as two meshes.
#include <cstdint>
#include <vector>

#include "sim/core/debris_points.h"
#include "sim/core/particle_frame.h"
#include "sim/core/tri_mesh.h"
#include "surfacing/core_topology.h"
#include "surfacing/shot_fracture.h"
#include "surfacing/surface_params.h"

namespace mudcrack {

/// Identity of a welded core vertex: its rest point and the smallest owner slot of its weld
/// class. Equal keys in the boundary and crack meshes are the same point, which stitches a
/// fragment's pieces into one closed surface.
inline uint64_t weld_key(RestPointKind kind, int32_t point, int rep) {
    return (uint64_t(kind) << 62) | (uint64_t(uint32_t(point)) << 2) | uint64_t(rep);
}

struct SurfacedFrame {
    TriMesh boundary;                         // skin of the original boundary faces, "boundary"
    TriMesh crack;                            // both sides of broken interfaces, "crack"
    std::vector<uint64_t> boundary_weld_key;  // weld_key of each boundary vertex
    std::vector<uint64_t> crack_weld_key;     // weld_key of each crack vertex
    int64_t broken_edges = 0;                 // edges with first_break <= frame
    int32_t fragments = 0;                    // fragments kept
    int32_t culled_fragments = 0;             // fragments below min_fragment_particles
    // plates mode (docs/physics.md §5.7): fragments are its pieces, face_fragment their ids
    int32_t debris_particles = 0;         // particles that tore loose (not meshed)
    int64_t wall_points_smoothed = 0;     // crack-wall rest points moved by the smoothing
    DebrisPoints debris;                  // filled when params.debris == DebrisOutput::Points
    std::vector<int32_t> particle_piece;  // piece of each particle (kDebris: none), (n_particles)
    std::vector<uint8_t> edge_cut;        // the edges the surface separates (broken, or in the
                                          // plates mode cut), which set the weld classes, (n_edges)
    std::vector<uint8_t> edge_settled;    // the cut edges whose sides have finished parting: a
                                          // vertex's position is made from the owners of its
                                          // class under these (plates mode in a sequence: cut
                                          // long enough ago that its gap has eased in at
                                          // open_speed; else edge_cut)
};

/// How many frames a fresh cut of the plates mode takes to ease in (FrameCores::opening in
/// core_surface.cpp): a cut at frame f moves its vertices beyond their particles in frames f to
/// f + easing_frames - 2 and is settled from f + easing_frames - 1; 0 when open_speed is 0
/// (cracks show at once). 10 at the default open_speed.
int easing_frames(const SurfaceParams& params);

/// Surfaces one frame. Deterministic: the result depends only on the arguments, never on the
/// thread count or on which other frames were surfaced before.
///
/// Boundary UVs are TetMesh::boundary_uv interpolated at the skin vertices' barycentric
/// coordinates; they are split at UV seams, while normals are shared across seams. Crack UVs are
/// triplanar_uv of the rest position by the dominant axis of the crack triangle's rest normal,
/// at the boundary's texture density (CoreTopology::uv_per_meter). Normals are area-weighted per
/// welded vertex. Saturation and alpha are averaged over the owners of each welded vertex.
/// In SurfaceMode::Plates the shot's fracture (shot_fracture.h) gives the frame its pieces and
/// cuts: face_fragment holds each face's piece id; crack walls are placed smoothly in rest space
/// and smoothed where they are over the shot's wall graph, their rims along the rim
/// (wall_smoothing.h, params.wall_smoothing steps each); the particles along the walls move by
/// their neighbourhood's fitted affine motion (wall_deformation.h); cores follow their particles'
/// rotation without the Jw scaling (a crack is as wide as the particles moved apart); a wall
/// vertex closer than close_gaps spacings to its far side in another piece meets it half way,
/// blending to its own position by 3 close_gaps, so a closed crack between pieces shows no gap
/// and an opening one does not pop; walls that reach no surface are not meshed.
/// @note At a crack tip inside a tet, the two sides of an interface share welded vertices and
///       their normals cancel; such a vertex takes the normal of its first face.
/// @param first_break first frame at which each edge broke (edge_breaks.h), (n_edges)
/// @param fracture the plates mode's fracture of the shot (shot_fracture.h), planned once from its
///        last frame; with it, a crack cut after its particles had moved apart parts at a bounded
///        speed from frame to frame. Without it, the plates mode plans it from this frame and
///        shows the frame on its own: every crack as open as its particles.
/// Throws InputError when the frame does not fit the mesh (check_frame_fits).
SurfacedFrame surface_frame(const CoreTopology& topo, const ParticleFrame& frame,
                            const std::vector<int32_t>& first_break, const SurfaceParams& params,
                            const ShotFracture* fracture = nullptr);

}  // namespace mudcrack
