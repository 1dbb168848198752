#include "surfacing/shot_fracture.h"

#include <algorithm>

#include "sim/core/parallel.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/fragments.h"

namespace mudcrack {
namespace {

/// [particle spacings] The neighbourhood whose motion a wall particle follows (wall_deformation.h):
/// 3 spacings, a cell and a half, some 50 particles on its side of a crack. Measured on the
/// demo's last frame (mc-measure, 2026-11-26, 35 wall_smoothing steps): crack-wall roughness 16.9
/// degrees at 2 spacings, 14.7 at 3; the rims' saw-tooth at the particle spacing is gone at both.
constexpr Real kWallMotionRadius = 3;

/// [particle spacings] How far the fitted motion may carry a point of a wall particle's core from
/// where the particle's own motion puts it (WallDeformation::max_lead). A particle torn loose from
/// its neighbourhood's motion stands centimetres from the fit, and the distance swings as it
/// tears; measured on the demo over its 40 frames (mc-measure --motion, 2026-11-27), the largest
/// vertex jump beyond its particles was 0.289 cells unbounded, 0.250 at 3 spacings, 0.244 at 2 and
/// 0.236 at 1.5 and 1, while the last frame's walls stayed 14.1 degrees rough.
constexpr Real kWallMotionMaxLead = 1.5;

}  // namespace

ShotFracture plan_shot_fracture(const CoreTopology& topo, const ParticleFrame& last_frame,
                                const std::vector<int32_t>& first_break,
                                const SurfaceParams& params) {
    const int last = last_frame.frame;
    std::vector<uint8_t> is_broken(topo.edges.size());
    parallel_for(topo.n_edges(), [&](int64_t e) { is_broken[e] = first_break[e] <= last ? 1 : 0; });
    PieceParams piece_params;
    piece_params.min_width = params.min_piece_size * params.cell_size;
    piece_params.debris_gap = params.debris_gap;

    ShotFracture fracture;
    fracture.last = find_pieces(topo, last_frame, is_broken, piece_params);
    // the frame each particle was first damaged (one of its edges broke)
    std::vector<int32_t> first_damage(topo.n_particles, kNeverBroken);
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        for (int32_t p : topo.edges[e]) first_damage[p] = std::min(first_damage[p], first_break[e]);
    fracture.cut_frame.assign(topo.edges.size(), kNeverBroken);
    parallel_for(topo.n_edges(), [&](int64_t e) {
        if (!fracture.last.is_cut[e]) return;
        const auto [p, q] = topo.edges[e];
        fracture.cut_frame[e] = is_broken[e]
                                    ? first_break[e]
                                    : std::min(last, std::max(first_damage[p], first_damage[q]));
    });
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (fracture.last.is_cut[e]) fracture.cut_edges.edge.push_back(e);
    fracture.cut_edges.vector.assign(fracture.cut_edges.edge.size(), Vec3f::Zero());
    fracture.walls = smooth_walls(topo, fracture.last.is_cut, params.wall_smoothing);
    if (params.wall_smoothing > 0) {
        fracture.wall_graph = plan_wall_graph(topo, fracture.last.is_cut);
        const Real spacing = mean_particle_spacing(topo);
        fracture.wall_motion =
            plan_wall_deformation(topo, fracture.last.is_cut, fracture.cut_frame, fracture.last.id,
                                  kWallMotionRadius * spacing, kWallMotionMaxLead * spacing);
    }
    return fracture;
}

void record_cut_edges(const CoreTopology& topo, const ParticleFrame& frame,
                      ShotFracture& fracture) {
    check_frame_fits(topo, frame);
    const int32_t next = frame.frame + 1;
    CutEdgeVectors& cut = fracture.cut_edges;
    parallel_for(static_cast<int64_t>(cut.edge.size()), [&](int64_t i) {
        const int32_t e = cut.edge[i];
        if (fracture.cut_frame[e] != next) return;
        const auto [p, q] = topo.edges[e];
        cut.vector[i] = frame.P[q] - frame.P[p];
    });
}

std::vector<int> frames_before_cuts(const ShotFracture& fracture, int cache_first, int first,
                                    int last, int easing) {
    // a cut at f eases in frames f .. f + easing - 2: those that reach [first, last]
    const int lo = std::max(cache_first, first + 1 - easing), hi = last - 1;
    std::vector<uint8_t> needed(std::max(0, hi - lo + 1), 0);
    for (int32_t f : fracture.cut_frame)
        if (f != kNeverBroken && f - 1 >= lo && f - 1 <= hi) needed[f - 1 - lo] = 1;
    std::vector<int> frames;
    for (int i = 0; i < int(needed.size()); ++i)
        if (needed[i]) frames.push_back(lo + i);
    return frames;
}

Pieces pieces_at_frame(const CoreTopology& topo, const ShotFracture& fracture, int frame) {
    const Pieces& last = fracture.last;
    Pieces pieces;
    pieces.is_cut.resize(topo.edges.size());
    parallel_for(topo.n_edges(),
                 [&](int64_t e) { pieces.is_cut[e] = fracture.cut_frame[e] <= frame ? 1 : 0; });
    const Fragments joined = find_fragments(topo, pieces.is_cut, 1);
    // each joined part takes the smallest id of the last frame's pieces in it
    std::vector<int32_t> part_id(joined.count, kDebris);
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        int32_t& id = part_id[joined.id[p]];
        if (last.id[p] != kDebris && (id == kDebris || last.id[p] < id)) id = last.id[p];
    }
    pieces.id.resize(topo.n_particles);
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        pieces.id[p] = part_id[joined.id[p]];
        pieces.debris += pieces.id[p] == kDebris;
    }
    for (int32_t id : part_id) pieces.count += id != kDebris;
    // debris remembers the plate particle it tore from, whichever piece that is in now
    pieces.root = last.root;
    return pieces;
}

}  // namespace mudcrack
