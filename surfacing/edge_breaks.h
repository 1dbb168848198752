#pragma once
/// The break history of Tu et al. 2023 Eq. 14: an edge (p, q) is broken at frame n when its
/// stretch ratio exceeded the threshold at ANY frame t <= n (a permanent state). So that frames
/// can be surfaced in any order and in parallel, the history is kept as the first frame at which
/// each edge broke; it is a minimum over frames, so it too can be accumulated in any order.
#include <cstdint>
#include <limits>
#include <vector>

#include "sim/core/particle_frame.h"
#include "surfacing/core_topology.h"
#include "surfacing/surface_params.h"

namespace mudcrack {

/// first_break_frame of an edge that never broke.
constexpr int32_t kNeverBroken = std::numeric_limits<int32_t>::max();

/// The stretch-ratio threshold of an edge (Eq. 14): 0.5 (Jw_p + Jw_q) zeta in Ours mode,
/// 0.5 (Jw_p^(1/3) + Jw_q^(1/3)) zeta with length_consistent (docs/physics.md §5.5), zeta in
/// Wang2019 mode (Jw = 1). @param jw_p, jw_q pore deformation determinants [-]
Real break_threshold(Real jw_p, Real jw_q, const SurfaceParams& params);

/// Throws InputError ("frame N: ...") when a frame does not fit the mesh: particle count, or an
/// attribute (Jw, Fe, saturation, alpha) that is neither empty nor one per particle.
void check_frame_fits(const CoreTopology& topo, const ParticleFrame& frame);

/// A first-break-frame array with no edge broken, (n_edges).
std::vector<int32_t> no_edge_breaks(const CoreTopology& topo);

/// Applies Eq. 14 to every edge at frame.frame: first_break[e] = min(first_break[e], frame.frame)
/// for each edge stretched past its threshold. Commutes across frames. Returns the number of
/// edges over the threshold in this frame.
int64_t record_edge_breaks(const CoreTopology& topo, const ParticleFrame& frame,
                           const SurfaceParams& params, std::vector<int32_t>& first_break);

/// into[e] = min(into[e], from[e]): combines histories recorded from disjoint sets of frames.
void merge_edge_breaks(std::vector<int32_t>& into, const std::vector<int32_t>& from);

/// Edges broken at frame n (first_break <= n).
int64_t count_broken_edges(const std::vector<int32_t>& first_break, int frame);

}  // namespace mudcrack
