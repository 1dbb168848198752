#pragma once
/// Shared checks and small in-memory surfaces for the init tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/io/mesh_io.h"
#include "sim/core/tet_mesh.h"
#include "tolerance.h"

namespace mudcrack::test {

/// Every tet is positively oriented (signed volume > 0).
inline void expect_all_tets_positive(const TetMesh& mesh) {
    EXPECT_FALSE(mesh.tets.empty()) << "no tets: nothing was checked";
    int64_t bad = 0;
    for (const Tet& t : mesh.tets)
        bad += !(signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]) > 0);
    EXPECT_EQ(bad, 0) << "of " << mesh.tets.size() << " tets";
}

/// The particle volumes sum to the tet volume to round-off, and all are positive.
inline void expect_volume_conserved(const TetMesh& mesh, const std::vector<Real>& volume0) {
    ASSERT_EQ(volume0.size(), mesh.X.size());
    Real tets = 0;
    for (const Tet& t : mesh.tets)
        tets += signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]);
    const Real particles = std::accumulate(volume0.begin(), volume0.end(), Real(0));
    EXPECT_NEAR(particles / tets, 1.0, tol::kRoundoffLoose)
        << "particles " << particles << " tets " << tets;
    EXPECT_GT(*std::min_element(volume0.begin(), volume0.end()), 0) << "a particle has no volume";
}

/// Every vertex is used by a tet (ids are 0..n-1 over used vertices).
inline void expect_no_unused_vertices(const TetMesh& mesh) {
    std::vector<char> used(mesh.X.size(), 0);
    for (const Tet& t : mesh.tets)
        for (int32_t v : t) used[v] = 1;
    EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
}

/// The boundary is closed and consistently oriented: each directed edge appears exactly once
/// and its reverse exactly once (so each undirected edge is shared by exactly 2 faces); and
/// it encloses the tet volume (outward orientation: divergence theorem gives the same volume).
inline void expect_closed_outward_boundary(const TetMesh& mesh) {
    ASSERT_FALSE(mesh.boundary.empty());
    std::map<std::pair<int32_t, int32_t>, int> directed;
    for (const Tri& f : mesh.boundary)
        for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
    int64_t open = 0, repeated = 0;
    for (const auto& [edge, count] : directed) {
        repeated += count != 1;
        const auto it = directed.find({edge.second, edge.first});
        open += it == directed.end() || it->second != 1;
    }
    EXPECT_EQ(open, 0) << "boundary edges without exactly one opposite half";
    EXPECT_EQ(repeated, 0) << "directed boundary edges used more than once";
    Real enclosed = 0, tets = 0;
    const Vec3 o = mesh.X[mesh.boundary[0][0]];
    for (const Tri& f : mesh.boundary)
        enclosed += signed_tet_volume(o, mesh.X[f[0]], mesh.X[f[1]], mesh.X[f[2]]);
    for (const Tet& t : mesh.tets)
        tets += signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]);
    EXPECT_NEAR(enclosed / tets, 1.0, tol::kRoundoffLoose)
        << "boundary does not enclose the tets outward";
}

/// One finite UV triple per boundary face.
inline void expect_finite_boundary_uvs(const TetMesh& mesh) {
    ASSERT_EQ(mesh.boundary_uv.size(), mesh.boundary.size());
    int64_t bad = 0;
    for (const auto& f : mesh.boundary_uv)
        for (const Vec2& uv : f) bad += !uv.allFinite();
    EXPECT_EQ(bad, 0);
}

/// A unit cube [0,1]^3 as 12 outward triangles.
inline InputSurface unit_cube() {
    InputSurface s;
    for (int k = 0; k < 8; ++k) s.positions.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
    // quads as (a, b, c, d) counter-clockwise from outside, split along a-c
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        s.faces.push_back({q[0], q[1], q[2]});
        s.faces.push_back({q[0], q[2], q[3]});
    }
    return s;
}

/// An icosphere of the given radius: an icosahedron subdivided `levels` times, projected.
inline InputSurface icosphere(Real radius, int levels) {
    const Real t = (1 + std::sqrt(5.0)) / 2;
    InputSurface s;
    s.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    s.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
               {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<int32_t, int32_t>, int32_t> mid;
        auto midpoint = [&](int32_t a, int32_t b) {
            const auto key = std::minmax(a, b);
            const auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            s.positions.push_back(0.5 * (s.positions[a] + s.positions[b]));
            return mid[key] = static_cast<int32_t>(s.positions.size() - 1);
        };
        std::vector<Tri> next;
        for (const Tri& f : s.faces) {
            const int32_t a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]),
                          c = midpoint(f[2], f[0]);
            next.push_back({f[0], a, c});
            next.push_back({f[1], b, a});
            next.push_back({f[2], c, b});
            next.push_back({a, b, c});
        }
        s.faces = std::move(next);
    }
    for (Vec3& p : s.positions) p = radius * p.normalized();
    return s;
}

}  // namespace mudcrack::test
