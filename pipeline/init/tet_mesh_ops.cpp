#include "pipeline/init/tet_mesh_ops.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "sim/core/parallel.h"

namespace mudcrack {

void drop_unused_vertices(TetMesh& mesh) {
    std::vector<int32_t> new_id(mesh.X.size(), -1);
    for (const Tet& t : mesh.tets)
        for (int32_t v : t) new_id[v] = 0;
    int32_t n = 0;
    for (size_t v = 0; v < new_id.size(); ++v) {
        if (new_id[v] < 0) continue;
        new_id[v] = n;
        mesh.X[n++] = mesh.X[v];
    }
    mesh.X.resize(n);
    for (Tet& t : mesh.tets)
        for (int32_t& v : t) v = new_id[v];
    for (Tri& f : mesh.boundary)
        for (int32_t& v : f) v = new_id[v];
}

std::vector<Tri> extract_boundary_faces(const std::vector<Tet>& tets) {
    // outward faces of a positive tet (0,1,2,3): the normal of (1,2,3) points away from 0, etc.
    static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    struct Face {
        std::array<int32_t, 3> key;  // sorted ids: identifies the face regardless of winding
        Tri tri;                     // outward winding as seen from its tet
    };
    std::vector<Face> faces;
    faces.reserve(tets.size() * 4);
    for (const Tet& t : tets) {
        for (const auto& f : kFace) {
            Face face{{t[f[0]], t[f[1]], t[f[2]]}, {t[f[0]], t[f[1]], t[f[2]]}};
            std::sort(face.key.begin(), face.key.end());
            faces.push_back(face);
        }
    }
    // a face shared by two tets appears twice after sorting; a boundary face once
    std::sort(faces.begin(), faces.end(),
              [](const Face& a, const Face& b) { return a.key < b.key; });
    std::vector<Tri> boundary;
    for (size_t i = 0; i < faces.size();) {
        size_t j = i + 1;
        while (j < faces.size() && faces[j].key == faces[i].key) ++j;
        if (j - i == 1) boundary.push_back(faces[i].tri);
        i = j;
    }
    return boundary;
}

int64_t count_non_positive_tets(const TetMesh& mesh, Real min_volume) {
    return parallel_reduce(
        static_cast<int64_t>(mesh.tets.size()), int64_t(0),
        [&](int64_t i) -> int64_t {
            const Tet& t = mesh.tets[i];
            return signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]) <=
                   min_volume;
        },
        [](int64_t a, int64_t b) { return a + b; });
}

Real total_tet_volume(const TetMesh& mesh) {
    return parallel_reduce(
        static_cast<int64_t>(mesh.tets.size()), Real(0),
        [&](int64_t i) {
            const Tet& t = mesh.tets[i];
            return signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]);
        },
        [](Real a, Real b) { return a + b; });
}

std::array<Real, 6> dihedral_angles_deg(const Vec3& a, const Vec3& b, const Vec3& c,
                                        const Vec3& d) {
    // the angle at edge (i,j) is between the two faces containing it, i.e. pi minus the angle
    // between the outward normals of the faces opposite the other two vertices k and l
    const Vec3 p[4] = {a, b, c, d};
    static constexpr int kOpposite[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    Vec3 n[4];
    for (int f = 0; f < 4; ++f) {
        const Vec3& u = p[kOpposite[f][0]];
        n[f] = (p[kOpposite[f][1]] - u).cross(p[kOpposite[f][2]] - u).normalized();
    }
    static constexpr int kEdgeFaces[6][2] = {{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}};
    std::array<Real, 6> angle;
    for (int e = 0; e < 6; ++e) {
        const Real cosine =
            std::clamp(n[kEdgeFaces[e][0]].dot(n[kEdgeFaces[e][1]]), Real(-1), Real(1));
        angle[e] = Real(180) - std::acos(cosine) * Real(180) / kPi;
    }
    return angle;
}

MeshQuality measure_quality(const TetMesh& mesh) {
    MeshQuality q;
    q.particles = static_cast<int64_t>(mesh.X.size());
    q.tets = static_cast<int64_t>(mesh.tets.size());
    q.boundary_faces = static_cast<int64_t>(mesh.boundary.size());
    q.tet_volume = total_tet_volume(mesh);

    struct Acc {
        Real min_angle = std::numeric_limits<Real>::infinity();
        Real max_angle = -std::numeric_limits<Real>::infinity();
        Real edge_sum = 0;
    };
    const Acc acc = parallel_reduce(
        q.tets, Acc{},
        [&](int64_t i) {
            const Tet& t = mesh.tets[i];
            const Vec3 &a = mesh.X[t[0]], &b = mesh.X[t[1]], &c = mesh.X[t[2]], &d = mesh.X[t[3]];
            const auto angles = dihedral_angles_deg(a, b, c, d);
            Acc r;
            r.min_angle = *std::min_element(angles.begin(), angles.end());
            r.max_angle = *std::max_element(angles.begin(), angles.end());
            r.edge_sum = (b - a).norm() + (c - a).norm() + (d - a).norm() + (c - b).norm() +
                         (d - b).norm() + (d - c).norm();
            return r;
        },
        [](const Acc& x, const Acc& y) {
            return Acc{std::min(x.min_angle, y.min_angle), std::max(x.max_angle, y.max_angle),
                       x.edge_sum + y.edge_sum};
        });
    if (q.tets > 0) {
        q.min_dihedral_deg = acc.min_angle;
        q.max_dihedral_deg = acc.max_angle;
        q.mean_edge_length = acc.edge_sum / Real(6 * q.tets);
    }
    if (!mesh.X.empty()) {
        q.bbox_min = q.bbox_max = mesh.X[0];
        for (const Vec3& x : mesh.X) {
            q.bbox_min = q.bbox_min.cwiseMin(x);
            q.bbox_max = q.bbox_max.cwiseMax(x);
        }
    }
    return q;
}

}  // namespace mudcrack
