#include "surfacing/core_topology.h"

#include "surfacing/weld_classes.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"

namespace mudcrack {
namespace {

[[noreturn]] void fail(const std::string& msg) { throw InputError("tet mesh: " + msg); }

/// Exclusive prefix sum of counts into offsets (size n + 1).
std::vector<int64_t> offsets_from_counts(const std::vector<int32_t>& count) {
    std::vector<int64_t> off(count.size() + 1, 0);
    for (size_t i = 0; i < count.size(); ++i) off[i + 1] = off[i] + count[i];
    return off;
}

struct FaceEntry {
    int32_t b, c;  // the two larger corners (the smallest is the bucket)
    int32_t ref;   // 4 * tet + opposite local corner
    bool operator<(const FaceEntry& o) const {
        return std::tie(b, c, ref) < std::tie(o.b, o.c, o.ref);
    }
};

void validate_tets(const TetMesh& mesh) {
    if (mesh.X.empty() || mesh.tets.empty())
        fail("no particles or no tets; expected a non-empty tet mesh");
    const int64_t n = static_cast<int64_t>(mesh.X.size());
    if (n >= std::numeric_limits<int32_t>::max() ||
        static_cast<int64_t>(mesh.tets.size()) * 6 >= std::numeric_limits<int32_t>::max())
        fail("too large for 32-bit ids (" + std::to_string(mesh.tets.size()) + " tets)");
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        const Tet& tet = mesh.tets[t];
        for (int k = 0; k < 4; ++k)
            if (tet[k] < 0 || tet[k] >= n)
                fail("tet " + std::to_string(t) + " corner " + std::to_string(k) + " = " +
                     std::to_string(tet[k]) + ": expected a particle id in [0, " +
                     std::to_string(n) + ")");
        const Real v =
            signed_tet_volume(mesh.X[tet[0]], mesh.X[tet[1]], mesh.X[tet[2]], mesh.X[tet[3]]);
        if (!(v > 0)) {
            std::ostringstream os;
            os << "tet " << t << " (" << tet[0] << "," << tet[1] << "," << tet[2] << "," << tet[3]
               << ") has rest volume " << v << " m^3; expected > 0 (positively oriented corners)";
            fail(os.str());
        }
    }
    if (!mesh.boundary_uv.empty() && mesh.boundary_uv.size() != mesh.boundary.size())
        fail("boundary_uv has " + std::to_string(mesh.boundary_uv.size()) +
             " entries; expected 0 or " + std::to_string(mesh.boundary.size()) +
             " (one per boundary face)");
}

/// Unique edges bucketed by their smaller particle id; fills edges, rest_length, tet_edges and
/// the edge -> tet CSR (the sorted bucket order is the CSR order).
void build_edges(const TetMesh& mesh, CoreTopology& topo) {
    const int32_t n = topo.n_particles;
    const int64_t n_tets = static_cast<int64_t>(mesh.tets.size());
    std::vector<int32_t> count(n, 0);
    for (const Tet& t : mesh.tets)
        for (const auto& e : kTetEdgeCorners) ++count[std::min(t[e[0]], t[e[1]])];
    const std::vector<int64_t> off = offsets_from_counts(count);
    // key = larger corner << 32 | (6 * tet + local edge), so a bucket sort groups by edge
    std::vector<uint64_t> key(off[n]);
    std::vector<int64_t> cursor(off.begin(), off.end() - 1);
    for (int64_t t = 0; t < n_tets; ++t) {
        const Tet& tet = mesh.tets[t];
        for (int k = 0; k < 6; ++k) {
            const int32_t a = tet[kTetEdgeCorners[k][0]], b = tet[kTetEdgeCorners[k][1]];
            key[cursor[std::min(a, b)]++] =
                (uint64_t(uint32_t(std::max(a, b))) << 32) | uint32_t(6 * t + k);
        }
    }
    std::vector<int32_t> n_unique(n, 0);
    parallel_for(n, [&](int64_t p) {
        std::sort(key.begin() + off[p], key.begin() + off[p + 1]);
        int32_t u = 0;
        for (int64_t i = off[p]; i < off[p + 1]; ++i)
            if (i == off[p] || (key[i] >> 32) != (key[i - 1] >> 32)) ++u;
        n_unique[p] = u;
    });
    const std::vector<int64_t> edge_base = offsets_from_counts(n_unique);
    const int64_t n_edges = edge_base[n];
    topo.edges.resize(n_edges);
    topo.rest_length.resize(n_edges);
    topo.tet_edges.resize(n_tets);
    topo.edge_tet.resize(off[n]);
    topo.edge_tet_begin.assign(n_edges + 1, static_cast<int32_t>(off[n]));
    parallel_for(n, [&](int64_t p) {
        int64_t id = edge_base[p] - 1;
        for (int64_t i = off[p]; i < off[p + 1]; ++i) {
            const int32_t q = int32_t(key[i] >> 32), ref = int32_t(key[i] & 0xffffffffu);
            if (i == off[p] || (key[i] >> 32) != (key[i - 1] >> 32)) {
                ++id;
                topo.edges[id] = {int32_t(p), q};
                topo.rest_length[id] = (topo.X[p] - topo.X[q]).norm();
                topo.edge_tet_begin[id] = static_cast<int32_t>(i);
            }
            topo.edge_tet[i] = ref;
            topo.tet_edges[ref / 6][ref % 6] = static_cast<int32_t>(id);
        }
    });
}

/// Unique faces bucketed by their smallest particle id. Returns the sorted buckets (for the
/// boundary lookup), fills tet_faces, and marks faces with a single tet.
struct FaceBuckets {
    std::vector<int64_t> off;
    std::vector<FaceEntry> entry;
    std::vector<int32_t> id_of_entry;
    std::vector<uint8_t> is_single;  // per face
};

FaceBuckets build_faces(const TetMesh& mesh, CoreTopology& topo) {
    const int32_t n = topo.n_particles;
    const int64_t n_tets = static_cast<int64_t>(mesh.tets.size());
    FaceBuckets fb;
    std::vector<int32_t> count(n, 0);
    auto sorted_face = [&](const Tet& tet, int l) {
        std::array<int32_t, 3> f{};
        for (int k = 0, j = 0; k < 4; ++k)
            if (k != l) f[j++] = tet[k];
        std::sort(f.begin(), f.end());
        return f;
    };
    for (const Tet& t : mesh.tets)
        for (int l = 0; l < 4; ++l) ++count[sorted_face(t, l)[0]];
    fb.off = offsets_from_counts(count);
    fb.entry.resize(fb.off[n]);
    std::vector<int64_t> cursor(fb.off.begin(), fb.off.end() - 1);
    for (int64_t t = 0; t < n_tets; ++t)
        for (int l = 0; l < 4; ++l) {
            const auto f = sorted_face(mesh.tets[t], l);
            fb.entry[cursor[f[0]]++] = {f[1], f[2], int32_t(4 * t + l)};
        }
    auto same = [&](int64_t i, int64_t j) {
        return fb.entry[i].b == fb.entry[j].b && fb.entry[i].c == fb.entry[j].c;
    };
    std::vector<int32_t> n_unique(n, 0);
    std::vector<uint8_t> bad(n, 0);
    parallel_for(n, [&](int64_t p) {
        std::sort(fb.entry.begin() + fb.off[p], fb.entry.begin() + fb.off[p + 1]);
        int32_t u = 0, run = 0;
        for (int64_t i = fb.off[p]; i < fb.off[p + 1]; ++i) {
            if (i == fb.off[p] || !same(i, i - 1)) {
                ++u;
                run = 0;
            }
            if (++run > 2) bad[p] = 1;
        }
        n_unique[p] = u;
    });
    for (int32_t p = 0; p < n; ++p)
        if (bad[p])
            fail("a face with corner particle " + std::to_string(p) +
                 " is shared by more than two tets; expected a manifold tet mesh");
    const std::vector<int64_t> face_base = offsets_from_counts(n_unique);
    topo.n_faces = static_cast<int32_t>(face_base[n]);
    topo.tet_faces.resize(n_tets);
    fb.id_of_entry.resize(fb.entry.size());
    fb.is_single.assign(topo.n_faces, 1);
    parallel_for(n, [&](int64_t p) {
        int64_t id = face_base[p] - 1;
        for (int64_t i = fb.off[p]; i < fb.off[p + 1]; ++i) {
            if (i == fb.off[p] || !same(i, i - 1))
                ++id;
            else
                fb.is_single[id] = 0;
            fb.id_of_entry[i] = static_cast<int32_t>(id);
            const int32_t ref = fb.entry[i].ref;
            topo.tet_faces[ref / 4][ref % 4] = static_cast<int32_t>(id);
        }
    });
    return fb;
}

/// Matches TetMesh::boundary to the single-tet faces: topo.skin_faces, checked and oriented.
void match_skin_faces(const TetMesh& mesh, const FaceBuckets& fb, CoreTopology& topo) {
    const size_t nb = mesh.boundary.size();
    topo.skin_faces.resize(nb);
    std::vector<uint8_t> matched(topo.n_faces, 0);
    int64_t n_single = 0;
    for (uint8_t s : fb.is_single) n_single += s;
    for (size_t i = 0; i < nb; ++i) {
        const Tri& tri = mesh.boundary[i];
        auto where = [&] {
            return "boundary face " + std::to_string(i) + " (" + std::to_string(tri[0]) + "," +
                   std::to_string(tri[1]) + "," + std::to_string(tri[2]) + ")";
        };
        for (int k = 0; k < 3; ++k)
            if (tri[k] < 0 || tri[k] >= topo.n_particles)
                fail(where() + ": particle id out of range");
        std::array<int32_t, 3> s = tri;
        std::sort(s.begin(), s.end());
        const FaceEntry probe{s[1], s[2], -1};
        const auto first = fb.entry.begin() + fb.off[s[0]],
                   last = fb.entry.begin() + fb.off[s[0] + 1];
        const auto it = std::lower_bound(first, last, probe);
        if (it == last || it->b != s[1] || it->c != s[2])
            fail(where() + " is not a face of any tet");
        const int32_t face = fb.id_of_entry[it - fb.entry.begin()];
        if (!fb.is_single[face])
            fail(where() + " is shared by two tets; expected a face of exactly one tet");
        if (matched[face]++) fail(where() + " is listed twice");
        const int32_t t = it->ref / 4, l = it->ref % 4;
        const Tet& tet = topo.tets[t];
        const auto& of = kTetOutwardFace[l];
        const std::array<int32_t, 3> out = {tet[of[0]], tet[of[1]], tet[of[2]]};
        const bool is_rotation = (out[0] == tri[0] && out[1] == tri[1]) ||
                                 (out[1] == tri[0] && out[2] == tri[1]) ||
                                 (out[2] == tri[0] && out[0] == tri[1]);
        if (!is_rotation) fail(where() + " is oriented inward; expected CCW seen from outside");
        SkinFace& sf = topo.skin_faces[i];
        sf.tet = t;
        sf.opposite = static_cast<int8_t>(l);
        sf.corner = tri;
        sf.face = face;
        auto local = [&](int32_t p) {
            for (int k = 0; k < 4; ++k)
                if (tet[k] == p) return k;
            return -1;
        };
        for (int k = 0; k < 3; ++k)
            sf.edge[k] = topo.tet_edges[t][kTetLocalEdge[local(tri[k])][local(tri[(k + 1) % 3])]];
    }
    if (static_cast<int64_t>(nb) != n_single)
        fail("boundary lists " + std::to_string(nb) + " faces but the tets have " +
             std::to_string(n_single) +
             " faces with a single tet; expected the boundary to be exactly those faces");
}

/// The texture density of the given UVs (uv length per rest length); else 1 per bounding-box
/// extent.
void set_uv_density(const TetMesh& mesh, CoreTopology& topo) {
    const size_t nb = mesh.boundary.size();
    Real uv_len = 0, x_len = 0;
    if (!mesh.boundary_uv.empty())
        for (size_t i = 0; i < nb; ++i)
            for (int k = 0; k < 3; ++k) {
                uv_len += (mesh.boundary_uv[i][(k + 1) % 3] - mesh.boundary_uv[i][k]).norm();
                x_len +=
                    (topo.X[mesh.boundary[i][(k + 1) % 3]] - topo.X[mesh.boundary[i][k]]).norm();
            }
    topo.has_boundary_uv = uv_len > 0 && x_len > 0;
    if (topo.has_boundary_uv) {
        topo.uv_per_meter = uv_len / x_len;
    } else {
        Vec3 lo = topo.X[0], hi = topo.X[0];
        for (const Vec3& x : topo.X) {
            lo = lo.cwiseMin(x);
            hi = hi.cwiseMax(x);
        }
        const Real extent = (hi - lo).maxCoeff();
        topo.uv_per_meter = extent > 0 ? 1 / extent : 1;
    }
}

/// The skin's UV vertices: one per (rest point, uv), split at UV seams, with their weld and output
/// slots.
void layout_skin_uv_vertices(const TetMesh& mesh, CoreTopology& topo) {
    const size_t nb = mesh.boundary.size();
    // one record per (boundary face, rest point); sort by (rest point, uv) to split at seams
    struct Record {
        RestPointKind kind;
        int32_t point;
        Vec2 uv;
        int32_t face, slot;
    };
    std::vector<Record> rec;
    rec.reserve(nb * 7);
    for (size_t i = 0; i < nb; ++i) {
        const SkinFace& sf = topo.skin_faces[i];
        std::array<Vec2, 7> uv;
        std::array<Vec3, 7> x0;
        for (int k = 0; k < 3; ++k) x0[k] = topo.X[sf.corner[k]];
        for (int k = 0; k < 3; ++k) x0[3 + k] = (x0[k] + x0[(k + 1) % 3]) / 2;
        x0[6] = (x0[0] + x0[1] + x0[2]) / 3;
        if (topo.has_boundary_uv) {
            const auto& fuv = mesh.boundary_uv[i];
            for (int k = 0; k < 3; ++k) uv[k] = fuv[k];
            for (int k = 0; k < 3; ++k) uv[3 + k] = (fuv[k] + fuv[(k + 1) % 3]) / 2;
            uv[6] = (fuv[0] + fuv[1] + fuv[2]) / 3;
        } else {
            const int axis = dominant_axis((x0[1] - x0[0]).cross(x0[2] - x0[0]));
            for (int k = 0; k < 7; ++k) uv[k] = triplanar_uv(x0[k], axis, topo.uv_per_meter);
        }
        for (int k = 0; k < 3; ++k)
            rec.push_back({RestPointKind::Particle, sf.corner[k], uv[k], int32_t(i), k});
        for (int k = 0; k < 3; ++k)
            rec.push_back({RestPointKind::EdgeMidpoint, sf.edge[k], uv[3 + k], int32_t(i), 3 + k});
        rec.push_back({RestPointKind::FaceCentroid, sf.face, uv[6], int32_t(i), 6});
    }
    std::sort(rec.begin(), rec.end(), [](const Record& a, const Record& b) {
        return std::make_tuple(a.kind, a.point, a.uv.x(), a.uv.y(), a.face, a.slot) <
               std::make_tuple(b.kind, b.point, b.uv.x(), b.uv.y(), b.face, b.slot);
    });
    topo.skin_uv_vertices.clear();
    // a rest point of kind k has 1 + k owners, hence 1 + k weld slots and output slots
    int32_t weld_slot = 0, out_slot = 0;
    for (size_t r = 0; r < rec.size(); ++r) {
        const bool new_point =
            r == 0 || rec[r].kind != rec[r - 1].kind || rec[r].point != rec[r - 1].point;
        if (new_point || rec[r].uv != rec[r - 1].uv) {
            if (new_point && r > 0) weld_slot += 1 + static_cast<int>(rec[r - 1].kind);
            topo.skin_uv_vertices.push_back(
                {rec[r].kind, rec[r].point, weld_slot, out_slot, rec[r].uv});
            out_slot += 1 + static_cast<int>(rec[r].kind);
        }
        topo.skin_faces[rec[r].face].uv_vertex[rec[r].slot] =
            static_cast<int32_t>(topo.skin_uv_vertices.size() - 1);
    }
    if (!rec.empty()) weld_slot += 1 + static_cast<int>(rec.back().kind);
    topo.n_skin_weld_slots = weld_slot;
    topo.n_skin_out_slots = out_slot;
}

/// Matches TetMesh::boundary to the single-tet faces and lays out the skin's UV vertices.
void build_skin(const TetMesh& mesh, const FaceBuckets& fb, CoreTopology& topo) {
    match_skin_faces(mesh, fb, topo);
    set_uv_density(mesh, topo);
    layout_skin_uv_vertices(mesh, topo);
}

}  // namespace

int dominant_axis(const Vec3& n) {
    const Vec3 a = n.cwiseAbs();
    return a.x() >= a.y() && a.x() >= a.z() ? 0 : (a.y() >= a.z() ? 1 : 2);
}

Vec2 triplanar_uv(const Vec3& x, int axis, Real uv_per_meter) {
    switch (axis) {
        case 0: return Vec2(x.z(), x.y()) * uv_per_meter;
        case 1: return Vec2(x.x(), x.z()) * uv_per_meter;
        default: return Vec2(x.x(), x.y()) * uv_per_meter;
    }
}

size_t CoreTopology::memory_bytes() const {
    const int64_t vectors = capacity_bytes(X) + capacity_bytes(tets) + capacity_bytes(edges) +
                            capacity_bytes(rest_length) + capacity_bytes(tet_edges) +
                            capacity_bytes(tet_faces) + capacity_bytes(edge_tet_begin) +
                            capacity_bytes(edge_tet) + capacity_bytes(skin_faces) +
                            capacity_bytes(skin_uv_vertices);
    return sizeof(*this) + static_cast<size_t>(vectors);
}

CoreTopology build_core_topology(const TetMesh& mesh) {
    validate_tets(mesh);
    CoreTopology topo;
    topo.n_particles = static_cast<int32_t>(mesh.X.size());
    topo.X = mesh.X;
    topo.tets = mesh.tets;
    build_edges(mesh, topo);
    const FaceBuckets fb = build_faces(mesh, topo);
    build_skin(mesh, fb, topo);
    return topo;
}

}  // namespace mudcrack

namespace mudcrack {

FaceOwners face_owners(const CoreTopology& topo, int32_t tet, int l) {
    const Tet& corners = topo.tets[tet];
    std::array<int, 3> local{};
    for (int k = 0, j = 0; k < 4; ++k)
        if (k != l) local[j++] = k;
    std::sort(local.begin(), local.end(), [&](int a, int b) { return corners[a] < corners[b]; });
    FaceOwners f;
    for (int k = 0; k < 3; ++k) {
        f.owner[k] = corners[local[k]];
        f.edge[k] = topo.tet_edges[tet][kTetLocalEdge[local[kFaceEdgeOwners[k][0]]]
                                                     [local[kFaceEdgeOwners[k][1]]]];
    }
    return f;
}

}  // namespace mudcrack
