#pragma once
/// The plates mode's fracture of a whole shot (docs/physics.md §5.7), decided once from its last
/// frame, the way a post-fracture tool cuts the rest geometry once where the particles stretched.
///
/// Deciding the pieces frame by frame let a band particle change sides as its neighbours' openings
/// changed, and a wall appear or vanish with it, so the welded vertices of a curling rim jumped by
/// centimetres between frames while the particles moved by a millimetre. Here the last frame's
/// pieces fix which side of each crack every particle is on, and where the walls run in the rest
/// state; frame n shows the cuts the soil has made by then. A wall appears only where and when an
/// edge breaks, a particle never changes side, and a wall vertex never moves in the rest state: a
/// frame's mesh moves with its particles alone.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "sim/core/particle_frame.h"
#include "surfacing/core_topology.h"
#include "surfacing/pieces.h"
#include "surfacing/surface_params.h"
#include "surfacing/wall_deformation.h"
#include "surfacing/wall_smoothing.h"

namespace mudcrack {

/// x_q - x_p of each edge (p, q) the shot cuts, the frame before its cut (record_cut_edges):
/// 16 bytes per cut edge, where a vector over every edge took 12 per edge.
struct CutEdgeVectors {
    std::vector<int32_t> edge;  // the edges the last frame cuts, ascending
    std::vector<Vec3f> vector;  // per edge: x_q - x_p; zero where that frame was not recorded
    /// The vector of cut edge e (one of `edge`).
    const Vec3f& of(int32_t e) const {
        return vector[std::lower_bound(edge.begin(), edge.end(), e) - edge.begin()];
    }
};

struct ShotFracture {
    Pieces last;                     // the pieces of the last frame (find_pieces)
    std::vector<int32_t> cut_frame;  // per edge: the first frame it is cut; kNeverBroken if never
    CutEdgeVectors cut_edges;        // where each cut edge's particles stood before its cut
    WallRestPositions walls;         // the last frame's walls, placed in the rest state
    WallGraph wall_graph;            // and as a graph, to smooth them where they are
    WallDeformation wall_motion;     // the smoothed motion of the particles along them
};

/// The fracture of a shot whose last frame is `last_frame`. `first_break` is the shot's break
/// history (edge_breaks.h), params its plates settings. A cut edge is cut from the frame it broke;
/// one that never broke (between two band particles that joined different sides) from the frame
/// both its particles are damaged, at the latest the last frame. Deterministic.
ShotFracture plan_shot_fracture(const CoreTopology& topo, const ParticleFrame& last_frame,
                                const std::vector<int32_t>& first_break,
                                const SurfaceParams& params);

/// Records into fracture.cut_edges each edge (p, q) cut in the frame after `frame`: x_q - x_p,
/// where its particles stood the last frame they were welded. A fresh crack shows at once what
/// they moved apart since, and eases in only the rest of its jump (FrameCores::opening in
/// core_surface.cpp). Each frame writes only its own edges, so frames can be recorded in any
/// order, also in parallel.
void record_cut_edges(const CoreTopology& topo, const ParticleFrame& frame, ShotFracture& fracture);

/// The frames record_cut_edges needs to surface frames [first, last] whose cuts ease in over
/// `easing` frames (easing_frames in core_surface.h), ascending: each frame in the cache
/// [cache_first, cache_last] after which an edge is cut that is still easing in one of them. A
/// cut in the cache's first frame has no frame before it: it shows at once.
std::vector<int> frames_before_cuts(const ShotFracture& fracture, int cache_first, int first,
                                    int last, int easing);

/// Records what surfacing frames [first, last] of a cache that starts at cache_first needs, with
/// cuts easing in over `easing` frames: record_cut_edges of each of frames_before_cuts, loaded by
/// load(n) one at a time (this runs beside the shot's fracture, before any frame's surfacing, and
/// two frames at once raised the demo's peak by 10 %). The one way mc-surface and mc-measure
/// prepare a fracture for fresh cracks.
template <class LoadFrame>
void record_cut_edges_for(const CoreTopology& topo, ShotFracture& fracture, int cache_first,
                          int first, int last, int easing, LoadFrame&& load) {
    for (int n : frames_before_cuts(fracture, cache_first, first, last, easing))
        record_cut_edges(topo, load(n), fracture);
}

/// The pieces of frame `frame` (at most the last frame): the particles joined through the edges
/// not yet cut. Each such piece holds one or more of the last frame's pieces and takes the
/// smallest of their ids, so an id lasts until a crack splits its piece; a piece holding none of
/// them is debris. At the last frame these are exactly `fracture.last`.
Pieces pieces_at_frame(const CoreTopology& topo, const ShotFracture& fracture, int frame);

}  // namespace mudcrack
