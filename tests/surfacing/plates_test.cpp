// The plates surfacing (docs/physics.md §5.7): pieces from a torn band, smoothed walls, closed
// gaps, debris, and the analytic width of a piece.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "surfacing/core_surface.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/lattice_mesh.h"
#include "surfacing/pieces.h"
#include "surfacing/shot_fracture.h"
#include "surfacing/wall_deformation.h"
#include "surfacing/wall_smoothing.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

using test::box_lattice;

constexpr double kH = 0.1;  // lattice spacing [m]
constexpr int kNx = 12, kNy = 3, kNz = 4;

int column_of(const Vec3& X) { return int(std::lround(X.x() / kH)); }

/// A slab torn along a band two particles wide (columns 5 and 6): every edge with a band particle
/// broke, so Eq. 14 leaves each band particle a chip of its own. Plates: columns 0-4 and 7-12.
struct TornSlab {
    TetMesh mesh = box_lattice(kNx, kNy, kNz, kH);
    CoreTopology topo = build_core_topology(mesh);
    std::vector<int32_t> first_break = no_edge_breaks(topo);

    TornSlab() {
        for (int32_t e = 0; e < topo.n_edges(); ++e) {
            const int a = column_of(topo.X[topo.edges[e][0]]),
                      b = column_of(topo.X[topo.edges[e][1]]);
            if (a == 5 || a == 6 || b == 5 || b == 6) first_break[e] = 1;
        }
    }
    /// Frame 1: the right plate and column 6 moved +dx (column 5 goes with the left plate).
    ParticleFrame opened(double dx) const {
        ParticleFrame f;
        f.frame = 1;
        for (const Vec3& X : topo.X) {
            const bool right = column_of(X) >= 6;
            f.P.push_back((X + Vec3(right ? dx : 0, 0, 0)).cast<float>());
            f.Fe.push_back(Mat3f::Identity());
        }
        return f;
    }
    std::vector<uint8_t> broken() const {
        std::vector<uint8_t> b(first_break.size());
        for (size_t e = 0; e < b.size(); ++e) b[e] = first_break[e] <= 1;
        return b;
    }
    /// The plates mode's fracture of the slab, planned from frame 1 opened 5 cm.
    ShotFracture fracture() const;
};

SurfaceParams plates_params() {
    SurfaceParams p;
    p.mode = SurfaceMode::Plates;
    p.cell_size = 2 * kH;  // /sim/h: two particle spacings, as in the shipped shots
    p.min_piece_size = 1;  // plates at least 0.2 m across
    return p;
}

ShotFracture TornSlab::fracture() const {
    return plan_shot_fracture(topo, opened(0.05), first_break, plates_params());
}

/// The connected groups of a mesh's faces through shared weld keys.
int count_sheets(const TriMesh& mesh, const std::vector<uint64_t>& key, int32_t piece) {
    // union-find over face indices, joined through shared keys
    std::vector<int> up;
    std::map<uint64_t, int> first_face;
    auto root = [&](int f) {
        while (up[f] != f) f = up[f] = up[up[f]];
        return f;
    };
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
        up.push_back(int(f));
        if (mesh.face_fragment[f] != piece) continue;
        for (int32_t v : mesh.faces[f]) {
            const auto [it, added] = first_face.try_emplace(key[v], int(f));
            if (!added) up[root(int(f))] = root(it->second);
        }
    }
    std::set<int> roots;
    for (size_t f = 0; f < mesh.faces.size(); ++f)
        if (mesh.face_fragment[f] == piece) roots.insert(root(int(f)));
    return int(roots.size());
}

/// Every edge of a piece, by weld key over both meshes, is used once in each direction.
bool is_closed(const SurfacedFrame& s, int32_t piece) {
    std::map<std::pair<uint64_t, uint64_t>, int> directed;
    auto add = [&](const TriMesh& m, const std::vector<uint64_t>& key) {
        for (size_t f = 0; f < m.faces.size(); ++f)
            if (m.face_fragment[f] == piece)
                for (int k = 0; k < 3; ++k)
                    ++directed[{key[m.faces[f][k]], key[m.faces[f][(k + 1) % 3]]}];
    };
    add(s.boundary, s.boundary_weld_key);
    add(s.crack, s.crack_weld_key);
    for (const auto& [e, n] : directed)
        if (n != 1 || !directed.count({e.second, e.first})) return false;
    return !directed.empty();
}

TEST(PieceWidth, IsTheSmallerInPlaneSideOfALatticeSlab) {
    // n points spaced a along an axis have variance a^2 (n^2 - 1) / 12: the width is n a exactly
    auto width = [](int nx, int ny, int nz, double a) {
        Vec3 sum = Vec3::Zero();
        Mat3 outer = Mat3::Zero();
        for (int i = 0; i < nx; ++i)
            for (int j = 0; j < ny; ++j)
                for (int k = 0; k < nz; ++k) {
                    const Vec3 x = a * Vec3(i, j, k);
                    sum += x;
                    outer += x * x.transpose();
                }
        return piece_width(sum, outer, int64_t(nx) * ny * nz, a);
    };
    // a crust plate: its short side
    EXPECT_NEAR(width(20, 3, 10, 0.01), 0.10, tol::kRoundoffLoose);
    EXPECT_NEAR(width(10, 1, 1, 0.01), 0.01, tol::kRoundoffLoose);  // a sliver: its thickness
    EXPECT_NEAR(width(1, 1, 1, 0.01), 0.01, tol::kRoundoff);        // one particle: the spacing
}

TEST(Pieces, ATornBandOfKnownWidthBecomesTwoPiecesWithOneWallEach) {
    const TornSlab slab;
    const ParticleFrame frame = slab.opened(0.05);
    PieceParams params;
    params.min_width = 2 * kH;
    const Pieces pieces = find_pieces(slab.topo, frame, slab.broken(), params);
    EXPECT_EQ(pieces.count, 2);
    EXPECT_EQ(pieces.debris, 0);
    // each band particle goes with the side it moved with; ids are the plates' smallest particles
    for (int32_t p = 0; p < slab.topo.n_particles; ++p)
        EXPECT_EQ(pieces.id[p], column_of(slab.topo.X[p]) <= 5 ? 0 : 8) << "particle " << p;
    // the only cut edges are those between columns 5 and 6: one wall
    for (int32_t e = 0; e < slab.topo.n_edges(); ++e) {
        const int a = column_of(slab.topo.X[slab.topo.edges[e][0]]),
                  b = column_of(slab.topo.X[slab.topo.edges[e][1]]);
        EXPECT_EQ(pieces.is_cut[e] != 0, std::min(a, b) == 5 && std::max(a, b) == 6)
            << "edge " << e;
    }

    const SurfacedFrame s = surface_frame(slab.topo, frame, slab.first_break, plates_params());
    EXPECT_EQ(s.fragments, 2);
    std::set<int32_t> ids(s.boundary.face_fragment.begin(), s.boundary.face_fragment.end());
    // particle 8: the first of column 8, the first untorn one
    EXPECT_EQ(ids, (std::set<int32_t>{0, 8}));
    for (int32_t piece : {0, 8}) {
        EXPECT_TRUE(is_closed(s, piece)) << "piece " << piece;
        EXPECT_EQ(count_sheets(s.crack, s.crack_weld_key, piece), 1)
            << "piece " << piece << ": one wall";
    }
}

TEST(Pieces, ACrackThatEndsInsideAPlateStaysCut) {
    // edges across the plane x = 0.55 broken only in the back half (z >= 0.2): one fragment,
    // no band particle, the crack still a cut inside the one piece
    const TornSlab slab;
    std::vector<uint8_t> broken(slab.topo.edges.size(), 0);
    int64_t n_broken = 0;
    for (int32_t e = 0; e < slab.topo.n_edges(); ++e) {
        const auto [p, q] = slab.topo.edges[e];
        const int a = column_of(slab.topo.X[p]), b = column_of(slab.topo.X[q]);
        if (std::min(a, b) == 5 && std::max(a, b) == 6 &&
            std::min(slab.topo.X[p].z(), slab.topo.X[q].z()) >= 0.2 - 1e-9)
            n_broken += broken[e] = 1;
    }
    ASSERT_GT(n_broken, 0);
    PieceParams params;
    params.min_width = 2 * kH;
    const Pieces pieces = find_pieces(slab.topo, slab.opened(0), broken, params);
    EXPECT_EQ(pieces.count, 1);
    EXPECT_EQ(pieces.is_cut, broken);
}

TEST(Pieces, AParticleTornFromBothSidesIsDebrisAndRemembersItsPiece) {
    const TornSlab slab;
    ParticleFrame frame = slab.opened(0.05);
    int32_t grain = -1;
    for (int32_t p = 0; p < slab.topo.n_particles && grain < 0; ++p)
        // on the top
        if (column_of(slab.topo.X[p]) == 5 && slab.topo.X[p].y() > 2.5 * kH) grain = p;
    frame.P[grain] += Vec3f(0, 0.5f, 0);  // thrown up: every edge stretched far past 1.5
    frame.v.assign(frame.P.size(), Vec3f::Zero());
    frame.v[grain] = Vec3f(0, 2, 0);
    SurfaceParams params = plates_params();
    params.debris = DebrisOutput::Points;
    const SurfacedFrame s = surface_frame(slab.topo, frame, slab.first_break, params);
    EXPECT_EQ(s.debris_particles, 1);
    ASSERT_EQ(s.debris.size(), 1u);
    EXPECT_EQ(s.debris.id[0], grain);
    EXPECT_EQ(s.debris.piece[0], 0);  // column 5: the left plate, nearest through the rest mesh
    EXPECT_EQ(s.debris.velocity[0], Vec3f(0, 2, 0));
    // no Jw: not dried
    EXPECT_NEAR(s.debris.radius[0], mean_particle_spacing(slab.topo) / 2, tol::kFloat);
    EXPECT_TRUE(is_closed(s, 0));  // the plate it left is still closed
    EXPECT_EQ(s.particle_piece[grain], kDebris);
}

/// The positions of a piece's crack vertices, one per face corner.
std::vector<Vec3f> wall_positions(const SurfacedFrame& s, int32_t piece) {
    std::vector<Vec3f> out;
    for (size_t f = 0; f < s.crack.faces.size(); ++f)
        if (s.crack.face_fragment[f] == piece)
            for (int32_t v : s.crack.faces[f]) out.push_back(s.crack.positions[v]);
    return out;
}

Vec3 mean(const std::vector<Vec3f>& xs) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3f& x : xs) sum += x.cast<double>();
    return sum / double(xs.size());
}

TEST(Plates, ACrackOpensAsFarAsThePlatesMovedAndAClosedOneShowsNoGap) {
    const TornSlab slab;
    const SurfaceParams params = plates_params();  // close_gaps: 0.25 spacings = 0.025 m
    // moved apart by 0.01 m: under close_gaps, the two walls coincide corner for corner
    const SurfacedFrame closed =
        surface_frame(slab.topo, slab.opened(0.01), slab.first_break, params);
    const auto left = wall_positions(closed, 0), right = wall_positions(closed, 8);
    ASSERT_FALSE(left.empty());
    ASSERT_EQ(left.size(), right.size());
    std::multiset<std::array<float, 3>> l, r;
    for (size_t i = 0; i < left.size(); ++i) {
        l.insert({left[i].x(), left[i].y(), left[i].z()});
        r.insert({right[i].x(), right[i].y(), right[i].z()});
    }
    EXPECT_EQ(l, r);
    // moved apart by 0.2 m (past 2 close_gaps): each wall where its plate put it, 0.2 m apart
    const SurfacedFrame open = surface_frame(slab.topo, slab.opened(0.2), slab.first_break, params);
    const Vec3 gap = mean(wall_positions(open, 8)) - mean(wall_positions(open, 0));
    EXPECT_NEAR(gap.x(), 0.2, tol::kFloat);
    EXPECT_NEAR(gap.y(), 0.0, tol::kFloat);
    EXPECT_NEAR(gap.z(), 0.0, tol::kFloat);
}

TEST(Plates, SmoothingFlattensTheDualCellStaircase) {
    // the cut between columns 5 and 6 of a Kuhn lattice: midpoints at x = 0.55, face and tet
    // centroids off it by up to h/4 - a staircase; smoothed, the wall lies near one plane
    const TornSlab slab;
    auto spread = [&](int iterations) {
        SurfaceParams params = plates_params();
        params.wall_smoothing = iterations;
        const SurfacedFrame s = surface_frame(slab.topo, slab.opened(0), slab.first_break, params);
        double lo = 1e30, hi = -1e30;
        for (const Vec3f& x : wall_positions(s, 0)) {
            lo = std::min(lo, double(x.x()));
            hi = std::max(hi, double(x.x()));
        }
        return hi - lo;
    };
    const double staircase = spread(0), smoothed = spread(10);
    EXPECT_GT(staircase, 0.4 * kH);
    EXPECT_LT(smoothed, 0.25 * staircase);
}

TEST(WallSmoothing, ACutAtAnAngleLiesCloserToItsPlaneThanTheDualCells) {
    // a plane at 24 degrees to the lattice: the dual cells' wall points scatter 0.3-0.4 spacings
    // about it; the fitted crossings and their mass points stay within a third of that
    const TetMesh mesh = box_lattice(12, 4, 12, kH);
    const CoreTopology topo = build_core_topology(mesh);
    const Vec3 n = Vec3(1, 0, 0.45).normalized();
    const double offset = n.dot(Vec3(0.6, 0, 0.6));
    auto side = [&](const Vec3& x) { return n.dot(x) - offset; };
    std::vector<uint8_t> cut(topo.edges.size());
    std::vector<int32_t> label(topo.n_particles);
    for (int32_t p = 0; p < topo.n_particles; ++p) label[p] = side(topo.X[p]) > 0;
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        cut[e] = label[topo.edges[e][0]] != label[topo.edges[e][1]];
    auto rms = [&](int iterations, RestPointKind kind) {
        const WallRestPositions w = smooth_walls(topo, cut, iterations);
        double sum = 0;
        int n_points = 0;
        for (int32_t t = 0; t < topo.n_tets(); ++t) {
            const Tet& c = topo.tets[t];
            bool crossed = false;
            for (int32_t e : topo.tet_edges[t]) crossed |= cut[e] != 0;
            if (!crossed) continue;
            const Vec3 centroid = (topo.X[c[0]] + topo.X[c[1]] + topo.X[c[2]] + topo.X[c[3]]) / 4;
            const Vec3 y = kind == RestPointKind::TetCentroid ? w.of(kind, t, centroid) : centroid;
            sum += side(y) * side(y);
            ++n_points;
        }
        return std::sqrt(sum / n_points);
    };
    const double dual = rms(0, RestPointKind::TetCentroid),
                 smoothed = rms(10, RestPointKind::TetCentroid);
    EXPECT_GT(dual, 0.3 * kH);
    EXPECT_LT(smoothed, dual / 2.5);
}

TEST(Plates, AFrameIsTheSameWhateverWasSurfacedBefore) {
    const TornSlab slab;
    const SurfaceParams params = plates_params();
    const SurfacedFrame a = surface_frame(slab.topo, slab.opened(0.05), slab.first_break, params);
    surface_frame(slab.topo, slab.opened(0.3), slab.first_break, params);
    const SurfacedFrame b = surface_frame(slab.topo, slab.opened(0.05), slab.first_break, params);
    EXPECT_EQ(a.boundary.positions, b.boundary.positions);
    EXPECT_EQ(a.crack.positions, b.crack.positions);
    EXPECT_EQ(a.crack.faces, b.crack.faces);
    EXPECT_EQ(a.crack.face_fragment, b.crack.face_fragment);
}

TEST(Plates, NoPlateWideEnoughLeavesOnlyDebris) {
    const TornSlab slab;
    SurfaceParams params = plates_params();
    params.min_piece_size = 100;  // 20 m: wider than the slab
    const SurfacedFrame s = surface_frame(slab.topo, slab.opened(0.05), slab.first_break, params);
    EXPECT_EQ(s.fragments, 0);
    EXPECT_EQ(s.debris_particles, slab.topo.n_particles);
    EXPECT_TRUE(s.boundary.faces.empty());
}

/// The slab of TornSlab whose band breaks in two stages: its top half (y above 1.5 spacings) at
/// frame `top`, the rest at frame `bottom`; `last` is its last frame, the plates `dx` apart.
struct StagedTear {
    TornSlab slab;
    int last;
    ParticleFrame last_frame;

    StagedTear(int top, int bottom, int last_frame_number, double dx) : last(last_frame_number) {
        for (int32_t e = 0; e < slab.topo.n_edges(); ++e) {
            if (slab.first_break[e] == kNeverBroken) continue;
            const auto [p, q] = slab.topo.edges[e];
            const bool upper = std::min(slab.topo.X[p].y(), slab.topo.X[q].y()) > 1.5 * kH;
            slab.first_break[e] = upper ? top : bottom;
        }
        last_frame = at(last, dx);
    }
    ParticleFrame at(int frame, double dx) const {
        ParticleFrame f = slab.opened(dx);
        f.frame = frame;
        return f;
    }
};

/// The shot's fracture as mc-surface plans it: from the last frame, with each cut edge recorded
/// the frame before its cut (record_cut_edges) from frame_at(n), n in [1, last).
template <class FrameAt>
ShotFracture plan_fracture(const TornSlab& slab, int last, const SurfaceParams& params,
                           FrameAt&& frame_at) {
    ShotFracture fracture = plan_shot_fracture(slab.topo, frame_at(last), slab.first_break, params);
    record_cut_edges_for(slab.topo, fracture, 1, 1, last, easing_frames(params), frame_at);
    return fracture;
}

TEST(ShotFracture, RecordsEachCutEdgeTheFrameBeforeItsCut) {
    // the upper band is cut at frame 2 and the lower at 5: frames 1 and 4 are recorded, each
    // cut edge as where its particles stood then (the right plate 0.01 m further each frame)
    const StagedTear tear(2, 5, 6, 0);
    const SurfaceParams params = plates_params();
    auto frame_at = [&](int n) { return tear.at(n, 0.01 * n); };
    const ShotFracture fracture = plan_fracture(tear.slab, tear.last, params, frame_at);
    EXPECT_EQ(easing_frames(params), 20);  // 4 spacings at 0.2 a frame
    EXPECT_EQ(frames_before_cuts(fracture, 1, 1, tear.last, 10), (std::vector<int>{1, 4}));
    // frame 6 alone: the cut at 2 has eased in by then, the one at 5 has not
    EXPECT_EQ(frames_before_cuts(fracture, 1, 6, 6, 3), (std::vector<int>{4}));
    EXPECT_EQ(frames_before_cuts(fracture, 1, 6, 6, 2), (std::vector<int>{}));
    EXPECT_EQ(frames_before_cuts(fracture, 1, 6, 6, 10), (std::vector<int>{1, 4}));
    int recorded = 0;
    ASSERT_EQ(fracture.cut_edges.edge.size(), fracture.cut_edges.vector.size());
    for (int32_t e = 0; e < tear.slab.topo.n_edges(); ++e) {
        const int32_t f = fracture.cut_frame[e];
        const bool listed =
            std::binary_search(fracture.cut_edges.edge.begin(), fracture.cut_edges.edge.end(), e);
        EXPECT_EQ(listed, f != kNeverBroken) << "edge " << e;
        if (!listed) continue;
        const auto [p, q] = tear.slab.topo.edges[e];
        const ParticleFrame before = frame_at(f - 1);
        EXPECT_EQ(fracture.cut_edges.of(e), Vec3f(before.P[q] - before.P[p])) << "edge " << e;
        ++recorded;
    }
    EXPECT_GT(recorded, 0);
}

TEST(ShotFracture, EachFrameShowsTheLastFramesCutsMadeByThenAndPiecesOnlySplit) {
    const StagedTear tear(2, 5, 6, 0.05);
    const SurfaceParams params = plates_params();
    const ShotFracture fracture =
        plan_shot_fracture(tear.slab.topo, tear.last_frame, tear.slab.first_break, params);
    // the last frame is find_pieces of the last frame
    PieceParams piece_params;
    piece_params.min_width = params.min_piece_size * params.cell_size;
    std::vector<uint8_t> broken_last(tear.slab.first_break.size());
    for (size_t e = 0; e < broken_last.size(); ++e)
        broken_last[e] = tear.slab.first_break[e] <= tear.last;
    const Pieces direct = find_pieces(tear.slab.topo, tear.last_frame, broken_last, piece_params);
    const Pieces last = pieces_at_frame(tear.slab.topo, fracture, tear.last);
    EXPECT_EQ(last.id, direct.id);
    EXPECT_EQ(last.is_cut, direct.is_cut);
    EXPECT_EQ(last.count, 2);

    std::vector<uint8_t> cut_before(tear.slab.topo.edges.size(), 0);
    std::vector<int32_t> id_before(tear.slab.topo.n_particles, 0);
    for (int n = 1; n <= tear.last; ++n) {
        const Pieces now = pieces_at_frame(tear.slab.topo, fracture, n);
        for (int32_t e = 0; e < tear.slab.topo.n_edges(); ++e) {
            // a cut of frame n is one of the last frame's cuts, made by then, and stays made
            if (now.is_cut[e]) {
                EXPECT_TRUE(direct.is_cut[e] && tear.slab.first_break[e] <= n) << "edge " << e;
            }
            EXPECT_GE(now.is_cut[e], cut_before[e]) << "frame " << n << ", edge " << e;
        }
        // the top half alone does not part the plates: one piece, with the smaller id, until frame
        // 5
        EXPECT_EQ(now.count, n < 5 ? 1 : 2) << "frame " << n;
        for (int32_t p = 0; p < tear.slab.topo.n_particles; ++p) {
            EXPECT_EQ(now.id[p], n < 5 ? 0 : direct.id[p]) << "frame " << n << ", particle " << p;
            // a piece keeps its id until it splits, then the part with its smallest particle does
            if (now.id[p] != id_before[p]) {
                EXPECT_EQ(n, 5);
            }
        }
        cut_before = now.is_cut;
        id_before = now.id;
    }
}

TEST(Plates, ACrackCutAfterItsParticlesPartedOpensAtABoundedSpeedThenAsFarAsThePlates) {
    // the band is 0.2 m open from the start but breaks only at frame 3: in a shot its walls part
    // by at most 2 open_speed (0.2) spacings a frame, then sit 0.2 m apart, as the frame surfaced
    // on its own shows them at once
    const StagedTear tear(3, 3, 20, 0.2);
    const SurfaceParams params = plates_params();
    const ShotFracture fracture =
        plan_fracture(tear.slab, tear.last, params, [&](int n) { return tear.at(n, 0.2); });
    const double speed = params.open_speed * mean_particle_spacing(tear.slab.topo);
    ASSERT_EQ(params.open_speed, 0.2);
    double gap_before = 0;
    for (int n = 3; n <= tear.last; ++n) {
        const SurfacedFrame s = surface_frame(tear.slab.topo, tear.at(n, 0.2),
                                              tear.slab.first_break, params, &fracture);
        ASSERT_EQ(s.fragments, 2) << "frame " << n;
        const double gap = (mean(wall_positions(s, 8)) - mean(wall_positions(s, 0))).x();
        EXPECT_LE(gap - gap_before, 2 * speed + tol::kFloat) << "frame " << n;
        EXPECT_GE(gap, gap_before - tol::kFloat) << "frame " << n;
        gap_before = gap;
    }
    EXPECT_NEAR(gap_before, 0.2, tol::kFloat);  // by frame 20 each side has parted its last
    // the same frame on its own (no shot around it) shows the crack as open as its plates
    const SurfacedFrame alone =
        surface_frame(tear.slab.topo, tear.at(3, 0.2), tear.slab.first_break, params);
    EXPECT_NEAR((mean(wall_positions(alone, 8)) - mean(wall_positions(alone, 0))).x(), 0.2,
                tol::kFloat);
}

TEST(Plates, ACrackThatKeepsWideningAfterItsCutShowsAllItsPlatesOpenedSinceEveryFrame) {
    // the band stands closed until its cut at frame 3, then the right plate moves 0.05 m a
    // frame, faster than open_speed (0.02 m): nothing was apart when it was welded, so nothing
    // is eased in, and the walls stand as far apart as the plates every frame. (A bound on the
    // walls' parting speed, as before, held them 0.04 m a frame apart: along a real rim, points
    // cut at different frames stood at different lags, the saw-teeth of docs/limitations.md.)
    const StagedTear tear(3, 3, 10, 0);
    SurfaceParams params = plates_params();
    params.close_gaps = 0;  // whose blend would pull the walls together under 0.075 m
    auto frame_at = [&](int n) { return tear.at(n, 0.05 * std::max(0, n - 2)); };
    const ShotFracture fracture = plan_fracture(tear.slab, tear.last, params, frame_at);
    for (int n = 3; n <= tear.last; ++n) {
        const SurfacedFrame s =
            surface_frame(tear.slab.topo, frame_at(n), tear.slab.first_break, params, &fracture);
        ASSERT_EQ(s.fragments, 2) << "frame " << n;
        const double gap = (mean(wall_positions(s, 8)) - mean(wall_positions(s, 0))).x();
        EXPECT_NEAR(gap, 0.05 * (n - 2), tol::kFloat) << "frame " << n;
    }
}

TEST(Plates, WithOpenSpeedZeroAFreshCrackShowsAsOpenAsItsPlatesAtOnce) {
    // the same band, 0.2 m open before it breaks at frame 3: with /surfacing/open_speed 0 the
    // shot's frame 3 shows it 0.2 m open, as the frame on its own does, and its cuts are settled
    const StagedTear tear(3, 3, 20, 0.2);
    SurfaceParams params = plates_params();
    params.open_speed = 0;
    const ShotFracture fracture =
        plan_shot_fracture(tear.slab.topo, tear.last_frame, tear.slab.first_break, params);
    const SurfacedFrame s =
        surface_frame(tear.slab.topo, tear.at(3, 0.2), tear.slab.first_break, params, &fracture);
    ASSERT_EQ(s.fragments, 2);
    EXPECT_NEAR((mean(wall_positions(s, 8)) - mean(wall_positions(s, 0))).x(), 0.2, tol::kFloat);
    EXPECT_EQ(s.edge_settled, s.edge_cut);
}

/// Each vertex's position by (weld key, piece), over both meshes.
std::map<std::pair<uint64_t, int32_t>, Vec3f> keyed_positions(const SurfacedFrame& s) {
    std::map<std::pair<uint64_t, int32_t>, Vec3f> out;
    auto add = [&](const TriMesh& m, const std::vector<uint64_t>& keys) {
        for (size_t f = 0; f < m.faces.size(); ++f)
            for (int32_t v : m.faces[f])
                out.emplace(std::make_pair(keys[v], m.face_fragment[f]), m.positions[v]);
    };
    add(s.boundary, s.boundary_weld_key);
    add(s.crack, s.crack_weld_key);
    return out;
}

TEST(Plates, AWallDoesNotPopWhenACrackIsCutNextToIt) {
    // the upper band breaks at frame 2, the lower at 5, the particles standing still 0.05 m
    // apart: the walls are smoothed over the shot's whole wall graph, so the upper wall does not
    // shift when the lower one joins it; the only moves are the lower band's sides parting at
    // open_speed (0.2 spacings a frame). Without close gaps, whose blend may add up to as much
    // again (docs/physics.md §5.7).
    const StagedTear tear(2, 5, 8, 0.05);
    SurfaceParams params = plates_params();
    params.close_gaps = 0;
    const ShotFracture fracture =
        plan_fracture(tear.slab, tear.last, params, [&](int n) { return tear.at(n, 0.05); });
    const double bound = 0.2 * mean_particle_spacing(tear.slab.topo) + tol::kFloat;
    auto before = keyed_positions(
        surface_frame(tear.slab.topo, tear.at(2, 0.05), tear.slab.first_break, params, &fracture));
    for (int n = 3; n <= tear.last; ++n) {
        auto now = keyed_positions(surface_frame(tear.slab.topo, tear.at(n, 0.05),
                                                 tear.slab.first_break, params, &fracture));
        double largest = 0;
        for (const auto& [key, y] : now) {
            const auto it = before.find(key);
            if (it != before.end()) largest = std::max(largest, double((y - it->second).norm()));
        }
        EXPECT_LE(largest, bound) << "frame " << n;
        before = std::move(now);
    }
}

TEST(WallGraph, SmoothsTheWallsWhereTheyAreAndTheirRimsAlongTheRim) {
    const TornSlab slab;
    const ShotFracture fracture = slab.fracture();
    const WallGraph& graph = fracture.wall_graph;
    ASSERT_FALSE(graph.empty());
    // the cut runs through the slab: its walls reach the surface and have a rim, a curve of its own
    EXPECT_GT(std::count(graph.held.begin(), graph.held.end(), 1), 0);
    ASSERT_GT(graph.rim_nodes.size(), 0u);
    std::vector<uint8_t> along_rim(graph.n_nodes, 0);
    for (size_t i = 0; i < graph.rim_nodes.size(); ++i) {
        const int32_t n = graph.rim_nodes[i];
        along_rim[n] = 1;
        EXPECT_TRUE(graph.held[n] && !graph.hidden[n]);
        for (int32_t m : graph.rim_neighbours[i]) EXPECT_TRUE(graph.held[m] && !graph.hidden[m]);
    }
    // nodes jittered by up to +-0.02 m across the wall: the wall loses most of it; the rim, a few
    // short curves whose held ends keep their jitter and whose long waves a curve keeps, about 2/3
    std::vector<Vec3> position(graph.n_nodes);
    for (int32_t n = 0; n < graph.n_nodes; ++n)
        position[n] = Vec3(0.02 * (double((n * 7919) % 101) / 50 - 1), 0, 0);
    const std::vector<Vec3> jittered = position;
    smooth_wall_nodes(graph, 25, position);
    double wall_before = 0, wall_after = 0, rim_before = 0, rim_after = 0;
    for (int32_t n = 0; n < graph.n_nodes; ++n) {
        if (graph.begin[n] == graph.begin[n + 1]) continue;  // no class of the point
        if (graph.held[n] && !along_rim[n]) {
            EXPECT_EQ(position[n], jittered[n]);
            continue;
        }
        double& before = along_rim[n] ? rim_before : wall_before;
        double& after = along_rim[n] ? rim_after : wall_after;
        before += jittered[n].squaredNorm();
        after += position[n].squaredNorm();
    }
    EXPECT_LT(wall_after, 0.1 * wall_before);
    EXPECT_LT(rim_after, 0.5 * rim_before);
}

TEST(WallGraph, AWallInsideTheSoilIsHiddenAndNotMeshed) {
    // a crack across the plane x = 0.25 m, 0.6 m square, inside a 1 m block: it reaches no
    // surface (find_pieces welds its last few particles to its rim, as a crack tapers)
    const TetMesh mesh = box_lattice(5, 10, 10, kH);
    const CoreTopology topo = build_core_topology(mesh);
    auto on_patch = [&](int32_t p) {
        return std::min(topo.X[p].y(), topo.X[p].z()) > 1.5 * kH &&
               std::max(topo.X[p].y(), topo.X[p].z()) < 8.5 * kH;
    };
    std::vector<int32_t> first_break = no_edge_breaks(topo);
    int32_t deep = -1;
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        const int a = column_of(topo.X[p]), b = column_of(topo.X[q]);
        if (std::min(a, b) != 2 || std::max(a, b) != 3 || !on_patch(p) || !on_patch(q)) continue;
        first_break[e] = 1;
        // at the patch's middle
        if ((topo.X[p] - Vec3(2 * kH, 5 * kH, 5 * kH)).norm() < 1e-9) deep = e;
    }
    ASSERT_GE(deep, 0);
    ParticleFrame frame;
    frame.frame = 1;
    for (const Vec3& X : topo.X) {
        frame.P.push_back(X.cast<float>());
        frame.Fe.push_back(Mat3f::Identity());
    }
    SurfaceParams params = plates_params();
    params.min_piece_size = 0.5;
    const ShotFracture fracture = plan_shot_fracture(topo, frame, first_break, params);
    ASSERT_TRUE(fracture.last.is_cut[deep]);
    const WallGraph& graph = fracture.wall_graph;
    const int32_t deep_point = graph.find(RestPointKind::EdgeMidpoint, deep);
    ASSERT_GE(deep_point, 0);
    EXPECT_TRUE(graph.hidden[graph.points[deep_point].first_node]);
    EXPECT_TRUE(graph.hidden[graph.points[deep_point].first_node + 1]);
    const SurfacedFrame s = surface_frame(topo, frame, first_break, params, &fracture);
    EXPECT_EQ(s.edge_cut[deep], 1);
    EXPECT_TRUE(s.crack.faces.empty());
    EXPECT_FALSE(s.boundary.faces.empty());
}

TEST(Plates, EveryFrameOfAGrowingNetworkIsClosed) {
    // a crack band three columns wide through the top of a block, its edges breaking at random
    // over five frames, and a few edges anywhere: partial walls, grains torn loose and walls inside
    // the soil that the last frame hides, while the plates part
    const TetMesh mesh = box_lattice(14, 6, 8, kH);
    const CoreTopology topo = build_core_topology(mesh);
    std::vector<int32_t> first_break = no_edge_breaks(topo);
    std::mt19937_64 rng(0);  // the engine's sequence is the same on every platform
    auto percent = [&] { return int(rng() % 100); };
    constexpr int kLast = 5;
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        const int a = column_of(topo.X[p]), b = column_of(topo.X[q]);
        const bool band = std::max(a, b) >= 5 && std::min(a, b) <= 8 &&
                          std::min(topo.X[p].y(), topo.X[q].y()) > 1.5 * kH;
        if (percent() < (band ? 80 : 3)) first_break[e] = 1 + percent() % kLast;
    }
    auto at = [&](int n) {  // the right plate moves away 1 cm a frame
        ParticleFrame f;
        f.frame = n;
        for (const Vec3& X : topo.X) {
            f.P.push_back((X + Vec3(column_of(X) > 6 ? 0.01 * n : 0, 0, 0)).cast<float>());
            f.Fe.push_back(Mat3f::Identity());
        }
        return f;
    };
    SurfaceParams params = plates_params();
    params.min_piece_size = 0.5;
    const ShotFracture fracture = plan_shot_fracture(topo, at(kLast), first_break, params);
    int hidden_nodes = 0;
    for (uint8_t h : fracture.wall_graph.hidden) hidden_nodes += h;
    ASSERT_GT(hidden_nodes, 0);
    for (int n = 1; n <= kLast; ++n) {
        const SurfacedFrame s = surface_frame(topo, at(n), first_break, params, &fracture);
        EXPECT_FALSE(s.crack.faces.empty()) << "frame " << n;
        std::set<int32_t> pieces(s.boundary.face_fragment.begin(), s.boundary.face_fragment.end());
        pieces.insert(s.crack.face_fragment.begin(), s.crack.face_fragment.end());
        for (int32_t piece : pieces)
            EXPECT_TRUE(is_closed(s, piece)) << "frame " << n << ", piece " << piece;
    }
}

TEST(WallDeformation, FollowsAnAffineMotionExactlyAndStaysOnItsSideOfEveryCut) {
    const TornSlab slab;
    const ShotFracture fracture = slab.fracture();
    const WallDeformation& d = fracture.wall_motion;
    ASSERT_FALSE(d.empty());
    for (size_t i = 0; i < d.particle.size(); ++i)
        for (int32_t k = d.begin[i]; k < d.begin[i + 1]; ++k)
            EXPECT_EQ(fracture.last.id[d.neighbour[k]], fracture.last.id[d.particle[i]]);
    // rotated about y and stretched: the fitted map is the motion itself
    const Mat3 M =
        Eigen::AngleAxisd(0.3, Vec3::UnitY()).toRotationMatrix() * Vec3(1.1, 0.9, 1.0).asDiagonal();
    const Vec3 shift(0.2, -0.1, 0.05);
    ParticleFrame frame;
    frame.frame = 1;
    for (const Vec3& X : slab.topo.X) frame.P.push_back((M * X + shift).cast<float>());
    // on entry each particle's own motion, as FrameCores passes it: its position, no rotation
    std::vector<Vec3> x;
    for (const Vec3f& P : frame.P) x.push_back(P.cast<double>());
    std::vector<Mat3> A(slab.topo.n_particles, Mat3::Identity());
    smooth_wall_motion(slab.topo, d, frame, 0, x, A);
    int fitted = 0;
    for (size_t i = 0; i < d.particle.size(); ++i) {
        if (d.rest_inverse[i].isZero()) continue;
        ++fitted;
        const int32_t p = d.particle[i];
        EXPECT_LT((x[p] - frame.P[p].cast<double>()).norm(), 1e-5);
        EXPECT_LT((A[p] - M).norm(), 1e-4);
    }
    EXPECT_GT(fitted, 0);
}

TEST(WallDeformation, EasesInFromOwnMotionToTheFitOverTheFramesAfterEachParticlesFirstCut) {
    // the slab's band is cut at frame 1; the fit is a stretch, the particles' own motion the
    // stretch and a shift of a tenth of a spacing, without its linear part
    const TornSlab slab;
    const ShotFracture fracture = slab.fracture();
    const WallDeformation& d = fracture.wall_motion;
    ASSERT_FALSE(d.empty());
    for (int32_t c : d.first_cut) EXPECT_EQ(c, 1);
    const Mat3 M = Vec3(1.1, 0.95, 1.0).asDiagonal();
    const Vec3 own_shift(0.01, 0, 0);
    constexpr int kEase = 4;
    for (int frame_number : {0, 1, 2, 3, 5, 9}) {
        ParticleFrame frame;
        frame.frame = frame_number;
        for (const Vec3& X : slab.topo.X) frame.P.push_back((M * X).cast<float>());
        std::vector<Vec3> x(slab.topo.n_particles), own_x(slab.topo.n_particles);
        for (int32_t p = 0; p < slab.topo.n_particles; ++p)
            own_x[p] = M * slab.topo.X[p] + own_shift;
        x = own_x;
        std::vector<Mat3> A(slab.topo.n_particles, Mat3::Identity());
        smooth_wall_motion(slab.topo, d, frame, kEase, x, A);
        const double w = std::clamp((frame_number - 1) / double(kEase), 0.0, 1.0);
        int fitted = 0;
        for (size_t i = 0; i < d.particle.size(); ++i) {
            if (d.rest_inverse[i].isZero()) continue;
            ++fitted;
            const int32_t p = d.particle[i];
            const Vec3 fit_x = M * slab.topo.X[p];
            EXPECT_LT((x[p] - (w * fit_x + (1 - w) * own_x[p])).norm(), 1e-5)
                << "frame " << frame_number << ", particle " << p;
            EXPECT_LT((A[p] - (w * M + (1 - w) * Mat3::Identity())).norm(), 1e-4)
                << "frame " << frame_number << ", particle " << p;
        }
        EXPECT_GT(fitted, 0);
    }
}

TEST(WallDeformation, CarriesAParticleTornLooseFromItsNeighbourhoodAtMostMaxLead) {
    // every particle follows a stretch, and one wall particle's own motion put it 10 spacings
    // away: the fit pulls it back by max_lead, no more, and its neighbours not at all
    const TornSlab slab;
    const ShotFracture fracture = slab.fracture();
    const WallDeformation& d = fracture.wall_motion;
    EXPECT_NEAR(d.max_lead, 1.5 * mean_particle_spacing(slab.topo), 1e-12);
    EXPECT_NEAR(d.core_reach, 0.5 * mean_particle_spacing(slab.topo), 1e-12);
    const Mat3 M = Vec3(1.1, 0.95, 1.0).asDiagonal();
    ParticleFrame frame;
    frame.frame = 1;
    for (const Vec3& X : slab.topo.X) frame.P.push_back((M * X).cast<float>());
    size_t loose = 0;
    while (loose < d.particle.size() && d.rest_inverse[loose].isZero()) ++loose;
    ASSERT_LT(loose, d.particle.size());
    const int32_t p = d.particle[loose];
    std::vector<Vec3> own_x;
    for (const Vec3f& P : frame.P) own_x.push_back(P.cast<double>());
    own_x[p] += Vec3(10 * kH, 0, 0);
    std::vector<Vec3> x = own_x;
    std::vector<Mat3> A(slab.topo.n_particles, Mat3::Identity());
    smooth_wall_motion(slab.topo, d, frame, 0, x, A);
    const double lead = (x[p] - own_x[p]).norm() + (A[p] - Mat3::Identity()).norm() * d.core_reach;
    EXPECT_NEAR(lead, d.max_lead, 1e-9);
    EXPECT_LT((x[p] - own_x[p]).normalized().x(), -0.999);  // back towards the fit
    for (size_t i = 0; i < d.particle.size(); ++i) {
        const int32_t q = d.particle[i];
        if (q == p || d.rest_inverse[i].isZero()) continue;
        EXPECT_LT((x[q] - M * slab.topo.X[q]).norm(), 1e-5) << "particle " << q;
        EXPECT_LT((A[q] - M).norm(), 1e-4) << "particle " << q;
    }
}

}  // namespace
}  // namespace mudcrack
