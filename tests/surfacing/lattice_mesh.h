#pragma once
/// Test and benchmark helper: a box lattice split into 6 tets per cell (Kuhn split along the
/// main diagonal, conforming across cells), positively oriented, with outward boundary faces and
/// UVs from a chosen projection.
#include <algorithm>
#include <array>
#include <map>
#include <vector>

#include "sim/core/tet_mesh.h"
#include "surfacing/core_topology.h"

namespace mudcrack::test {

enum class LatticeUv { None, Continuous, Triplanar };

inline TetMesh box_lattice(int nx, int ny, int nz, double h, LatticeUv uv = LatticeUv::Continuous,
                           const Vec3& origin = Vec3::Zero()) {
    TetMesh mesh;
    auto id = [&](int i, int j, int k) { return int32_t((k * (ny + 1) + j) * (nx + 1) + i); };
    for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j)
            for (int i = 0; i <= nx; ++i) mesh.X.push_back(origin + h * Vec3(i, j, k));
    const std::array<std::array<int, 3>, 6> perms = {
        {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                for (const auto& perm : perms) {
                    std::array<int, 3> c = {i, j, k};
                    Tet t{};
                    t[0] = id(c[0], c[1], c[2]);
                    for (int s = 0; s < 3; ++s) {
                        ++c[perm[s]];
                        t[s + 1] = id(c[0], c[1], c[2]);
                    }
                    if (signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]) <
                        0)
                        std::swap(t[2], t[3]);
                    mesh.tets.push_back(t);
                }
    // boundary: faces of exactly one tet, in that tet's outward order
    std::map<std::array<int32_t, 3>, std::pair<int, Tri>> faces;
    for (const Tet& t : mesh.tets)
        for (int l = 0; l < 4; ++l) {
            const auto& of = kTetOutwardFace[l];
            Tri f = {t[of[0]], t[of[1]], t[of[2]]};
            std::array<int32_t, 3> key = f;
            std::sort(key.begin(), key.end());
            auto& entry = faces[key];
            ++entry.first;
            entry.second = f;
        }
    for (const auto& [key, entry] : faces)
        if (entry.first == 1) mesh.boundary.push_back(entry.second);
    if (uv != LatticeUv::None)
        for (const Tri& f : mesh.boundary) {
            const Vec3 n = (mesh.X[f[1]] - mesh.X[f[0]]).cross(mesh.X[f[2]] - mesh.X[f[0]]);
            std::array<Vec2, 3> fuv;
            for (int c = 0; c < 3; ++c) {
                const Vec3& x = mesh.X[f[c]];
                fuv[c] = uv == LatticeUv::Continuous
                             ? Vec2(x.x() + 0.5 * x.z(), x.y() - 0.25 * x.z())
                             : triplanar_uv(x, dominant_axis(n), 2.0);
            }
            mesh.boundary_uv.push_back(fuv);
        }
    return mesh;
}

}  // namespace mudcrack::test
