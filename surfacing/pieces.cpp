#include "surfacing/pieces.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>
#include <utility>

#include "sim/core/parallel.h"
#include "surfacing/fragments.h"

namespace mudcrack {
namespace {

/// The edges at each particle, as CSR: the edge ids of particle p are edge[begin[p] .. begin[p+1]).
struct ParticleEdges {
    std::vector<int32_t> begin, edge;

    explicit ParticleEdges(const CoreTopology& topo)
        : begin(topo.n_particles + 1, 0),
          edge(2 * topo.edges.size()) {
        for (const auto& pq : topo.edges) {
            ++begin[pq[0] + 1];
            ++begin[pq[1] + 1];
        }
        for (int32_t p = 0; p < topo.n_particles; ++p) begin[p + 1] += begin[p];
        std::vector<int32_t> fill(begin.begin(), begin.end() - 1);
        for (int32_t e = 0; e < topo.n_edges(); ++e) {
            edge[fill[topo.edges[e][0]]++] = e;
            edge[fill[topo.edges[e][1]]++] = e;
        }
    }
};

/// A path's rest length counts this much beside its opening: it only breaks ties between paths
/// that opened alike (most open none at all).
constexpr Real kRestLengthWeight = 1e-3;

int32_t other_end(const CoreTopology& topo, int32_t e, int32_t p) {
    return topo.edges[e][0] == p ? topo.edges[e][1] : topo.edges[e][0];
}

/// Multi-source shortest paths from every particle with root[p] >= 0 into the particles with
/// root[p] == -1 that `may_enter` admits, along paths that cost at most max_cost; each particle
/// reached takes the root (and piece) of the path that reaches it first. Ties go to the smaller
/// root id, so the result is deterministic.
template <class Cost>
void grow_from_roots(const CoreTopology& topo, const ParticleEdges& adj, std::vector<int32_t>& root,
                     const std::vector<uint8_t>& may_enter, Real max_cost, Cost&& cost) {
    using Item = std::pair<Real, int32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    std::vector<Real> dist(topo.n_particles, std::numeric_limits<Real>::infinity());
    for (int32_t p = 0; p < topo.n_particles; ++p)
        if (root[p] >= 0) {
            dist[p] = 0;
            queue.push({0, p});
        }
    while (!queue.empty()) {
        const auto [d, p] = queue.top();
        queue.pop();
        if (d > dist[p]) continue;
        for (int32_t i = adj.begin[p]; i < adj.begin[p + 1]; ++i) {
            const int32_t e = adj.edge[i], q = other_end(topo, e, p);
            if (!may_enter[q]) continue;
            const Real next = d + cost(e);
            if (!(next <= max_cost)) continue;
            if (next < dist[q] || (next == dist[q] && root[p] < root[q])) {
                dist[q] = next;
                root[q] = root[p];
                queue.push({next, q});
            }
        }
    }
}

/// Whether two plate particles are on the same side of the cracks near them: joined through at
/// most kSideHops edges of plate particles. Across a crack the plate particles join only around
/// its end, or not at all, so the two sides of a crack are farther apart than that, except within
/// about kSideHops / 2 particles of where it ends: there the wall closes, as a crack tapers.
class SameSide {
public:
    SameSide(const CoreTopology& topo, const ParticleEdges& adj,
             const std::vector<uint8_t>& is_band, const std::vector<uint8_t>& edge_off)
        : m_topo(topo),
          m_adj(adj),
          m_band(is_band),
          m_off(edge_off),
          m_stamp(topo.n_particles, 0) {}

    bool operator()(int32_t a, int32_t b) {
        if (a == b) return true;
        const uint64_t key = (uint64_t(uint32_t(std::min(a, b))) << 32) | uint32_t(std::max(a, b));
        const auto known = m_known.find(key);
        if (known != m_known.end()) return known->second;
        const bool joined = search(a, b);
        m_known.emplace(key, joined);
        return joined;
    }

private:
    bool search(int32_t a, int32_t b) {
        ++m_visit;
        m_ring.assign(1, a);
        m_stamp[a] = m_visit;
        for (int hop = 0, begin = 0; hop < kSideHops; ++hop) {
            const int end = int(m_ring.size());
            for (int i = begin; i < end; ++i)
                for (int32_t k = m_adj.begin[m_ring[i]]; k < m_adj.begin[m_ring[i] + 1]; ++k) {
                    const int32_t e = m_adj.edge[k], q = other_end(m_topo, e, m_ring[i]);
                    if (m_off[e] || m_band[q] || m_stamp[q] == m_visit) continue;
                    if (q == b) return true;
                    m_stamp[q] = m_visit;
                    m_ring.push_back(q);
                }
            begin = end;
        }
        return false;
    }

    static constexpr int kSideHops = 3;
    const CoreTopology& m_topo;
    const ParticleEdges& m_adj;
    const std::vector<uint8_t>& m_band;
    const std::vector<uint8_t>& m_off;
    std::vector<uint32_t> m_stamp;
    uint32_t m_visit = 0;
    std::vector<int32_t> m_ring;
    std::unordered_map<uint64_t, bool> m_known;
};

}  // namespace

Real piece_width(const Vec3& sum, const Mat3& sum_outer, int64_t count, Real spacing) {
    if (count < 2) return spacing;
    const Vec3 mean = sum / Real(count);
    const Mat3 cov = sum_outer / Real(count) - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov, Eigen::EigenvaluesOnly);
    // ascending: [1] is the middle one
    const Real lambda2 = std::max(Real(0), eig.eigenvalues()[1]);
    return std::sqrt(12 * lambda2 + spacing * spacing);
}

Real mean_particle_spacing(const CoreTopology& topo) {
    Real volume = 0;
    for (const Tet& t : topo.tets)
        volume += (topo.X[t[1]] - topo.X[t[0]])
                      .cross(topo.X[t[2]] - topo.X[t[0]])
                      .dot(topo.X[t[3]] - topo.X[t[0]]) /
                  6;
    return topo.n_particles > 0 ? std::cbrt(volume / topo.n_particles) : Real(0);
}

Pieces find_pieces(const CoreTopology& topo, const ParticleFrame& frame,
                   const std::vector<uint8_t>& is_broken, const PieceParams& params) {
    const int32_t n = topo.n_particles;
    // plate cores: the soil no crack touched, i.e. the particles without a broken edge, joined
    // through their edges (a damaged particle is band, however it still hangs together)
    std::vector<uint8_t> is_damaged(n, 0), core_edge_off(topo.edges.size());
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (is_broken[e]) is_damaged[topo.edges[e][0]] = is_damaged[topo.edges[e][1]] = 1;
    parallel_for(topo.n_edges(), [&](int64_t e) {
        core_edge_off[e] =
            is_broken[e] || is_damaged[topo.edges[e][0]] || is_damaged[topo.edges[e][1]];
    });
    const Fragments frag = find_fragments(topo, core_edge_off, 1);

    // plates: fragments at least min_width across, named by their smallest particle
    const Real spacing = mean_particle_spacing(topo);
    std::vector<Vec3> sum(frag.count, Vec3::Zero());
    std::vector<Mat3> sum_outer(frag.count, Mat3::Zero());
    std::vector<int64_t> count(frag.count, 0);
    std::vector<int32_t> smallest(frag.count, -1);
    for (int32_t p = 0; p < n; ++p) {
        const int32_t f = frag.id[p];
        sum[f] += topo.X[p];
        sum_outer[f] += topo.X[p] * topo.X[p].transpose();
        if (count[f]++ == 0) smallest[f] = p;
    }
    std::vector<uint8_t> is_plate(frag.count);
    for (int32_t f = 0; f < frag.count; ++f)
        is_plate[f] = !is_damaged[smallest[f]] &&
                      piece_width(sum[f], sum_outer[f], count[f], spacing) >= params.min_width;

    Pieces pieces;
    pieces.root.assign(n, -1);
    std::vector<uint8_t> is_band(n);
    for (int32_t p = 0; p < n; ++p) {
        is_band[p] = is_damaged[p] || !is_plate[frag.id[p]] ? 1 : 0;
        if (!is_band[p]) pieces.root[p] = p;
    }

    // the band joins the plate it moved with: along the path that opened least (the sum over its
    // edges of how much longer than at rest they are), within debris_gap; ties go to the shorter
    // path at rest
    const ParticleEdges adj(topo);
    std::vector<Real> opening(topo.edges.size());
    parallel_for(topo.n_edges(), [&](int64_t e) {
        const auto [p, q] = topo.edges[e];
        opening[e] =
            std::max(Real(0), Real((frame.P[p] - frame.P[q]).norm()) - topo.rest_length[e]);
    });
    const Real max_opening = params.debris_gap * spacing;
    grow_from_roots(topo, adj, pieces.root, is_band, max_opening, [&](int32_t e) {
        return opening[e] + kRestLengthWeight * topo.rest_length[e];
    });
    pieces.id.assign(n, kDebris);
    std::vector<uint8_t> is_debris(n, 0);
    for (int32_t p = 0; p < n; ++p) {
        if (pieces.root[p] >= 0)
            pieces.id[p] = smallest[frag.id[pieces.root[p]]];
        else
            is_debris[p] = 1;
    }
    // debris remembers the plate it tore from: the nearest through the rest mesh
    std::vector<int32_t> torn_from = pieces.root;
    grow_from_roots(topo, adj, torn_from, is_debris, std::numeric_limits<Real>::infinity(),
                    [&](int32_t e) { return topo.rest_length[e]; });
    for (int32_t p = 0; p < n; ++p)
        if (is_debris[p]) {
            pieces.root[p] = torn_from[p];
            ++pieces.debris;
        }
    for (int32_t f = 0; f < frag.count; ++f) pieces.count += is_plate[f];

    // cut edges: between pieces, to debris, and along the cracks inside a piece: a broken edge
    // whose ends hang from plate particles on two sides of a crack
    pieces.is_cut.resize(topo.edges.size());
    SameSide same_side(topo, adj, is_band, core_edge_off);
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        const int32_t a = pieces.id[p], b = pieces.id[q];
        bool cut = a == kDebris || b == kDebris || a != b;
        if (!cut && is_broken[e]) cut = !same_side(pieces.root[p], pieces.root[q]);
        pieces.is_cut[e] = cut ? 1 : 0;
    }
    return pieces;
}

}  // namespace mudcrack
