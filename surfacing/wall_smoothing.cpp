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
/// Taubin's pair: smooths without shrinking. Over k steps its transfer function at a mode of
/// the graph's Laplacian with eigenvalue e (0-2) is ((1 - lambda e)(1 - mu e))^k; this pair's 25
/// steps match 50 steps of the common (0.5, -0.53) within 0.017 at every e, for half the
/// passes over the nodes, which were half of a plates frame's surfacing time.
constexpr Real kLambda = 0.67, kMu = -0.72;
/// The share of its own position a wall node keeps after smoothing where it is. Between two
/// points where a crack's sides meet (its tips), Taubin steps pull a narrow strip of the two
/// sides onto each other to the last bit, two vertices of one piece at one position; keeping a
/// little of where its particles put it keeps the sides apart by as much of their true gap.
constexpr Real kKeptInput = 0.05;
constexpr int kFitSteps = 3;     // the fit's neighbourhood: cut edges within 3 face-steps
constexpr Real kFitSigma = 1.5;  // its Gaussian weight's sigma, in mean edge lengths

/// The cut edges and which of them share a face (on the boundary: a boundary face).
struct CutEdgeGraph {
    std::vector<int32_t> edge;                     // cut edge ids
    std::vector<int32_t> node_of;                  // node of each edge, -1 when not cut, (n_edges)
    std::vector<std::vector<int32_t>> neighbours;  // nodes whose edges share a face with this one
                                                   // (a rim node: a boundary face)
    std::vector<std::vector<int32_t>> all_neighbours;  // nodes whose edges share any face
    std::vector<uint8_t> is_rim;  // on the boundary: its neighbours are rim nodes
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
        // no plane
        if (near.size() < 4 || !(eig.eigenvalues()[1] > 1e-6 * eig.eigenvalues()[2])) continue;
        const Vec3 normal = eig.eigenvectors().col(0);
        const auto [p, q] = topo.edges[g.edge[i]];
        const Real along = normal.dot(topo.X[q] - topo.X[p]);
        if (std::abs(along) > 1e-9 * topo.rest_length[g.edge[i]])
            t[i] = normal.dot(centre - topo.X[p]) / along;
    }
    return t;
}

/// The mass point of a face or a tet: the mean of its cut edges' crossings, pulled halfway to its
/// centroid when only one edge is cut (a crack tip), so no wall triangle degenerates.
Vec3 mass_point(const std::vector<Vec3>& crossing, const CutEdgeGraph& g, const int32_t* edges,
                int n_edges, const Vec3& centroid) {
    Vec3 sum = Vec3::Zero();
    int n = 0;
    for (int k = 0; k < n_edges; ++k)
        if (g.node_of[edges[k]] >= 0) {
            sum += crossing[g.node_of[edges[k]]];
            ++n;
        }
    return n == 1 ? Vec3((sum + centroid) / 2) : Vec3(sum / n);
}

/// Finds the walls inside the soil: the parts of the graph with no rim node. They are hidden
/// (a cavity left by a grain torn loose inside a piece, a hairline that reaches no surface): no
/// camera sees them, and Taubin smoothing would shrink a small one to a point and weld its two
/// sides into one. Their nodes are held and marked hidden.
void find_hidden_walls(WallGraph& g) {
    g.hidden.assign(g.n_nodes, 0);
    std::vector<int32_t> part(g.n_nodes, -1), stack, members;
    for (int32_t seed = 0; seed < g.n_nodes; ++seed) {
        if (part[seed] >= 0) continue;
        part[seed] = seed;
        stack.assign(1, seed);
        members.clear();
        bool reaches_surface = false;
        while (!stack.empty()) {
            const int32_t a = stack.back();
            stack.pop_back();
            members.push_back(a);
            reaches_surface |= g.held[a] != 0;
            for (int32_t k = g.begin[a]; k < g.begin[a + 1]; ++k)
                if (part[g.neighbour[k]] < 0) {
                    part[g.neighbour[k]] = seed;
                    stack.push_back(g.neighbour[k]);
                }
        }
        if (!reaches_surface)
            for (int32_t a : members) g.held[a] = g.hidden[a] = 1;
    }
}

/// The graph's points (each cut edge's midpoint, its tets' centroids and their faces' centroids
/// that hold the edge) and nodes into g; returns the links of the last frame's wall triangles
/// (as build_crack makes them), both ways, each joining two nodes.
std::vector<std::array<int32_t, 2>> add_wall_points(const CoreTopology& topo,
                                                    const std::vector<uint8_t>& is_cut,
                                                    WallGraph& g) {
    g.point_of = {std::vector<int32_t>(topo.n_edges(), -1), std::vector<int32_t>(topo.n_faces, -1),
                  std::vector<int32_t>(topo.n_tets(), -1)};
    // the points, in order of first use: each cut edge's midpoint, then around it its tets'
    // centroids and the centroids of the two faces of each that hold the edge
    auto add_point = [&](RestPointKind kind, int32_t id, int32_t tet, int corner) {
        int32_t& index = g.point_of[int(kind) - 1][id];
        if (index >= 0) return index;
        WallGraph::Point point;
        point.kind = kind;
        point.id = id;
        point.tet = tet;
        point.corner = int8_t(corner);
        point.first_node = g.n_nodes;
        unsigned mask = 0;
        switch (kind) {
            case RestPointKind::EdgeMidpoint:
                point.reps = {0, 1, 2, 3};  // a cut edge's two owners are two classes
                g.n_nodes += 2;
                break;
            case RestPointKind::FaceCentroid: {
                const FaceOwners f = face_owners(topo, tet, corner);
                for (int k = 0; k < 3; ++k)
                    if (is_cut[f.edge[k]]) mask |= 1u << k;
                point.reps = face_weld_reps(mask);
                g.n_nodes += 3;
                break;
            }
            default:
                for (int k = 0; k < 6; ++k)
                    if (is_cut[topo.tet_edges[tet][k]]) mask |= 1u << k;
                point.reps = tet_weld_reps(mask);
                g.n_nodes += 4;
        }
        index = static_cast<int32_t>(g.points.size());
        g.points.push_back(point);
        return index;
    };
    auto node = [&](int32_t point, int slot) {
        return g.points[point].first_node + g.points[point].reps[slot];
    };
    auto face_slot = [&](int32_t tet, int corner, int32_t particle) {
        const FaceOwners f = face_owners(topo, tet, corner);
        return int(std::find(f.owner.begin(), f.owner.end(), particle) - f.owner.begin());
    };
    std::vector<std::array<int32_t, 2>> links;
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        if (!is_cut[e]) continue;
        const int32_t m = add_point(RestPointKind::EdgeMidpoint, e, 0, 0);
        for (int32_t c = topo.edge_tet_begin[e]; c < topo.edge_tet_begin[e + 1]; ++c) {
            const int32_t t = topo.edge_tet[c] / 6;
            const int i = kTetEdgeCorners[topo.edge_tet[c] % 6][0],
                      j = kTetEdgeCorners[topo.edge_tet[c] % 6][1];
            int k = -1, l = -1;
            for (int q = 0; q < 4; ++q)
                if (q != i && q != j) (k < 0 ? k : l) = q;
            const int32_t tet_point = add_point(RestPointKind::TetCentroid, t, t, 0);
            // opposite l
            const int32_t face_k =
                add_point(RestPointKind::FaceCentroid, topo.tet_faces[t][l], t, l);
            // opposite k
            const int32_t face_l =
                add_point(RestPointKind::FaceCentroid, topo.tet_faces[t][k], t, k);
            for (int corner : {i, j}) {
                const int32_t owner = topo.tets[t][corner];
                const int32_t nm = node(m, owner == topo.edges[e][0] ? 0 : 1),
                              ng = node(tet_point, corner);
                const int32_t nk =
                    node(face_k, face_slot(g.points[face_k].tet, g.points[face_k].corner, owner));
                const int32_t nl =
                    node(face_l, face_slot(g.points[face_l].tet, g.points[face_l].corner, owner));
                for (const auto& [a, b] :
                     {std::array<int32_t, 2>{nm, nk}, {nk, ng}, {ng, nm}, {nm, nl}, {nl, ng}})
                    links.push_back({a, b}), links.push_back({b, a});
            }
        }
    }
    return links;
}

/// g's neighbours (CSR) from the links: sorted, without repeats.
void link_wall_nodes(std::vector<std::array<int32_t, 2>> links, WallGraph& g) {
    std::sort(links.begin(), links.end());
    links.erase(std::unique(links.begin(), links.end()), links.end());
    g.begin.assign(g.n_nodes + 1, 0);
    for (const auto& [a, b] : links) ++g.begin[a + 1];
    for (int32_t n = 0; n < g.n_nodes; ++n) g.begin[n + 1] += g.begin[n];
    g.neighbour.resize(links.size());
    // links are sorted by node
    for (size_t k = 0; k < links.size(); ++k) g.neighbour[k] = links[k][1];
}

/// The nodes held by the wall's smoothing: those of points on the boundary (skin edges'
/// midpoints, skin faces' centroids) and of hidden walls; the rest with neighbours are free.
void hold_wall_boundary(const CoreTopology& topo, WallGraph& g) {
    g.held.assign(g.n_nodes, 0);
    auto hold = [&](RestPointKind kind, int32_t id) {
        const int32_t point = g.find(kind, id);
        if (point < 0) return;
        const int n_owners = kind == RestPointKind::EdgeMidpoint ? 2 : 3;
        std::fill_n(g.held.begin() + g.points[point].first_node, n_owners, uint8_t(1));
    };
    for (const SkinFace& sf : topo.skin_faces) {
        hold(RestPointKind::FaceCentroid, sf.face);
        for (int32_t e : sf.edge) hold(RestPointKind::EdgeMidpoint, e);
    }
    find_hidden_walls(g);
    for (int32_t n = 0; n < g.n_nodes; ++n)
        if (!g.held[n] && g.begin[n] < g.begin[n + 1]) g.free_nodes.push_back(n);
}

/// The rim nodes that lie on a curve of the rim (exactly two rim neighbours).
void trace_rim(WallGraph& g) {
    // the rim: held for the wall's smoothing, which would pull it off the skin, but a curve of
    // its own. Held where its particles put it, it showed every particle's own motion along a
    // plate's edge: a scalloped rim, and flutes down the wall below it.
    auto on_rim = [&](int32_t n) { return g.held[n] && !g.hidden[n]; };
    for (int32_t n = 0; n < g.n_nodes; ++n) {
        if (!on_rim(n)) continue;
        std::vector<int32_t> along;
        for (int32_t k = g.begin[n]; k < g.begin[n + 1]; ++k)
            if (on_rim(g.neighbour[k])) along.push_back(g.neighbour[k]);
        if (along.size() != 2) continue;  // a rim's end, or where three cracks meet: held
        g.rim_nodes.push_back(n);
        g.rim_neighbours.push_back({along[0], along[1]});
    }
}

}  // namespace

WallGraph plan_wall_graph(const CoreTopology& topo, const std::vector<uint8_t>& is_cut) {
    WallGraph g;
    link_wall_nodes(add_wall_points(topo, is_cut, g), g);
    hold_wall_boundary(topo, g);
    trace_rim(g);
    // kept for the whole shot: without the slack push_back left (up to half of each)
    g.points.shrink_to_fit();
    g.free_nodes.shrink_to_fit();
    g.rim_nodes.shrink_to_fit();
    g.rim_neighbours.shrink_to_fit();
    return g;
}

void smooth_wall_nodes(const WallGraph& g, int steps, std::vector<Vec3>& position) {
    // in single precision, as the meshes are written: half the memory traffic of the steps
    std::vector<Vec3f> y(position.size()), next;
    parallel_for(g.n_nodes, [&](int64_t n) { y[n] = position[n].cast<float>(); });
    next = y;  // only the free and rim nodes change; the others are the same in both
    const int64_t n_free = static_cast<int64_t>(g.free_nodes.size());
    const int64_t n_rim = static_cast<int64_t>(g.rim_nodes.size());
    for (int it = 0; it < 2 * steps; ++it) {
        const float step = float(it % 2 == 0 ? kLambda : kMu);
        parallel_for(n_free, [&](int64_t i) {
            const int32_t n = g.free_nodes[i];
            Vec3f mean = Vec3f::Zero();
            for (int32_t k = g.begin[n]; k < g.begin[n + 1]; ++k) mean += y[g.neighbour[k]];
            next[n] = y[n] + step * (mean / float(g.begin[n + 1] - g.begin[n]) - y[n]);
        });
        parallel_for(n_rim, [&](int64_t i) {
            const int32_t n = g.rim_nodes[i];
            const auto [a, b] = g.rim_neighbours[i];
            next[n] = y[n] + step * ((y[a] + y[b]) / 2 - y[n]);
        });
        std::swap(y, next);
    }
    auto keep_input = [&](int32_t n) {
        position[n] += (1 - kKeptInput) * (y[n].cast<Real>() - position[n]);
    };
    parallel_for(n_free, [&](int64_t i) { keep_input(g.free_nodes[i]); });
    parallel_for(n_rim, [&](int64_t i) { keep_input(g.rim_nodes[i]); });
}

WallRestPositions smooth_walls(const CoreTopology& topo, const std::vector<uint8_t>& is_cut,
                               int iterations) {
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
            next[i] =
                std::clamp(d.dot(target - topo.X[p]) / d.squaredNorm(), kMinCrossing, kMaxCrossing);
        });
        std::swap(t, next);
        parallel_for(n, [&](int64_t i) { crossing[i] = point(i, t[i]); });
    }
    // the wall's rest points: crossings on the edges, mass points in the faces and tets
    for (int64_t i = 0; i < n; ++i) out.set(RestPointKind::EdgeMidpoint, g.edge[i], crossing[i]);
    for (int32_t tet = 0; tet < topo.n_tets(); ++tet) {
        const auto& te = topo.tet_edges[tet];
        if (std::none_of(te.begin(), te.end(), [&](int32_t e) { return g.node_of[e] >= 0; }))
            continue;
        const Tet& c = topo.tets[tet];
        out.set(RestPointKind::TetCentroid, tet,
                mass_point(crossing, g, te.data(), 6,
                           (topo.X[c[0]] + topo.X[c[1]] + topo.X[c[2]] + topo.X[c[3]]) / 4));
        for (int l = 0; l < 4; ++l) {
            const auto fe = face_edges(topo, tet, l);
            if (std::none_of(fe.begin(), fe.end(), [&](int32_t e) { return g.node_of[e] >= 0; }))
                continue;
            const auto& fc = kTetOutwardFace[l];
            out.set(RestPointKind::FaceCentroid, topo.tet_faces[tet][l],
                    mass_point(crossing, g, fe.data(), 3,
                               (topo.X[c[fc[0]]] + topo.X[c[fc[1]]] + topo.X[c[fc[2]]]) / 3));
        }
    }
    out.shrink_to_fit();
    return out;
}

}  // namespace mudcrack
