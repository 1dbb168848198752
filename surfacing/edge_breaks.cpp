#include "surfacing/edge_breaks.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/core/error.h"
#include "sim/core/parallel.h"

namespace mudcrack {

Real break_threshold(Real jw_p, Real jw_q, const SurfaceParams& params) {
    if (params.mode == SurfaceMode::Wang2019) return params.zeta;
    if (params.length_consistent)
        return Real(0.5) * (std::cbrt(jw_p) + std::cbrt(jw_q)) * params.zeta;
    return Real(0.5) * (jw_p + jw_q) * params.zeta;
}

void check_frame_fits(const CoreTopology& topo, const ParticleFrame& frame) {
    const std::string where = "frame " + std::to_string(frame.frame) + ": ";
    const size_t n = static_cast<size_t>(topo.n_particles);
    if (frame.P.size() != n)
        throw InputError(where + "has " + std::to_string(frame.P.size()) +
                         " particles; the tet mesh has " + std::to_string(n) +
                         " (a cache from another shot?)");
    auto check = [&](const char* name, size_t size) {
        if (size != 0 && size != n)
            throw InputError(where + "attribute " + name + " has " + std::to_string(size) +
                             " values; expected 0 or " + std::to_string(n));
    };
    check("Jw", frame.Jw.size());
    check("Fe", frame.Fe.size());
    check("saturation", frame.saturation.size());
    check("alpha", frame.alpha.size());
}

std::vector<int32_t> no_edge_breaks(const CoreTopology& topo) {
    return std::vector<int32_t>(topo.edges.size(), kNeverBroken);
}

int64_t record_edge_breaks(const CoreTopology& topo, const ParticleFrame& frame,
                           const SurfaceParams& params, std::vector<int32_t>& first_break) {
    check_frame_fits(topo, frame);
    if (first_break.size() != topo.edges.size())
        throw InputError("edge break history has " + std::to_string(first_break.size()) +
                         " edges; the tet mesh has " + std::to_string(topo.edges.size()));
    const bool has_jw = !frame.Jw.empty();
    const int32_t n = frame.frame;
    return parallel_reduce(
        topo.n_edges(), int64_t(0),
        [&](int64_t e) -> int64_t {
            const auto [p, q] = topo.edges[e];
            const Real length = (frame.P[p].cast<Real>() - frame.P[q].cast<Real>()).norm();
            const Real jw_p = has_jw ? Real(frame.Jw[p]) : Real(1),
                       jw_q = has_jw ? Real(frame.Jw[q]) : Real(1);
            if (!(length > break_threshold(jw_p, jw_q, params) * topo.rest_length[e])) return 0;
            first_break[e] = std::min(first_break[e], n);
            return 1;
        },
        [](int64_t a, int64_t b) { return a + b; });
}

void merge_edge_breaks(std::vector<int32_t>& into, const std::vector<int32_t>& from) {
    if (into.size() != from.size())
        throw RuntimeError("merge_edge_breaks: " + std::to_string(into.size()) + " vs " +
                           std::to_string(from.size()) + " edges");
    for (size_t e = 0; e < into.size(); ++e) into[e] = std::min(into[e], from[e]);
}

int64_t count_broken_edges(const std::vector<int32_t>& first_break, int frame) {
    return parallel_reduce(
        static_cast<int64_t>(first_break.size()), int64_t(0),
        [&](int64_t e) -> int64_t { return first_break[e] <= frame ? 1 : 0; },
        [](int64_t a, int64_t b) { return a + b; });
}

}  // namespace mudcrack
