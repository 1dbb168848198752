#include "surfacing/core_surface.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/core/union_find.h"
#include "surfacing/core_rotation.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/fragments.h"
#include "surfacing/pieces.h"
#include "surfacing/shot_fracture.h"
#include "surfacing/wall_smoothing.h"
#include "surfacing/weld_classes.h"

namespace mudcrack {
namespace {

/// A rest point with its owners (the corners of its simplex) and their weld classes this frame.
struct PointOwners {
    int n = 0;                       // number of owners, 1-4
    std::array<int32_t, 4> owner{};  // particle ids
    WeldReps rep{};                  // class representative of each owner slot
    Vec3 y0 = Vec3::Zero();          // rest position [m]
    RestPointKind kind = RestPointKind::Particle;
    int32_t point = 0;              // the rest point's particle, edge, face or tet id
    int n_edges = 0;                // edges between owners: 0, 1 (edge), 3 (face), 6 (tet)
    std::array<int32_t, 6> edge{};  // their ids, in the order of the weld tables' mask bits

    /// The weld classes under a mask of cut edges (bit k: edge[k]).
    WeldReps reps_under(unsigned mask) const {
        switch (kind) {
            case RestPointKind::EdgeMidpoint: return {0, int8_t(mask & 1u), 2, 3};
            case RestPointKind::FaceCentroid: return face_weld_reps(mask);
            case RestPointKind::TetCentroid: return tet_weld_reps(mask);
            default: return {0, 1, 2, 3};
        }
    }

    int slot_of(int32_t particle) const {
        for (int j = 0; j < n; ++j)
            if (owner[j] == particle) return j;
        return 0;
    }
};

/// [particle spacings] The largest jump a fresh cut eases in (FrameCores::opening): two cells in
/// a lattice of two particles per cell, so at the default open_speed every cut has eased in
/// within 20 frames. A late cut of a weld class whose particles drifted apart without their edge
/// breaking makes the longest jumps: on the demo's frame 32 (`mc-measure --motion`, 2026-11-27)
/// 2 spacings left a vertex 0.30 cells beyond its particles' move (at /init/seed 2, 0.92), 3
/// left 0.11 (0.44) and 4 0.11 (0.11); the largest jump over the 40 frames is then 0.235 (0.249),
/// at frame 6 (10), with the same wall roughness on every frame.
constexpr Real kMaxEasedGap = 4;

/// What the plates mode adds to a frame's cores (docs/physics.md §5.7).
struct PlateCores {
    const WallRestPositions* walls = nullptr;      // smoothed rest points of the crack walls
    const WallGraph* wall_graph = nullptr;         // the shot's walls, smoothed where they are
    const WallDeformation* wall_motion = nullptr;  // smoothed motion of the particles along them
    int wall_steps = 0;                            // Taubin steps over wall_graph
    const std::vector<int32_t>* piece = nullptr;   // piece of each particle (kDebris: none)
    Real close_gap = 0;                            // [m] sides closer than this meet
    // the frame each edge is cut from, and its vector the frame before (ShotFracture)
    const std::vector<int32_t>* cut_frame = nullptr;
    const CutEdgeVectors* cut_edges = nullptr;
    // [m per frame] how fast a fresh crack's sides part
    Real open_speed = 0;
    // [m] the largest jump a cut eases in (kMaxEasedGap spacings), and in how many frames
    Real max_eased_gap = 0;
    int easing_frames = 0;
};

/// smoothstep from 0 at a to 1 at b.
Real smoothstep(Real a, Real b, Real x) {
    const Real t = std::clamp((x - a) / (b - a), Real(0), Real(1));
    return t * t * (3 - 2 * t);
}

/// Everything a frame's core vertices depend on: positions, the core transforms s_p R_p of
/// Eq. 13, broken edges, and the shading attributes.
class FrameCores {
public:
    FrameCores(const CoreTopology& topo, const ParticleFrame& frame,
               const std::vector<uint8_t>& is_broken, const SurfaceParams& params,
               const PlateCores& plates = {})
        : m_topo(topo),
          m_frame(frame),
          m_broken(is_broken),
          m_plates(plates),
          m_x(topo.n_particles),
          m_A(topo.n_particles) {
        const bool has_jw = !frame.Jw.empty() && params.mode == SurfaceMode::Ours;
        const bool has_fe = !frame.Fe.empty();
        // per particle: x_p and J_w^(1/3) R_p (Eq. 13; Wang 2019 drops the J_w factor)
        parallel_for(topo.n_particles, [&](int64_t p) {
            m_x[p] = frame.P[p].cast<Real>();
            const Mat3 R = has_fe ? core_rotation(frame.Fe[p].cast<Real>()) : Mat3::Identity();
            m_A[p] = has_jw ? Real(std::cbrt(Real(frame.Jw[p]))) * R : R;
        });
        if (plates.wall_motion)
            smooth_wall_motion(topo, *plates.wall_motion, frame, plates.easing_frames, m_x, m_A);
        if (plates.wall_graph && !plates.wall_graph->empty()) smooth_walls_where_they_are();
    }

    bool has_saturation() const { return !m_frame.saturation.empty(); }
    /// Plates mode: walls that reach no surface in this frame are not meshed (hide_unseen_walls).
    bool hides_unseen_walls() const { return m_plates.wall_graph != nullptr; }
    bool has_alpha() const { return !m_frame.alpha.empty(); }

    PointOwners particle_point(int32_t p) const {
        PointOwners o;
        o.n = 1;
        o.owner[0] = p;
        o.rep = {0, 1, 2, 3};
        o.y0 = m_topo.X[p];
        o.point = p;
        return o;
    }
    PointOwners edge_point(int32_t e) const {
        PointOwners o;
        o.n = 2;
        o.owner = {m_topo.edges[e][0], m_topo.edges[e][1], 0, 0};
        o.rep = {0, int8_t(m_broken[e] ? 1 : 0), 2, 3};
        o.y0 =
            rest(RestPointKind::EdgeMidpoint, e, (m_topo.X[o.owner[0]] + m_topo.X[o.owner[1]]) / 2);
        o.kind = RestPointKind::EdgeMidpoint;
        o.point = e;
        o.n_edges = 1;
        o.edge[0] = e;
        return o;
    }
    /// The centroid of the face of tet t opposite local corner l; owners sorted by id.
    PointOwners face_point(int32_t t, int l) const {
        const FaceOwners f = face_owners(m_topo, t, l);
        PointOwners o;
        unsigned mask = 0;
        for (int k = 0; k < 3; ++k)
            if (m_broken[f.edge[k]]) mask |= 1u << k;
        o.kind = RestPointKind::FaceCentroid;
        o.point = m_topo.tet_faces[t][l];
        o.n_edges = 3;
        o.n = 3;
        o.owner = {f.owner[0], f.owner[1], f.owner[2], 0};
        o.edge = {f.edge[0], f.edge[1], f.edge[2], 0, 0, 0};
        o.rep = face_weld_reps(mask);
        o.y0 = rest(RestPointKind::FaceCentroid, m_topo.tet_faces[t][l],
                    (m_topo.X[o.owner[0]] + m_topo.X[o.owner[1]] + m_topo.X[o.owner[2]]) / 3);
        return o;
    }
    PointOwners tet_point(int32_t t) const {
        const Tet& tet = m_topo.tets[t];
        unsigned mask = 0;
        for (int k = 0; k < 6; ++k)
            if (m_broken[m_topo.tet_edges[t][k]]) mask |= 1u << k;
        PointOwners o;
        o.kind = RestPointKind::TetCentroid;
        o.point = t;
        o.n_edges = 6;
        for (int k = 0; k < 6; ++k) o.edge[k] = m_topo.tet_edges[t][k];
        o.n = 4;
        o.owner = tet;
        o.rep = tet_weld_reps(mask);
        o.y0 =
            rest(RestPointKind::TetCentroid, t,
                 (m_topo.X[tet[0]] + m_topo.X[tet[1]] + m_topo.X[tet[2]] + m_topo.X[tet[3]]) / 4);
        return o;
    }

    /// Eq. 13: y = x_p + J_w,p^(1/3) R_p (y0 - X_p).
    Vec3 extrapolate(int32_t p, const Vec3& y0) const {
        return m_x[p] + m_A[p] * (y0 - m_topo.X[p]);
    }

    struct Welded {
        Vec3 position = Vec3::Zero();
        Real saturation = 0, alpha = 0;
    };
    /// The welded vertex of class `rep`: the average of its members' copies (copy()); in the
    /// plates mode, eased in from where a fresh cut split it (opening) and closed.
    Welded welded(const PointOwners& o, int rep) const {
        Welded w;
        int members = 0;
        for (int j = 0; j < o.n; ++j) {
            if (o.rep[j] != rep) continue;
            const int32_t p = o.owner[j];
            w.position += copy(o, j);
            if (has_saturation()) w.saturation += m_frame.saturation[p];
            if (has_alpha()) w.alpha += m_frame.alpha[p];
            ++members;
        }
        w.position /= members;
        w.saturation /= members;
        w.alpha /= members;
        if (m_plates.cut_frame && m_plates.open_speed > 0) opening(o, rep, w.position);
        if (m_plates.piece && m_plates.close_gap > 0) close_gap(o, rep, w.position);
        return w;
    }

private:
    /// The copy of point o's owner slot j: Eq. 13's extrapolation; on the shot's walls in the
    /// plates mode, the smoothed node of its class under the last frame's cuts (WallGraph).
    Vec3 copy(const PointOwners& o, int j) const {
        const int32_t point = m_wall_node.empty() ? -1 : m_plates.wall_graph->find(o.kind, o.point);
        if (point < 0) return extrapolate(o.owner[j], o.y0);
        const WallGraph::Point& w = m_plates.wall_graph->points[point];
        return m_wall_node[w.first_node + w.reps[j]].cast<Real>();
    }

    /// The shot's walls smoothed where they are (plates mode): each node starts at the mean of the
    /// copies of its class's owners, then wall_steps Taubin steps over the fixed graph.
    void smooth_walls_where_they_are() {
        const WallGraph& graph = *m_plates.wall_graph;
        std::vector<Vec3> node(graph.n_nodes, Vec3::Zero());
        parallel_for(static_cast<int64_t>(graph.points.size()), [&](int64_t i) {
            const WallGraph::Point& w = graph.points[i];
            const PointOwners o = w.kind == RestPointKind::EdgeMidpoint ? edge_point(w.id)
                                  : w.kind == RestPointKind::FaceCentroid
                                      ? face_point(w.tet, w.corner)
                                      : tet_point(w.id);
            std::array<int, 4> members{};
            for (int j = 0; j < o.n; ++j) {
                node[w.first_node + w.reps[j]] += extrapolate(o.owner[j], o.y0);
                ++members[w.reps[j]];
            }
            for (int r = 0; r < o.n; ++r)
                if (members[r] > 0) node[w.first_node + r] /= members[r];
        });
        smooth_wall_nodes(graph, m_plates.wall_steps, node);
        // kept in single precision, as the meshes are written: the largest array of a plates frame
        m_wall_node.resize(graph.n_nodes);
        parallel_for(graph.n_nodes, [&](int64_t n) { m_wall_node[n] = node[n].cast<float>(); });
    }

    Vec3 rest(RestPointKind kind, int32_t id, const Vec3& y0) const {
        return m_plates.walls ? m_plates.walls->of(kind, id, y0) : y0;
    }
    /// A fresh crack eases in the jump its cut would make (plates mode). When a cut at frame f
    /// splits this side's class S from the class O it had before, the side would jump from
    /// where O was welded the frame before to where S is. Today that way is c_O - c_S, the means
    /// of their copies, but it has grown since by what the particles moved apart after the cut
    /// (a crack that keeps widening), which shows at once. That growth is measured on the edges
    /// between the two cut at f: G = sum_(i in S, k in O \ S) (x_k - x_i) / (|O| |S|), today's
    /// less the frame before the cut's (cut_edges, record_cut_edges), the mean pair standing in
    /// for pairs cut earlier; for an edge's midpoint it is how far its two particles moved apart.
    /// The particles' own vectors, not their cores' turned offsets: a torn particle's rotation can
    /// turn by half a turn from one frame to the next. Only G's part along the way counts: the
    /// side stands min(|c_O - c_S| - G.w, kMaxEasedGap) - a open_speed from S toward O (w the
    /// way's direction, a = now - f + 1 the cut's age), when that is positive; several cuts add
    /// up. So a cut moves a vertex at most open_speed a frame beyond its particles (the rare jump
    /// over kMaxEasedGap jumps the excess), every cut has eased in by easing_frames, and the whole
    /// rim of a crack follows its particles alike: no saw-teeth.
    void opening(const PointOwners& o, int rep, Vec3& side) const {
        const std::vector<int32_t>& cut_frame = *m_plates.cut_frame;
        const CutEdgeVectors& cut_edges = *m_plates.cut_edges;
        const Real speed = m_plates.open_speed;
        const int now = m_frame.frame;
        std::array<Vec3, 4> copies;
        bool have_copies = false;
        Vec3 offset = Vec3::Zero();
        for (int k = 0; k < o.n_edges; ++k) {
            const int32_t f = cut_frame[o.edge[k]];
            const int age = now - f + 1;
            if (f > now || age >= m_plates.easing_frames) continue;
            // each cut frame once: at its first edge
            bool seen = false;
            for (int l = 0; l < k && !seen; ++l) seen = cut_frame[o.edge[l]] == f;
            if (seen) continue;
            unsigned before = 0, after = 0;
            for (int l = 0; l < o.n_edges; ++l) {
                if (cut_frame[o.edge[l]] < f) before |= 1u << l;
                if (cut_frame[o.edge[l]] <= f) after |= 1u << l;
            }
            const WeldReps old_reps = o.reps_under(before), new_reps = o.reps_under(after);
            std::array<bool, 4> in_old{}, in_new{};
            int n_old = 0, n_new = 0;
            for (int j = 0; j < o.n; ++j) {
                in_old[j] = old_reps[j] == old_reps[rep];
                in_new[j] = new_reps[j] == new_reps[rep];
                n_old += in_old[j];
                n_new += in_new[j];
            }
            if (n_new == n_old) continue;  // this cut did not split this side's class
            if (!have_copies) {
                for (int j = 0; j < o.n; ++j) copies[j] = copy(o, j);
                have_copies = true;
            }
            Vec3 way = Vec3::Zero();  // n_old n_new (c_O - c_S)
            for (int j = 0; j < o.n; ++j) {
                if (in_old[j]) way += Real(n_new) * copies[j];
                if (in_new[j]) way -= Real(n_old) * copies[j];
            }
            // what the particles opened since, on the pairs cut at f (the others' vectors are
            // from their own, earlier cuts); at least one pair is, or the class would not split
            Vec3 growth = Vec3::Zero();
            int pairs_cut_at_f = 0;
            for (int l = 0; l < o.n_edges; ++l) {
                const int32_t e = o.edge[l];
                const auto [p, q] = m_topo.edges[e];
                const int i = o.slot_of(p), j = o.slot_of(q);
                const bool q_split_off = in_new[i] && in_old[j] && !in_new[j];
                const bool p_split_off = in_new[j] && in_old[i] && !in_new[i];
                if ((!q_split_off && !p_split_off) || cut_frame[e] != f) continue;
                const Vec3 grown = (m_frame.P[q] - m_frame.P[p] - cut_edges.of(e)).cast<Real>();
                growth += q_split_off ? grown : Vec3(-grown);
                ++pairs_cut_at_f;
            }
            // the mean pair's growth over all |S| |O \ S| pairs, / (|O| |S|): G
            const int pairs = n_new * (n_old - n_new);
            growth *= Real(pairs) / Real(std::max(1, pairs_cut_at_f) * n_old * n_new);
            // the way less what the particles opened along it since, toward where O was welded
            const Real way_length = way.norm() / Real(n_old * n_new);
            if (!(way_length > 0)) continue;
            const Real length = way_length - std::max(Real(0), growth.dot(way) / way.norm());
            const Real left = std::min(length, m_plates.max_eased_gap) - Real(age) * speed;
            if (left > 0) offset += (left / way.norm()) * way;
        }
        side += offset;
    }

    /// Close gaps (plates mode): the copies of this point's owners in other pieces are the far
    /// side of a crack wall. Within close_gap of it, the side meets the far side half way, as the
    /// far side does; it blends back to its own by 3 close_gap (smoothstep), so it never moves
    /// more than close_gap for it, and as the gap opens the side moves at most as fast as the gap
    /// grows (a blend to 2 close_gap moved it up to 1.4 times as fast: a pop while a fresh crack
    /// parts). A crack inside one piece keeps its walls apart: two walls of one piece
    /// at the same place would make it non-manifold to a reader that joins by position.
    void close_gap(const PointOwners& o, int rep, Vec3& side) const {
        const std::vector<int32_t>& piece = *m_plates.piece;
        int32_t mine = kDebris;
        for (int j = 0; j < o.n && mine == kDebris; ++j)
            if (o.rep[j] == rep) mine = piece[o.owner[j]];
        Vec3 others = Vec3::Zero();
        int n_others = 0;
        for (int j = 0; j < o.n; ++j) {
            const int32_t p = o.owner[j];
            if (piece[p] == kDebris || piece[p] == mine) continue;
            others += copy(o, j);
            ++n_others;
        }
        if (mine == kDebris || n_others == 0) return;
        const Vec3 far_side = others / n_others;
        const Real gap = (side - far_side).norm();
        const Vec3 middle = (side + far_side) / 2;
        side =
            middle + smoothstep(m_plates.close_gap, 3 * m_plates.close_gap, gap) * (side - middle);
    }

    const CoreTopology& m_topo;
    const ParticleFrame& m_frame;
    const std::vector<uint8_t>& m_broken;
    PlateCores m_plates;
    std::vector<Vec3> m_x;           // current positions [m], (n_particles)
    std::vector<Mat3> m_A;           // core transforms s_p R_p, (n_particles)
    std::vector<Vec3f> m_wall_node;  // plates mode: the smoothed wall nodes (WallGraph), (n_nodes)
};

/// A triangle under construction: output slots (vertex identity incl. UV split), weld slots
/// (normal sharing) and the owner particle.
struct SlotTri {
    std::array<int32_t, 3> out_slot;
    std::array<int32_t, 3> weld_slot;
    int32_t owner = -1;  // -1: culled
};

/// Numbers the output slots by first appearance in triangle order and fills faces, fragment
/// ids and, per vertex, its slot, weld and first face; the weld slots the faces use get compact
/// ids in the same order, so the normals are summed over those alone (a tet's centroid has four
/// weld slots and uses one or two). Sequential, hence deterministic. Two passes, so every array
/// is allocated once at its final size: these are the largest of a cracked frame's surfacing.
struct Numbered {
    std::vector<int32_t> vertex_slot;   // out slot of each vertex
    std::vector<int32_t> vertex_weld;   // compact weld id of each vertex
    std::vector<int32_t> vertex_face;   // first face using the vertex
    std::vector<int32_t> weld_of_slot;  // compact weld id of each weld slot, -1 when unused
    int32_t n_welds = 0;
};

Numbered number_vertices(const std::vector<SlotTri>& tris, int64_t n_out_slots,
                         int64_t n_weld_slots, const Fragments& frag, TriMesh& mesh) {
    Numbered num;
    std::vector<int32_t> vertex_of(n_out_slots, -1);
    num.weld_of_slot.assign(n_weld_slots, -1);
    int32_t nv = 0;
    size_t nf = 0;
    for (const SlotTri& t : tris) {
        if (t.owner < 0) continue;
        ++nf;
        for (int k = 0; k < 3; ++k) {
            if (vertex_of[t.out_slot[k]] >= 0) continue;
            vertex_of[t.out_slot[k]] = nv++;
            if (num.weld_of_slot[t.weld_slot[k]] < 0)
                num.weld_of_slot[t.weld_slot[k]] = num.n_welds++;
        }
    }
    num.vertex_slot.resize(nv);
    num.vertex_weld.resize(nv);
    num.vertex_face.assign(nv, -1);
    mesh.faces.resize(nf);
    mesh.face_fragment.resize(nf);
    int32_t f = 0;
    for (const SlotTri& t : tris) {
        if (t.owner < 0) continue;
        Tri& face = mesh.faces[f];
        for (int k = 0; k < 3; ++k) {
            const int32_t v = vertex_of[t.out_slot[k]];
            if (num.vertex_face[v] < 0) {
                num.vertex_slot[v] = t.out_slot[k];
                num.vertex_weld[v] = num.weld_of_slot[t.weld_slot[k]];
                num.vertex_face[v] = f;
            }
            face[k] = v;
        }
        mesh.face_fragment[f++] = frag.id[t.owner];
    }
    return num;
}

/// The skin's shading normals at its edge midpoints and face centroids: the mean of the unit
/// normals at the corner particles of the skin triangles that use them (a midpoint: its edge's two
/// particles; a centroid: its face's three), in place of their own area-weighted normals. A
/// centroid's own normal is its face's, so each boundary face of the tet mesh shaded as a facet
/// of its own: the quilted tops a close-up showed at the particle spacing. Interpolated from the
/// particles, the shading is as smooth as the soil. Only classes welded to the corner count, so a
/// crack's rim stays sharp.
void interpolate_skin_normals(const std::vector<SlotTri>& skin, const Numbered& num,
                              std::vector<Vec3>& weld_normal) {
    std::vector<Vec3> from_corners(weld_normal.size(), Vec3::Zero());
    for (const SlotTri& t : skin) {
        if (t.owner < 0) continue;
        const Vec3& corner = weld_normal[num.weld_of_slot[t.weld_slot[0]]];
        const Real len = corner.norm();
        if (!(len > 0)) continue;
        for (int c = 1; c < 3; ++c) from_corners[num.weld_of_slot[t.weld_slot[c]]] += corner / len;
    }
    for (size_t w = 0; w < weld_normal.size(); ++w)
        if (from_corners[w].norm() > 0) weld_normal[w] = from_corners[w];
}

/// Area-weighted normals per weld, shared by all vertices of that weld (across UV seams); with
/// `skin`, the skin's midpoints and centroids interpolate their corners' normals instead. A
/// face's normal is computed where it is used rather than stored: one Vec3 per face was the
/// largest array of a cracked frame's surfacing.
void compute_normals(const std::vector<Vec3>& position, const Numbered& num, TriMesh& mesh,
                     const std::vector<SlotTri>* skin = nullptr) {
    auto face_normal = [&](size_t f) {
        const Tri& t = mesh.faces[f];
        return Vec3((position[t[1]] - position[t[0]]).cross(position[t[2]] - position[t[0]]));
    };
    std::vector<Vec3> weld_normal(num.n_welds, Vec3::Zero());
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
        const Vec3 n = face_normal(f);
        for (int k = 0; k < 3; ++k) weld_normal[num.vertex_weld[mesh.faces[f][k]]] += n;
    }
    if (skin) interpolate_skin_normals(*skin, num, weld_normal);
    mesh.normals.resize(position.size());
    parallel_for(static_cast<int64_t>(position.size()), [&](int64_t v) {
        Vec3 n = weld_normal[num.vertex_weld[v]];
        const Vec3 own = face_normal(num.vertex_face[v]);
        if (!(n.norm() > 1e-12 * own.norm())) n = own;
        const Real len = n.norm();
        mesh.normals[v] = (len > 0 ? Vec3(n / len) : Vec3(0, 1, 0)).cast<float>();
    });
}

/// Positions, UVs and shading attributes of the numbered vertices, from a per-vertex evaluator.
template <class Eval>
std::vector<Vec3> fill_vertices(const FrameCores& cores, const Numbered& num, Eval&& eval,
                                TriMesh& mesh, std::vector<uint64_t>& keys) {
    const size_t nv = num.vertex_slot.size();
    std::vector<Vec3> position(nv);
    mesh.positions.resize(nv);
    mesh.uvs.resize(nv);
    keys.resize(nv);
    if (cores.has_saturation()) mesh.saturation.resize(nv);
    if (cores.has_alpha()) mesh.alpha.resize(nv);
    parallel_for(static_cast<int64_t>(nv), [&](int64_t v) {
        Vec2 uv;
        const FrameCores::Welded w = eval(num.vertex_slot[v], uv, keys[v]);
        position[v] = w.position;
        mesh.positions[v] = w.position.cast<float>();
        mesh.uvs[v] = uv.cast<float>();
        if (cores.has_saturation()) mesh.saturation[v] = static_cast<float>(w.saturation);
        if (cores.has_alpha()) mesh.alpha[v] = static_cast<float>(w.alpha);
    });
    return position;
}

/// The owners of rest point j (0-6, SkinFace numbering) of a skin face.
PointOwners skin_point(const FrameCores& cores, const SkinFace& sf, int j) {
    if (j < 3) return cores.particle_point(sf.corner[j]);
    if (j < 6) return cores.edge_point(sf.edge[j - 3]);
    return cores.face_point(sf.tet, sf.opposite);
}

void build_boundary(const CoreTopology& topo, const FrameCores& cores, const Fragments& frag,
                    SurfacedFrame& out) {
    TriMesh& mesh = out.boundary;
    const int64_t nb = static_cast<int64_t>(topo.skin_faces.size());
    // six skin triangles per boundary face, two per corner, owned by the corner particle
    std::vector<SlotTri> tris(nb * 6);
    parallel_for(nb, [&](int64_t i) {
        const SkinFace& sf = topo.skin_faces[i];
        std::array<PointOwners, 7> pt;
        for (int j = 0; j < 7; ++j) pt[j] = skin_point(cores, sf, j);
        for (int k = 0; k < 6; ++k) {
            const auto& corners = kSkinTriangles[k];
            const int32_t owner = sf.corner[corners[0]];
            SlotTri& t = tris[i * 6 + k];
            t.owner = frag.id[owner] >= 0 ? owner : -1;
            for (int c = 0; c < 3; ++c) {
                const PointOwners& o = pt[corners[c]];
                const int rep = o.rep[o.slot_of(owner)];
                const SkinUvVertex& uvv = topo.skin_uv_vertices[sf.uv_vertex[corners[c]]];
                t.out_slot[c] = uvv.out_slot + rep;
                t.weld_slot[c] = uvv.weld_slot + rep;
            }
        }
    });
    const Numbered num =
        number_vertices(tris, topo.n_skin_out_slots, topo.n_skin_weld_slots, frag, mesh);

    // out slot -> (skin face, rest point j) of some triangle using it, to evaluate the vertex
    std::vector<std::array<int32_t, 2>> slot_source(topo.n_skin_out_slots, {-1, -1});
    for (int64_t i = 0; i < nb; ++i)
        for (int j = 0; j < 7; ++j) {
            const SkinUvVertex& uvv = topo.skin_uv_vertices[topo.skin_faces[i].uv_vertex[j]];
            for (int r = 0; r <= static_cast<int>(uvv.kind); ++r)
                if (slot_source[uvv.out_slot + r][0] < 0)
                    slot_source[uvv.out_slot + r] = {int32_t(i), j};
        }
    auto eval = [&](int32_t slot, Vec2& uv, uint64_t& key) {
        const auto [i, j] = slot_source[slot];
        const SkinFace& sf = topo.skin_faces[i];
        const SkinUvVertex& uvv = topo.skin_uv_vertices[sf.uv_vertex[j]];
        const int rep = slot - uvv.out_slot;
        uv = uvv.uv;
        key = weld_key(uvv.kind, uvv.point, rep);
        return cores.welded(skin_point(cores, sf, j), rep);
    };
    const std::vector<Vec3> position = fill_vertices(cores, num, eval, mesh, out.boundary_weld_key);
    compute_normals(position, num, mesh, &tris);
}

/// The smallest projection axis that gives rest point y0 the same UV as `axis`, so a vertex is
/// split by projection only where its UVs actually differ.
int canonical_axis(const Vec3& y0, int axis, Real uv_per_meter) {
    const Vec2 uv = triplanar_uv(y0, axis, uv_per_meter);
    for (int a = 0; a < axis; ++a)
        if (triplanar_uv(y0, a, uv_per_meter) == uv) return a;
    return axis;
}

/// Parity of the permutation (i, j, k, l) of (0, 1, 2, 3): true when even.
bool is_even_permutation(int i, int j, int k, int l) {
    const int p[4] = {i, j, k, l};
    int inversions = 0;
    for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) inversions += p[a] > p[b];
    return inversions % 2 == 0;
}

/// Compact ranks of the faces and tets around the broken edges, in order of first use, and each
/// broken edge's first interface triangle (4 per incident tet).
struct CrackRanks {
    std::vector<int32_t> face_rank, tet_rank;         // -1: not around a broken edge
    std::vector<std::array<int32_t, 2>> active_face;  // (tet, opposite corner) by rank
    std::vector<int32_t> active_tet;                  // by rank
    std::vector<int64_t> tri_begin;                   // (broken edges + 1)
};

CrackRanks rank_crack_elements(const CoreTopology& topo, const std::vector<int32_t>& broken) {
    const int64_t nbr = static_cast<int64_t>(broken.size());
    CrackRanks ranks;
    std::vector<int32_t>& face_rank = ranks.face_rank;
    std::vector<int32_t>& tet_rank = ranks.tet_rank;
    std::vector<std::array<int32_t, 2>>& active_face = ranks.active_face;
    std::vector<int32_t>& active_tet = ranks.active_tet;
    std::vector<int64_t>& tri_begin = ranks.tri_begin;
    face_rank.assign(topo.n_faces, -1);
    tet_rank.assign(topo.n_tets(), -1);
    tri_begin.assign(nbr + 1, 0);
    for (int64_t r = 0; r < nbr; ++r) {
        const int32_t e = broken[r];
        const int32_t b = topo.edge_tet_begin[e], end = topo.edge_tet_begin[e + 1];
        tri_begin[r + 1] = tri_begin[r] + 4 * int64_t(end - b);
        for (int32_t c = b; c < end; ++c) {
            const int32_t t = topo.edge_tet[c] / 6;
            for (int l = 0; l < 4; ++l) {
                const int32_t f = topo.tet_faces[t][l];
                const auto& ij = kTetEdgeCorners[topo.edge_tet[c] % 6];
                if (l == ij[0] || l == ij[1] || face_rank[f] >= 0) continue;
                face_rank[f] = static_cast<int32_t>(active_face.size());
                active_face.push_back({t, l});
            }
            if (tet_rank[t] < 0) {
                tet_rank[t] = static_cast<int32_t>(active_tet.size());
                active_tet.push_back(t);
            }
        }
    }
    return ranks;
}

/// Culls (owner -1) the wall triangles of this frame that reach no surface: the parts of the walls,
/// joined through shared weld slots, with no point on the skin (a skin edge's midpoint or a skin
/// face's centroid). A wall inside the soil (a cavity left by a grain torn loose, a hairline) is
/// a closed surface of its own that no camera sees, and the wall graph holds its nodes where the
/// dual cells put them. Decided on the frame's own walls, not the last frame's: a wall hidden at
/// the end can be joined to a visible one earlier, while the cuts between them are still to come,
/// and culling it then would leave a hole in the visible one. Sequential, hence deterministic.
void hide_unseen_walls(const CoreTopology& topo, const std::vector<int32_t>& broken,
                       const CrackRanks& ranks, int64_t face0, int64_t n_weld,
                       std::vector<SlotTri>& tris) {
    UnionFind walls(static_cast<int32_t>(n_weld));
    for (const SlotTri& t : tris)
        if (t.owner >= 0)
            walls.unite(t.weld_slot[0], t.weld_slot[1]),
                walls.unite(t.weld_slot[0], t.weld_slot[2]);
    std::vector<uint8_t> seen(n_weld, 0);  // by root
    auto see = [&](int64_t first_slot, int n_slots) {
        for (int k = 0; k < n_slots; ++k)
            seen[walls.find(static_cast<int32_t>(first_slot + k))] = 1;
    };
    for (const SkinFace& sf : topo.skin_faces) {
        if (ranks.face_rank[sf.face] >= 0) see(face0 + 3 * int64_t(ranks.face_rank[sf.face]), 3);
        for (int32_t e : sf.edge) {
            // broken is ascending
            const auto r = std::lower_bound(broken.begin(), broken.end(), e);
            if (r != broken.end() && *r == e) see(2 * int64_t(r - broken.begin()), 2);
        }
    }
    for (SlotTri& t : tris)
        if (t.owner >= 0 && !seen[walls.find(t.weld_slot[0])]) t.owner = -1;
}

void build_crack(const CoreTopology& topo, const FrameCores& cores, const Fragments& frag,
                 const std::vector<uint8_t>& is_broken, SurfacedFrame& out) {
    TriMesh& mesh = out.crack;
    std::vector<int32_t> broken;
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (is_broken[e]) broken.push_back(e);
    const int64_t nbr = static_cast<int64_t>(broken.size());

    // faces and tets around broken edges get compact ranks, in order of first use
    CrackRanks ranks = rank_crack_elements(topo, broken);
    std::vector<int32_t>& face_rank = ranks.face_rank;
    std::vector<int32_t>& tet_rank = ranks.tet_rank;
    const std::vector<std::array<int32_t, 2>>& active_face = ranks.active_face;
    const std::vector<int32_t>& active_tet = ranks.active_tet;
    const std::vector<int64_t>& tri_begin = ranks.tri_begin;
    // weld slots: 2 per broken-edge midpoint, 3 per active face centroid, 4 per active tet
    // centroid; out slot = 3 * weld slot + projection axis
    const int64_t face0 = 2 * nbr, tet0 = face0 + 3 * int64_t(active_face.size());
    const int64_t n_weld = tet0 + 4 * int64_t(active_tet.size());

    // per (broken edge, incident tet): 2 interface triangles, each on both sides
    std::vector<SlotTri> tris(tri_begin[nbr]);
    parallel_for(nbr, [&](int64_t r) {
        const int32_t e = broken[r];
        const PointOwners m = cores.edge_point(e);
        for (int32_t c = topo.edge_tet_begin[e]; c < topo.edge_tet_begin[e + 1]; ++c) {
            const int32_t t = topo.edge_tet[c] / 6, le = topo.edge_tet[c] % 6;
            const int i = kTetEdgeCorners[le][0], j = kTetEdgeCorners[le][1];
            int k = -1, l = -1;
            for (int q = 0; q < 4; ++q)
                if (q != i && q != j) (k < 0 ? k : l) = q;
            // c_ijk is the face opposite l, c_ijl the face opposite k
            const PointOwners ck = cores.face_point(t, l), cl = cores.face_point(t, k),
                              g = cores.tet_point(t);
            const int64_t wck = face0 + 3 * int64_t(face_rank[topo.tet_faces[t][l]]);
            const int64_t wcl = face0 + 3 * int64_t(face_rank[topo.tet_faces[t][k]]);
            const int64_t wg = tet0 + 4 * int64_t(tet_rank[t]);
            const int axis_k = dominant_axis((ck.y0 - m.y0).cross(g.y0 - m.y0));
            const int axis_l = dominant_axis((cl.y0 - m.y0).cross(g.y0 - m.y0));
            // (m, c_ijk, g) points from i towards j iff (i, j, k, l) is an even permutation
            const bool even = is_even_permutation(i, j, k, l);
            int64_t out_index = tri_begin[r] + 4 * int64_t(c - topo.edge_tet_begin[e]);
            for (int side = 0; side < 2; ++side) {
                const int32_t owner = topo.tets[t][side == 0 ? i : j];
                auto corner = [&](const PointOwners& o, int64_t w0, int axis, SlotTri& tri,
                                  int slot) {
                    const int rep = o.rep[o.slot_of(owner)];
                    axis = canonical_axis(o.y0, axis, topo.uv_per_meter);
                    tri.weld_slot[slot] = static_cast<int32_t>(w0 + rep);
                    tri.out_slot[slot] = static_cast<int32_t>(3 * (w0 + rep) + axis);
                };
                // side i keeps (m, c_ijk, g) when even; side j is the mirror image
                const bool flip_k = (side == 0) != even;
                SlotTri& tk = tris[out_index++];
                SlotTri& tl = tris[out_index++];
                tk.owner = tl.owner = frag.id[owner] >= 0 ? owner : -1;
                corner(m, 2 * r, axis_k, tk, 0);
                corner(ck, wck, axis_k, tk, flip_k ? 2 : 1);
                corner(g, wg, axis_k, tk, flip_k ? 1 : 2);
                corner(m, 2 * r, axis_l, tl, 0);
                corner(cl, wcl, axis_l, tl, flip_k ? 1 : 2);
                corner(g, wg, axis_l, tl, flip_k ? 2 : 1);
            }
        }
    });
    if (cores.hides_unseen_walls()) hide_unseen_walls(topo, broken, ranks, face0, n_weld, tris);
    Numbered num = number_vertices(tris, 3 * n_weld, n_weld, frag, mesh);
    // released before the vertices are made, which is the peak of a frame's surfacing
    std::vector<SlotTri>().swap(tris);
    std::vector<int32_t>().swap(face_rank);
    std::vector<int32_t>().swap(tet_rank);
    // the skin's corner normals need it, the walls not
    std::vector<int32_t>().swap(num.weld_of_slot);

    auto eval = [&](int32_t slot, Vec2& uv, uint64_t& key) {
        const int64_t w = slot / 3;
        const int axis = slot % 3;
        PointOwners o;
        int rep;
        if (w < face0) {
            o = cores.edge_point(broken[w / 2]);
            rep = static_cast<int>(w % 2);
            key = weld_key(RestPointKind::EdgeMidpoint, broken[w / 2], rep);
        } else if (w < tet0) {
            const auto [t, l] = active_face[(w - face0) / 3];
            o = cores.face_point(t, l);
            rep = static_cast<int>((w - face0) % 3);
            key = weld_key(RestPointKind::FaceCentroid, topo.tet_faces[t][l], rep);
        } else {
            const int32_t t = active_tet[(w - tet0) / 4];
            o = cores.tet_point(t);
            rep = static_cast<int>((w - tet0) % 4);
            key = weld_key(RestPointKind::TetCentroid, t, rep);
        }
        uv = triplanar_uv(o.y0, axis, topo.uv_per_meter);
        return cores.welded(o, rep);
    };
    const std::vector<Vec3> position = fill_vertices(cores, num, eval, mesh, out.crack_weld_key);
    compute_normals(position, num, mesh);
}

/// The plates mode's debris (DebrisOutput::Points): the particles that tore loose.
DebrisPoints collect_debris(const CoreTopology& topo, const ParticleFrame& frame,
                            const Pieces& pieces, Real spacing) {
    DebrisPoints d;
    const Real radius = spacing / 2;
    for (int32_t p = 0; p < topo.n_particles; ++p) {
        if (pieces.id[p] != kDebris) continue;
        d.position.push_back(frame.P[p]);
        d.velocity.push_back(frame.v.empty() ? Vec3f::Zero() : frame.v[p]);
        d.radius.push_back(
            float(radius * (frame.Jw.empty() ? 1.0 : std::cbrt(double(frame.Jw[p])))));
        d.id.push_back(p);
        d.piece.push_back(pieces.root[p] >= 0 ? pieces.id[pieces.root[p]] : -1);
    }
    return d;
}

/// The plates mode: the frame's pieces and walls from the shot's fracture, close gaps, then the
/// same meshing as the other modes. With `in_sequence`, the frame is one of a shot's frames and
/// fresh cracks part at params.open_speed (0: at once); else (a frame on its own) they show at
/// once.
void surface_plates(const CoreTopology& topo, const ParticleFrame& frame,
                    const ShotFracture& fracture, const SurfaceParams& params, bool in_sequence,
                    SurfacedFrame& out) {
    Pieces pieces = pieces_at_frame(topo, fracture, frame.frame);
    Fragments frag;
    frag.id = pieces.id;  // kDebris is a culled fragment's -1
    frag.count = pieces.count;
    out.fragments = pieces.count;
    out.debris_particles = pieces.debris;
    const Real spacing = mean_particle_spacing(topo);
    if (params.debris == DebrisOutput::Points)
        out.debris = collect_debris(topo, frame, pieces, spacing);

    out.wall_points_smoothed = static_cast<int64_t>(fracture.walls.size());
    PlateCores plates;
    plates.walls = &fracture.walls;
    plates.wall_graph = &fracture.wall_graph;
    plates.wall_motion = &fracture.wall_motion;
    plates.wall_steps = params.wall_smoothing;
    plates.piece = &pieces.id;
    plates.close_gap = params.close_gaps * spacing;
    if (in_sequence) {
        plates.cut_frame = &fracture.cut_frame;
        plates.cut_edges = &fracture.cut_edges;
        plates.max_eased_gap = kMaxEasedGap * spacing;
        plates.easing_frames = easing_frames(params);
        plates.open_speed = params.open_speed * spacing;
    }
    const FrameCores cores(topo, frame, pieces.is_cut, params, plates);
    build_boundary(topo, cores, frag, out);
    if (params.cracks) build_crack(topo, cores, frag, pieces.is_cut, out);
    out.particle_piece = std::move(pieces.id);
    if (in_sequence && params.open_speed > 0) {
        // a cut has eased in from its age easing_frames on
        out.edge_settled.assign(topo.edges.size(), 0);
        const int settled_by = frame.frame + 1 - plates.easing_frames;
        parallel_for(topo.n_edges(), [&](int64_t e) {
            out.edge_settled[e] = fracture.cut_frame[e] <= settled_by ? 1 : 0;
        });
    } else {
        out.edge_settled = pieces.is_cut;
    }
    out.edge_cut = std::move(pieces.is_cut);
}

}  // namespace

int easing_frames(const SurfaceParams& params) {
    if (!(params.open_speed > 0)) return 0;
    // a cut of age a eases in min(|way|, kMaxEasedGap) - a open_speed > 0: ages below this
    return static_cast<int>(std::ceil(kMaxEasedGap / params.open_speed - 1e-9));
}

SurfacedFrame surface_frame(const CoreTopology& topo, const ParticleFrame& frame,
                            const std::vector<int32_t>& first_break, const SurfaceParams& params,
                            const ShotFracture* fracture) {
    check_frame_fits(topo, frame);
    if (first_break.size() != topo.edges.size())
        throw InputError("frame " + std::to_string(frame.frame) + ": edge break history has " +
                         std::to_string(first_break.size()) + " edges; the tet mesh has " +
                         std::to_string(topo.edges.size()));
    SurfacedFrame out;
    out.boundary.name = "boundary";
    out.crack.name = "crack";

    // Eq. 14 with the permanent broken state: broken at n iff it first broke at some t <= n
    std::vector<uint8_t> is_broken(topo.edges.size());
    parallel_for(topo.n_edges(),
                 [&](int64_t e) { is_broken[e] = first_break[e] <= frame.frame ? 1 : 0; });
    out.broken_edges = count_broken_edges(first_break, frame.frame);
    if (params.mode == SurfaceMode::Plates) {
        if (fracture) {
            surface_plates(topo, frame, *fracture, params, true, out);
        } else {
            surface_plates(topo, frame, plan_shot_fracture(topo, frame, first_break, params),
                           params, false, out);
        }
        return out;
    }

    const Fragments frag = find_fragments(topo, is_broken, params.min_fragment_particles);
    out.fragments = frag.count;
    out.culled_fragments = frag.culled;

    const FrameCores cores(topo, frame, is_broken, params);
    build_boundary(topo, cores, frag, out);
    if (params.cracks) build_crack(topo, cores, frag, is_broken, out);
    out.edge_settled = is_broken;
    out.edge_cut = std::move(is_broken);
    return out;
}

}  // namespace mudcrack
