#include "pipeline/measure/mesh_measures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/LU>

#include "pipeline/io/checksum.h"
#include "surfacing/pieces.h"
#include "surfacing/weld_classes.h"

namespace mudcrack {
namespace {

/// A hashable identity for an exact float position, or any three 32-bit words.
struct Key3 {
    uint32_t a, b, c;
    int32_t piece;
    bool operator==(const Key3& o) const {
        return a == o.a && b == o.b && c == o.c && piece == o.piece;
    }
};
static_assert(sizeof(Key3) == 16, "Key3Hash hashes the key's bytes: no padding");
struct Key3Hash {
    // four 32-bit words, no padding: the key's bytes are its identity
    size_t operator()(const Key3& k) const { return size_t(fnv1a64(&k, sizeof(Key3))); }
};
Key3 position_key(const Vec3f& p, int32_t piece) {
    Key3 k{};
    std::memcpy(&k.a, &p.x(), 4);
    std::memcpy(&k.b, &p.y(), 4);
    std::memcpy(&k.c, &p.z(), 4);
    k.piece = piece;
    return k;
}

int32_t face_piece(const TriMesh& m, size_t f) {
    return m.face_fragment.empty() ? 0 : m.face_fragment[f];
}

Vec3 face_normal(const TriMesh& m, size_t f) {
    const Tri& t = m.faces[f];
    const Vec3 a = m.positions[t[0]].cast<Real>(), b = m.positions[t[1]].cast<Real>(),
               c = m.positions[t[2]].cast<Real>();
    return (b - a).cross(c - a) / 2;  // length: the area
}

/// Both meshes' triangles with their corners welded by exact position within each piece.
struct WeldedFaces {
    struct Face {
        std::array<int32_t, 3> v;
        int32_t piece;
        bool is_crack;
        Vec3 area_normal;
    };
    std::vector<Face> faces;
    std::vector<Vec3f> position;  // per welded vertex

    void add(const TriMesh& m, bool is_crack, std::unordered_map<Key3, int32_t, Key3Hash>& index) {
        for (size_t f = 0; f < m.faces.size(); ++f) {
            Face face{{}, face_piece(m, f), is_crack, face_normal(m, f)};
            for (int k = 0; k < 3; ++k) {
                const Vec3f& p = m.positions[m.faces[f][k]];
                const auto [it, added] =
                    index.try_emplace(position_key(p, face.piece), int32_t(position.size()));
                if (added) position.push_back(p);
                face.v[k] = it->second;
            }
            faces.push_back(face);
        }
    }
};

uint64_t edge_key(int32_t a, int32_t b) {
    if (a > b) std::swap(a, b);
    return (uint64_t(uint32_t(a)) << 32) | uint32_t(b);
}

}  // namespace

MeshPieces measure_mesh_pieces(const TriMesh& boundary, const TriMesh& crack, Real cell) {
    WeldedFaces w;
    std::unordered_map<Key3, int32_t, Key3Hash> index;
    w.add(boundary, false, index);
    w.add(crack, true, index);

    // pieces and chips: the second principal width of each piece's welded vertices
    std::map<int32_t, std::set<int32_t>> piece_vertices;
    std::map<int32_t, int64_t> piece_faces;
    for (const auto& f : w.faces) {
        ++piece_faces[f.piece];
        piece_vertices[f.piece].insert(f.v.begin(), f.v.end());
    }
    MeshPieces out;
    out.pieces = static_cast<int32_t>(piece_faces.size());
    int64_t chip_faces = 0;
    for (const auto& [piece, verts] : piece_vertices) {
        Vec3 sum = Vec3::Zero();
        Mat3 outer = Mat3::Zero();
        for (int32_t v : verts) {
            const Vec3 x = w.position[v].cast<Real>();
            sum += x;
            outer += x * x.transpose();
        }
        if (piece_width(sum, outer, int64_t(verts.size()), 0) < 2 * cell) {
            ++out.chips;
            chip_faces += piece_faces[piece];
        }
    }
    out.chip_triangle_fraction =
        w.faces.empty() ? 0.0 : double(chip_faces) / double(w.faces.size());

    // edges: closedness per piece, wall roughness, rims on the top
    std::unordered_map<uint64_t, std::vector<int32_t>> edge_faces;  // welded vertices are per piece
    for (size_t f = 0; f < w.faces.size(); ++f)
        for (int k = 0; k < 3; ++k)
            edge_faces[edge_key(w.faces[f].v[k], w.faces[f].v[(k + 1) % 3])].push_back(int32_t(f));
    std::unordered_set<int32_t> open_pieces;
    double angle_sum = 0, weight_sum = 0;
    for (const auto& [key, fs] : edge_faces) {
        if (fs.size() != 2) {
            ++out.open_edges;
            out.hole_edges += fs.size() % 2;
            open_pieces.insert(w.faces[fs[0]].piece);
            continue;
        }
        const auto &f0 = w.faces[fs[0]], &f1 = w.faces[fs[1]];
        const Real a0 = f0.area_normal.norm(), a1 = f1.area_normal.norm();
        if (f0.is_crack && f1.is_crack && a0 > 0 && a1 > 0) {
            const Real c =
                std::clamp(f0.area_normal.dot(f1.area_normal) / (a0 * a1), Real(-1), Real(1));
            angle_sum += (a0 + a1) / 2 * std::acos(c);
            weight_sum += (a0 + a1) / 2;
        }
        if (f0.is_crack != f1.is_crack) {
            const auto& skin = f0.is_crack ? f1 : f0;
            if (a0 > 0 && a1 > 0 && skin.area_normal.y() / skin.area_normal.norm() > 0.7) {
                const int32_t u = int32_t(key >> 32), v = int32_t(key & 0xffffffffu);
                out.top_crack_length += (w.position[u] - w.position[v]).cast<Real>().norm() / 2;
            }
        }
    }
    out.open_pieces = static_cast<int32_t>(open_pieces.size());
    out.crack_roughness_deg = weight_sum > 0 ? angle_sum / weight_sum * 180 / kPi : 0.0;
    for (const auto& f : w.faces)
        if (f.is_crack) out.crack_area += f.area_normal.norm() / 2;
    out.crack_area_per_metre =
        out.top_crack_length > 0 ? out.crack_area / out.top_crack_length : 0.0;
    return out;
}

namespace {

/// The particles a vertex named by its weld key (core_surface.h) follows: the owners of its rest
/// point in its weld class.
struct ClassMembers {
    int n = 0;
    std::array<int32_t, 4> particle{};
};

class WeldClassOwners {
public:
    explicit WeldClassOwners(const CoreTopology& t) : m_topo(t), m_face_tet(t.n_faces) {
        for (int32_t tet = 0; tet < t.n_tets(); ++tet)
            for (int l = 0; l < 4; ++l) m_face_tet[t.tet_faces[tet][l]] = {tet, l};
    }
    /// The owners in the class that holds owner slot `rep` of weld key `key` under the cut edges
    /// `cut` (a frame's edge_cut, or fewer cuts: its class then, which holds today's).
    ClassMembers members(uint64_t key, const std::vector<uint8_t>& cut) const {
        const auto kind = RestPointKind(key >> 62);
        const int32_t point = int32_t((key >> 2) & 0xffffffffu);
        const int rep = int(key & 3u);
        std::array<int32_t, 4> owner{};
        WeldReps reps{0, 1, 2, 3};
        int n = 1;
        switch (kind) {
            case RestPointKind::Particle: owner[0] = point; break;
            case RestPointKind::EdgeMidpoint:
                n = 2;
                owner = {m_topo.edges[point][0], m_topo.edges[point][1], 0, 0};
                reps[1] = int8_t(cut[point] ? 1 : 0);
                break;
            case RestPointKind::FaceCentroid: {
                const auto [tet, l] = m_face_tet[point];
                const FaceOwners f = face_owners(m_topo, tet, l);
                unsigned mask = 0;
                for (int k = 0; k < 3; ++k)
                    if (cut[f.edge[k]]) mask |= 1u << k;
                n = 3;
                owner = {f.owner[0], f.owner[1], f.owner[2], 0};
                reps = face_weld_reps(mask);
                break;
            }
            case RestPointKind::TetCentroid: {
                unsigned mask = 0;
                for (int k = 0; k < 6; ++k)
                    if (cut[m_topo.tet_edges[point][k]]) mask |= 1u << k;
                n = 4;
                owner = m_topo.tets[point];
                reps = tet_weld_reps(mask);
                break;
            }
        }
        ClassMembers out;
        for (int j = 0; j < n; ++j)
            if (reps[j] == reps[rep]) out.particle[out.n++] = owner[j];
        return out;
    }

private:
    const CoreTopology& m_topo;
    // a tet holding each face, and the corner opposite it
    std::vector<std::pair<int32_t, int>> m_face_tet;
};

/// The distance from `target` to the convex hull of points[0..n) (n <= 4): the least over the
/// hull's faces (every subset) of the distance to the subset's affine hull, among the subsets
/// whose nearest point has non-negative barycentric weights.
Real distance_to_hull(const std::array<Vec3, 4>& points, int n, const Vec3& target) {
    Real best = std::numeric_limits<Real>::infinity();
    for (unsigned subset = 1; subset < (1u << n); ++subset) {
        std::array<int, 4> idx{};
        int k = 0;
        for (int i = 0; i < n; ++i)
            if (subset & (1u << i)) idx[k++] = i;
        // nearest point origin + E mu of the subset's affine hull: (E^T E) mu = E^T (target -
        // origin), the unused rows of the 3 x 3 system set to mu_i = 0
        const Vec3& origin = points[idx[0]];
        Mat3 E = Mat3::Zero(), gram = Mat3::Identity();
        for (int i = 1; i < k; ++i) E.col(i - 1) = points[idx[i]] - origin;
        gram.topLeftCorner(k - 1, k - 1) = (E.transpose() * E).topLeftCorner(k - 1, k - 1);
        const Eigen::FullPivLU<Mat3> lu(gram);
        if (!lu.isInvertible()) continue;
        const Vec3 mu = lu.solve(Vec3(E.transpose() * (target - origin)));
        if ((mu.array() < -1e-9).any() || mu.sum() > 1 + 1e-9) continue;
        best = std::min(best, (origin + E * mu - target).norm());
    }
    return best;
}

struct KeyPiece {
    uint64_t key;
    int32_t piece;
    bool operator==(const KeyPiece& o) const { return key == o.key && piece == o.piece; }
};
struct KeyPieceHash {
    size_t operator()(const KeyPiece& k) const {
        return size_t(k.key * 0x9E3779B97F4A7C15ull) ^ size_t(k.piece);
    }
};

/// Each vertex's (weld key, piece) and position, over both meshes.
std::unordered_map<KeyPiece, Vec3f, KeyPieceHash> keyed_positions(const SurfacedFrame& s) {
    std::unordered_map<KeyPiece, Vec3f, KeyPieceHash> out;
    auto add = [&](const TriMesh& m, const std::vector<uint64_t>& keys) {
        for (size_t f = 0; f < m.faces.size(); ++f)
            for (int32_t v : m.faces[f])
                out.try_emplace({keys[v], face_piece(m, f)}, m.positions[v]);
    };
    add(s.boundary, s.boundary_weld_key);
    add(s.crack, s.crack_weld_key);
    return out;
}

}  // namespace

SurfaceMotion measure_surface_motion(const CoreTopology& topo, const SurfacedFrame& a,
                                     const ParticleFrame& frame_a, const SurfacedFrame& b,
                                     const ParticleFrame& frame_b, Real cell) {
    SurfaceMotion out;
    const WeldClassOwners owners(topo);
    const auto in_a = keyed_positions(a);
    std::vector<double> jumps;
    for (const auto& [kp, yb] : keyed_positions(b)) {
        const auto it = in_a.find(kp);
        if (it == in_a.end()) continue;
        const Vec3 moved = (yb - it->second).cast<Real>();
        // its particles: the owners of its class under a's settled cuts, which hold its class
        // under every later cut (cuts only grow)
        const ClassMembers followed =
            owners.members(kp.key, a.edge_settled.empty() ? a.edge_cut : a.edge_settled);
        std::array<Vec3, 4> particle_moved;
        for (int j = 0; j < followed.n; ++j) {
            const int32_t p = followed.particle[j];
            particle_moved[j] = (frame_b.P[p] - frame_a.P[p]).cast<Real>();
        }
        jumps.push_back(distance_to_hull(particle_moved, followed.n, moved) / cell);
    }
    out.vertices_compared = static_cast<int64_t>(jumps.size());
    if (!jumps.empty()) {
        std::sort(jumps.begin(), jumps.end());
        out.jump_max_cells = jumps.back();
        out.jump_p99_cells = jumps[std::min(jumps.size() - 1, size_t(0.99 * double(jumps.size())))];
    }
    if (a.particle_piece.size() == b.particle_piece.size()) {
        const std::unordered_set<int32_t> ids_a(a.particle_piece.begin(), a.particle_piece.end()),
            ids_b(b.particle_piece.begin(), b.particle_piece.end());
        for (size_t p = 0; p < a.particle_piece.size(); ++p) {
            const int32_t pa = a.particle_piece[p], pb = b.particle_piece[p];
            if (pa != pb && pa != kDebris && pb != kDebris && ids_a.count(pb) && ids_b.count(pa))
                ++out.piece_changes;
        }
    }
    return out;
}

}  // namespace mudcrack
