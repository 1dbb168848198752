#include "surfacing/wall_smoothing.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "sim/core/parallel.h"

namespace mudcrack {
namespace {

/// Where a wall crosses each cut edge may slide between 5 % and 95 % of the edge: never onto a
/// particle, so every skin triangle keeps its orientation.
constexpr Real kMinCrossing = 0.05, kMaxCrossing = 0.95;
constexpr Real kLambda = 0.5, kMu = -0.53;  // Taubin's pair: smooths without shrinking
constexpr int kFitSteps = 3;     // the fit's neighbourhood: cut edges within 3 face-steps
constexpr Real kFitSigma = 1.5;  // its Gaussian weight's sigma, in mean edge lengths

/// The cut edges and which of them share a face (on the boundary: a boundary face).
struct CutEdgeGraph {
    std::vector<int32_t> edge;                     // cut edge ids
    std::vector<int32_t> node_of;                  // node of each edge, -1 when not cut, (n_edges)
    std::vector<std::vector<int32_t>> neighbours;  // nodes whose edges share a face with this one
                                                   // (a rim node: a boundary face)
    std::vector<std::vector<int32_t>> all_neighbours;  // nodes whose edges share any face
    std::vector<uint8_t> is_rim;                   // on the boundary: its neighbours are rim nodes
};

/// The edges of face f (opposite local corner l of tet t).
std::array<int32_t, 3> face_edges(const CoreTopology& topo, int32_t t, int l) {
    std::array<int32_t, 3> out{};
    int n = 0;
    for (int k = 0; k < 6; ++k) {
        const auto& ij = kTetEdgeCorners[k];
        if (ij[0] != l && ij[1] != l) out[n++] = topo.tet_edges[t][k];
    }
    return out;
}

CutEdgeGraph build_graph(const CoreTopology& topo, const std::vector<uint8_t>& is_cut) {
    CutEdgeGraph g;
    g.node_of.assign(topo.edges.size(), -1);
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (is_cut[e]) {
            g.node_of[e] = static_cast<int32_t>(g.edge.size());
            g.edge.push_back(e);
        }
    std::vector<uint8_t> boundary_face(topo.n_faces, 0);
    g.is_rim.assign(g.edge.size(), 0);
    for (const SkinFace& sf : topo.skin_faces) {
        boundary_face[sf.face] = 1;
        for (int32_t e : sf.edge)
            if (g.node_of[e] >= 0) g.is_rim[g.node_of[e]] = 1;
    }
    g.neighbours.resize(g.edge.size());
    g.all_neighbours.resize(g.edge.size());
    for (int32_t t = 0; t < topo.n_tets(); ++t)
        for (int l = 0; l < 4; ++l) {
            const auto edges = face_edges(topo, t, l);
            const bool on_boundary = boundary_face[topo.tet_faces[t][l]] != 0;
            for (int32_t a : edges)
                for (int32_t b : edges) {
                    const int32_t na = a == b ? -1 : g.node_of[a], nb = g.node_of[b];
                    if (na < 0 || nb < 0) continue;
                    g.all_neighbours[na].push_back(nb);
                    // a rim node follows only the rim: neighbours across boundary faces
                    if (g.is_rim[na] && !(on_boundary && g.is_rim[nb])) continue;
                    g.neighbours[na].push_back(nb);
                }
        }
    for (auto* lists : {&g.neighbours, &g.all_neighbours})
        for (auto& list : *lists) {
            std::sort(list.begin(), list.end());
            list.erase(std::unique(list.begin(), list.end()), list.end());
        }
    return g;
}

/// Where a wall crosses each cut edge before smoothing: where the edge meets the plane fitted
/// (weighted least squares, Gaussian in distance) to the midpoints of the cut edges within
/// kFitSteps face-steps of it. On a flat cut the midpoints scatter about its plane, so the
/// crossings land near it whatever the lattice (on a Kuhn lattice cut at an angle, 0.12 spacings
/// RMS off it instead of 0.4 for the dual cells' centroids); on a curved one the plane is the
/// wall's local tangent. A rim crossing fits the whole wall around it, not only the
/// rim, so its plane is not degenerate.
std::vector<Real> fitted_crossings(const CoreTopology& topo, const CutEdgeGraph& g) {
    const int64_t n = static_cast<int64_t>(g.edge.size());
    std::vector<Vec3> mid(n);
    Real length = 0;
    for (int64_t i = 0; i < n; ++i) {
        const auto [p, q] = topo.edges[g.edge[i]];
        mid[i] = (topo.X[p] + topo.X[q]) / 2;
        length += topo.rest_length[g.edge[i]];
    }
    const Real sigma = kFitSigma * (n > 0 ? length / Real(n) : Real(1));
    std::vector<Real> t(n, Real(0.5));
    std::vector<int64_t> seen(n, -1);  // the node whose neighbourhood last listed each node
    std::vector<int32_t> near;
    for (int64_t i = 0; i < n; ++i) {
        near.assign(1, int32_t(i));
        seen[i] = i;
        for (int step = 0, begin = 0; step < kFitSteps; ++step) {
            const int end = int(near.size());
            for (int k = begin; k < end; ++k)
                for (int32_t j : g.all_neighbours[near[k]])
                    if (seen[j] != i) {
                        seen[j] = i;
                        near.push_back(j);
                    }
            begin = end;
        }
        // weighted mean and covariance in one pass: sum w x x^T - W c c^T
        Real weight = 0;
        Vec3 sum = Vec3::Zero();
        Mat3 outer = Mat3::Zero();
        for (int32_t j : near) {
            const Vec3 d = mid[j] - mid[i];
            const Real w = std::exp(-d.squaredNorm() / (2 * sigma * sigma));
            weight += w;
            sum += w * d;
            outer += w * d * d.transpose();
        }
        const Vec3 offset = sum / weight;
        const Vec3 centre = mid[i] + offset;
        const Mat3 cov = outer - weight * offset * offset.transpose();
        const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
        if (near.size() < 4 || !(eig.eigenvalues()[1] > 1e-6 * eig.eigenvalues()[2])) continue;  // no plane
        const Vec3 normal = eig.eigenvectors().col(0);
        const auto [p, q] = topo.edges[g.edge[i]];
        const Real along = normal.dot(topo.X[q] - topo.X[p]);
        if (std::abs(along) > 1e-9 * topo.rest_length[g.edge[i]]) t[i] = normal.dot(centre - topo.X[p]) / along;
    }
    return t;
}

/// The mass point of a face or a tet: the mean of its cut edges' crossings, pulled halfway to its
/// centroid when only one edge is cut (a crack tip), so no wall triangle degenerates.
Vec3 mass_point(const std::vector<Vec3>& crossing, const CutEdgeGraph& g, const int32_t* edges, int n_edges,
                const Vec3& centroid) {
    Vec3 sum = Vec3::Zero();
    int n = 0;
    for (int k = 0; k < n_edges; ++k)
        if (g.node_of[edges[k]] >= 0) {
            sum += crossing[g.node_of[edges[k]]];
            ++n;
        }
    return n == 1 ? Vec3((sum + centroid) / 2) : Vec3(sum / n);
}

}  // namespace

WallRestPositions smooth_walls(const CoreTopology& topo, const std::vector<uint8_t>& is_cut, int iterations) {
    if (iterations <= 0) return WallRestPositions();
    WallRestPositions out(topo.n_edges(), topo.n_faces, topo.n_tets());
    const CutEdgeGraph g = build_graph(topo, is_cut);
    const int64_t n = static_cast<int64_t>(g.edge.size());
    auto point = [&](int64_t i, Real t) {
        const auto [p, q] = topo.edges[g.edge[i]];
        return Vec3(topo.X[p] + t * (topo.X[q] - topo.X[p]));
    };
    // crossings on the locally fitted wall plane, then Taubin smoothing, each kept on its own edge
    std::vector<Real> t = fitted_crossings(topo, g), next(n);
    for (Real& ti : t) ti = std::clamp(ti, kMinCrossing, kMaxCrossing);
    std::vector<Vec3> crossing(n);
    parallel_for(n, [&](int64_t i) { crossing[i] = point(i, t[i]); });
    for (int it = 0; it < 2 * iterations; ++it) {
        const Real step = it % 2 == 0 ? kLambda : kMu;
        parallel_for(n, [&](int64_t i) {
            const auto& nb = g.neighbours[i];
            next[i] = t[i];
            if (nb.empty()) return;
            Vec3 mean = Vec3::Zero();
            for (int32_t j : nb) mean += crossing[j];
            const Vec3 target = crossing[i] + step * (mean / Real(nb.size()) - crossing[i]);
            const auto [p, q] = topo.edges[g.edge[i]];
            const Vec3 d = topo.X[q] - topo.X[p];
            next[i] = std::clamp(d.dot(target - topo.X[p]) / d.squaredNorm(), kMinCrossing, kMaxCrossing);
        });
        std::swap(t, next);
        parallel_for(n, [&](int64_t i) { crossing[i] = point(i, t[i]); });
    }
    // the wall's rest points: crossings on the edges, mass points in the faces and tets
    for (int64_t i = 0; i < n; ++i) out.set(RestPointKind::EdgeMidpoint, g.edge[i], crossing[i]);
    for (int32_t tet = 0; tet < topo.n_tets(); ++tet) {
        const auto& te = topo.tet_edges[tet];
        if (std::none_of(te.begin(), te.end(), [&](int32_t e) { return g.node_of[e] >= 0; })) continue;
        const Tet& c = topo.tets[tet];
        out.set(RestPointKind::TetCentroid, tet,
                mass_point(crossing, g, te.data(), 6, (topo.X[c[0]] + topo.X[c[1]] + topo.X[c[2]] + topo.X[c[3]]) / 4));
        for (int l = 0; l < 4; ++l) {
            const auto fe = face_edges(topo, tet, l);
            if (std::none_of(fe.begin(), fe.end(), [&](int32_t e) { return g.node_of[e] >= 0; })) continue;
            const auto& fc = kTetOutwardFace[l];
            out.set(RestPointKind::FaceCentroid, topo.tet_faces[tet][l],
                    mass_point(crossing, g, fe.data(), 3, (topo.X[c[fc[0]]] + topo.X[c[fc[1]]] + topo.X[c[fc[2]]]) / 3));
        }
    }
    return out;
}

}  // namespace mudcrack
