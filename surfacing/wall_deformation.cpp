#include "surfacing/wall_deformation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/core/parallel.h"
#include "surfacing/pieces.h"

namespace mudcrack {
namespace {

constexpr size_t kMinNeighbours = 6;  // an affine map in 3D needs 4; 6 keeps it from pivoting
constexpr Real kMinFlatness = 0.02;   // least / largest principal rest variance to fit

/// The edges at each particle: CSR over topo.edges.
struct ParticleEdges {
    std::vector<int32_t> begin, edge;
    explicit ParticleEdges(const CoreTopology& topo)
        : begin(topo.n_particles + 1, 0),
          edge(2 * topo.edges.size()) {
        for (const auto& pq : topo.edges)
            for (int32_t p : pq) ++begin[p + 1];
        for (int32_t p = 0; p < topo.n_particles; ++p) begin[p + 1] += begin[p];
        std::vector<int32_t> fill(begin.begin(), begin.end() - 1);
        for (int32_t e = 0; e < topo.n_edges(); ++e)
            for (int32_t p : topo.edges[e]) edge[fill[p]++] = e;
    }
};

/// The wall particles: the corners of every tet around a cut edge (the owners of its wall
/// points), each with the frame of its first cut.
void find_wall_particles(const CoreTopology& topo, const std::vector<uint8_t>& is_cut,
                         const std::vector<int32_t>& cut_frame, const std::vector<int32_t>& piece,
                         WallDeformation& d) {
    constexpr int32_t kNever = std::numeric_limits<int32_t>::max();
    std::vector<int32_t> first_cut(topo.n_particles, kNever);
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        if (!is_cut[e]) continue;
        for (int32_t c = topo.edge_tet_begin[e]; c < topo.edge_tet_begin[e + 1]; ++c)
            for (int32_t p : topo.tets[topo.edge_tet[c] / 6])
                first_cut[p] = std::min(first_cut[p], cut_frame[e]);
    }
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        if (first_cut[p] == kNever || piece[p] == kDebris) continue;
        d.particle.push_back(p);
        d.first_cut.push_back(first_cut[p]);
    }
}

/// The particles within `radius` of p in the rest state reached from it through uncut edges
/// within its piece, ascending.
std::vector<int32_t> neighbourhood(const CoreTopology& topo, const ParticleEdges& adjacency,
                                   const std::vector<uint8_t>& is_cut,
                                   const std::vector<int32_t>& piece, int32_t p, Real radius) {
    // which particles this search has met: marked with a number of its own
    thread_local std::vector<uint64_t> met;
    thread_local uint64_t search = 0;
    if (met.size() != size_t(topo.n_particles)) met.assign(topo.n_particles, 0);
    const uint64_t mark = ++search;
    std::vector<int32_t> near{p};
    met[p] = mark;
    for (size_t k = 0; k < near.size(); ++k) {
        const int32_t q = near[k];
        for (int32_t c = adjacency.begin[q]; c < adjacency.begin[q + 1]; ++c) {
            const int32_t e = adjacency.edge[c];
            const int32_t r = topo.edges[e][0] == q ? topo.edges[e][1] : topo.edges[e][0];
            if (met[r] == mark || is_cut[e] || piece[r] != piece[p] ||
                (topo.X[r] - topo.X[p]).norm() > radius)
                continue;
            met[r] = mark;
            near.push_back(r);
        }
    }
    std::sort(near.begin(), near.end());
    return near;
}

}  // namespace

size_t WallDeformation::memory_bytes() const {
    return (particle.size() + first_cut.size() + begin.size() + neighbour.size()) *
               sizeof(int32_t) +
           weight.size() * sizeof(float) + rest_centre.size() * sizeof(Vec3) +
           rest_inverse.size() * sizeof(Mat3);
}

WallDeformation plan_wall_deformation(const CoreTopology& topo, const std::vector<uint8_t>& is_cut,
                                      const std::vector<int32_t>& cut_frame,
                                      const std::vector<int32_t>& piece, Real radius,
                                      Real max_lead) {
    WallDeformation d;
    d.max_lead = max_lead;
    d.core_reach = mean_particle_spacing(topo) / 2;
    find_wall_particles(topo, is_cut, cut_frame, piece, d);
    const int64_t n = static_cast<int64_t>(d.particle.size());
    const ParticleEdges adjacency(topo);
    std::vector<std::vector<int32_t>> found(n);
    parallel_for(n, [&](int64_t i) {
        found[i] = neighbourhood(topo, adjacency, is_cut, piece, d.particle[i], radius);
    });
    d.begin.assign(n + 1, 0);
    for (int64_t i = 0; i < n; ++i)
        d.begin[i + 1] = d.begin[i] + static_cast<int32_t>(found[i].size());
    d.neighbour.resize(d.begin[n]);
    d.weight.resize(d.begin[n]);
    d.rest_centre.resize(n);
    d.rest_inverse.resize(n);
    const Real sigma = radius / 2;
    parallel_for(n, [&](int64_t i) {
        const int32_t p = d.particle[i];
        Real total = 0;
        Vec3 centre = Vec3::Zero();
        for (size_t k = 0; k < found[i].size(); ++k) {
            const int32_t q = found[i][k];
            const float w =
                float(std::exp(-(topo.X[q] - topo.X[p]).squaredNorm() / (2 * sigma * sigma)));
            d.neighbour[d.begin[i] + k] = q;
            d.weight[d.begin[i] + k] = w;
            total += w;
            centre += Real(w) * topo.X[q];
        }
        centre /= total;
        Mat3 cov = Mat3::Zero();
        for (int32_t k = d.begin[i]; k < d.begin[i + 1]; ++k) {
            const Vec3 r = topo.X[d.neighbour[k]] - centre;
            cov += Real(d.weight[k]) * r * r.transpose();
        }
        d.rest_centre[i] = centre;
        d.rest_inverse[i] = Mat3::Zero();
        const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
        if (found[i].size() >= kMinNeighbours &&
            eig.eigenvalues()[0] > kMinFlatness * eig.eigenvalues()[2])
            d.rest_inverse[i] = cov.inverse();
    });
    return d;
}

void smooth_wall_motion(const CoreTopology& topo, const WallDeformation& d,
                        const ParticleFrame& frame, int ease_frames, std::vector<Vec3>& x,
                        std::vector<Mat3>& A) {
    parallel_for(static_cast<int64_t>(d.particle.size()), [&](int64_t i) {
        if (d.rest_inverse[i].isZero()) return;
        const Real w = ease_frames > 0
                           ? std::clamp(Real(frame.frame - d.first_cut[i]) / Real(ease_frames),
                                        Real(0), Real(1))
                           : Real(1);
        if (w == 0) return;
        Real total = 0;
        Vec3 centre = Vec3::Zero();
        for (int32_t k = d.begin[i]; k < d.begin[i + 1]; ++k) {
            total += Real(d.weight[k]);
            centre += Real(d.weight[k]) * frame.P[d.neighbour[k]].cast<Real>();
        }
        centre /= total;
        Mat3 cross = Mat3::Zero();
        for (int32_t k = d.begin[i]; k < d.begin[i + 1]; ++k) {
            const int32_t q = d.neighbour[k];
            cross += Real(d.weight[k]) * (frame.P[q].cast<Real>() - centre) *
                     (topo.X[q] - d.rest_centre[i]).transpose();
        }
        const int32_t p = d.particle[i];
        const Mat3 fitted_A = cross * d.rest_inverse[i];
        const Vec3 fitted_x = centre + fitted_A * (topo.X[p] - d.rest_centre[i]);
        const Vec3 dx = fitted_x - x[p];
        const Mat3 dA = fitted_A - A[p];
        const Real lead = dx.norm() + dA.norm() * d.core_reach;
        const Real share = w * (lead > d.max_lead ? d.max_lead / lead : Real(1));
        A[p] += share * dA;
        x[p] += share * dx;
    });
}

}  // namespace mudcrack
