// Particle-core surfacing (docs/physics.md §5): topology, welding, closed surfaces, volumes, UVs,
// crack faces, the moisture-aware break criterion and frame-order independence.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <utility>

#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "surfacing/core_rotation.h"
#include "surfacing/core_surface.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/fragments.h"
#include "surfacing/lattice_mesh.h"
#include "surfacing/weld_classes.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// a float normal's length against 1
constexpr float kUnitNormal = 1e-6f;

using test::box_lattice;
using test::LatticeUv;

/// An affine frame x = A X + b with Fe = Fe_value and uniform Jw.
ParticleFrame affine_frame(const TetMesh& mesh, const Mat3& A, const Vec3& b, const Mat3& Fe,
                           float jw, int frame = 1) {
    ParticleFrame f;
    f.frame = frame;
    for (const Vec3& X : mesh.X) {
        f.P.push_back((A * X + b).cast<float>());
        f.Fe.push_back(Fe.cast<float>());
        f.Jw.push_back(jw);
        f.saturation.push_back(0.5f);
        f.alpha.push_back(-0.01f);
    }
    return f;
}

/// Signed volume enclosed by triangles (divergence theorem).
template <class Pos>
double enclosed_volume(const std::vector<Tri>& faces, const Pos& pos) {
    double v = 0;
    for (const Tri& t : faces) v += pos(t[0]).dot(pos(t[1]).cross(pos(t[2]))) / 6;
    return v;
}

/// Every undirected edge is used by exactly two faces, once in each direction.
::testing::AssertionResult is_closed_oriented(const std::vector<std::array<uint64_t, 3>>& faces) {
    std::map<std::pair<uint64_t, uint64_t>, int> directed;
    for (const auto& f : faces)
        for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
    for (const auto& [e, n] : directed) {
        if (n != 1) return ::testing::AssertionFailure() << "directed edge used " << n << " times";
        const auto it = directed.find({e.second, e.first});
        if (it == directed.end())
            return ::testing::AssertionFailure() << "edge without an opposite half-edge";
    }
    return ::testing::AssertionSuccess() << directed.size() / 2 << " edges";
}

std::vector<std::array<uint64_t, 3>> faces_by_key(const TriMesh& mesh,
                                                  const std::vector<uint64_t>& key,
                                                  int fragment = -1) {
    std::vector<std::array<uint64_t, 3>> out;
    for (size_t f = 0; f < mesh.faces.size(); ++f)
        if (fragment < 0 || mesh.face_fragment[f] == fragment)
            out.push_back({key[mesh.faces[f][0]], key[mesh.faces[f][1]], key[mesh.faces[f][2]]});
    return out;
}

std::vector<std::array<uint64_t, 3>> faces_by_index(const TriMesh& mesh) {
    std::vector<std::array<uint64_t, 3>> out;
    for (const Tri& t : mesh.faces) out.push_back({uint64_t(t[0]), uint64_t(t[1]), uint64_t(t[2])});
    return out;
}

double mesh_volume(const TriMesh& mesh) {
    return enclosed_volume(mesh.faces, [&](int v) { return mesh.positions[v].cast<double>(); });
}

double rest_volume(const TetMesh& mesh) {
    double v = 0;
    for (Real pv : particle_rest_volumes(mesh)) v += pv;
    return v;
}

Mat3 rotation(double angle, const Vec3& axis) {
    return Eigen::AngleAxis<Real>(angle, axis.normalized()).toRotationMatrix();
}

void expect_same_mesh(const TriMesh& a, const TriMesh& b) {
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.uvs, b.uvs);
    EXPECT_EQ(a.saturation, b.saturation);
    EXPECT_EQ(a.alpha, b.alpha);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.face_fragment, b.face_fragment);
}

TEST(CoreTopology, LatticeCountsMatchTheKuhnSplit) {
    const int nx = 4, ny = 3, nz = 5;
    const TetMesh mesh = box_lattice(nx, ny, nz, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    const int64_t axis_edges = int64_t(nx) * (ny + 1) * (nz + 1) + int64_t(nx + 1) * ny * (nz + 1) +
                               int64_t(nx + 1) * (ny + 1) * nz;
    const int64_t face_diagonals =
        int64_t(nx) * ny * (nz + 1) + int64_t(nx) * (ny + 1) * nz + int64_t(nx + 1) * ny * nz;
    const int64_t body_diagonals = int64_t(nx) * ny * nz;
    EXPECT_EQ(topo.n_edges(), axis_edges + face_diagonals + body_diagonals);
    EXPECT_EQ(topo.n_tets(), 6 * nx * ny * nz);
    // Euler: V - E + F - T = 1 for a ball
    EXPECT_EQ(int64_t(topo.n_particles) - topo.n_edges() + topo.n_faces - topo.n_tets(), 1);
    EXPECT_EQ(topo.skin_faces.size(), size_t(4 * (nx * ny + ny * nz + nx * nz)));
    EXPECT_EQ(topo.edge_tet.size(), size_t(6 * topo.n_tets()));
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        const auto [p, q] = topo.edges[e];
        EXPECT_LT(p, q);
        EXPECT_NEAR(topo.rest_length[e], (mesh.X[p] - mesh.X[q]).norm(), tol::kRoundoff);
        for (int32_t c = topo.edge_tet_begin[e]; c < topo.edge_tet_begin[e + 1]; ++c)
            EXPECT_EQ(topo.tet_edges[topo.edge_tet[c] / 6][topo.edge_tet[c] % 6], e);
    }
    // continuous UVs: no seams, so one UV vertex per boundary rest point
    EXPECT_EQ(topo.n_skin_out_slots, topo.n_skin_weld_slots);
    EXPECT_GT(topo.memory_bytes(), size_t(0));
}

TEST(CoreTopology, RejectsBadMeshes) {
    TetMesh inverted = box_lattice(2, 2, 2, 0.1);
    std::swap(inverted.tets[3][0], inverted.tets[3][1]);
    EXPECT_THROW(build_core_topology(inverted), InputError);
    TetMesh missing = box_lattice(2, 2, 2, 0.1);
    missing.boundary.pop_back();
    missing.boundary_uv.pop_back();
    EXPECT_THROW(build_core_topology(missing), InputError);
    TetMesh inward = box_lattice(2, 2, 2, 0.1);
    std::swap(inward.boundary[0][1], inward.boundary[0][2]);
    EXPECT_THROW(build_core_topology(inward), InputError);
    TetMesh out_of_range = box_lattice(2, 2, 2, 0.1);
    out_of_range.tets[0][2] = 1000;
    try {
        build_core_topology(out_of_range);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("tet 0 corner 2 = 1000"), std::string::npos)
            << e.what();
    }
}

TEST(WeldClasses, TablesJoinThroughUnbrokenEdges) {
    EXPECT_EQ(tet_weld_reps(0), (WeldReps{0, 0, 0, 0}));
    EXPECT_EQ(tet_weld_reps(63), (WeldReps{0, 1, 2, 3}));
    // only (0,1) broken: 0 and 1 stay welded through 2 and 3 (the crack front closes in the tet)
    EXPECT_EQ(tet_weld_reps(1u << 0), (WeldReps{0, 0, 0, 0}));
    // all edges of corner 3 broken: it separates
    EXPECT_EQ(tet_weld_reps((1u << 2) | (1u << 4) | (1u << 5)), (WeldReps{0, 0, 0, 3}));
    EXPECT_EQ(face_weld_reps(1u << 0)[1], 0);
    EXPECT_EQ(face_weld_reps((1u << 0) | (1u << 2)), (WeldReps{0, 1, 0, 3}));
}

TEST(CoreRotation, RecoversThePolarRotationAndFixesSigns) {
    const Mat3 R0 = rotation(0.7, Vec3(1, 2, 3));
    Mat3 S;
    S << 1.3, 0.1, 0.0, 0.1, 0.8, 0.05, 0.0, 0.05, 1.1;
    const Mat3 R = core_rotation(R0 * S);
    EXPECT_LT((R - R0).norm(), 1e-12) << R;
    // an inverted Fe still gives a proper rotation
    const Mat3 inverted = R0 * Vec3(1.2, 0.9, -0.3).asDiagonal();
    const Mat3 Ri = core_rotation(inverted);
    EXPECT_NEAR(Ri.determinant(), 1.0, tol::kRoundoff);
    EXPECT_LT((Ri.transpose() * Ri - Mat3::Identity()).norm(), 1e-12);
    EXPECT_LT((core_rotation(Mat3::Identity()) - Mat3::Identity()).norm(), tol::kRoundoff);
}

TEST(BreakThreshold, FollowsEq14AndItsVariants) {
    SurfaceParams p;
    p.zeta = 2;
    EXPECT_DOUBLE_EQ(break_threshold(0.5, 0.7, p), 0.5 * (0.5 + 0.7) * 2);
    p.length_consistent = true;
    EXPECT_DOUBLE_EQ(break_threshold(0.5, 0.7, p), 0.5 * (std::cbrt(0.5) + std::cbrt(0.7)) * 2);
    p.mode = SurfaceMode::Wang2019;
    EXPECT_DOUBLE_EQ(break_threshold(0.5, 0.7, p), 2.0);
}

struct IntactCase {
    const char* name;
    Mat3 A;  // x = A X + b
    Mat3 Fe;
    float jw;
    SurfaceMode mode;
};

TEST(SurfaceFrame, IntactBoundaryIsClosedAndEnclosesTheParticleVolume) {
    const TetMesh mesh = box_lattice(5, 3, 4, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    const std::vector<int32_t> never = no_edge_breaks(topo);
    const double v0 = rest_volume(mesh);
    const Mat3 R = rotation(0.4, Vec3(0.3, 1, -0.2));
    const float jw = 0.7f;
    const double s = std::cbrt(double(jw));
    const std::vector<IntactCase> cases = {
        {"identity", Mat3::Identity(), Mat3::Identity(), 1.f, SurfaceMode::Ours},
        {"scaled+rotated (ours)", 1.3 * R, 1.3 * R, 1.f, SurfaceMode::Ours},
        {"scaled+rotated (wang2019)", 1.3 * R, 1.3 * R, 1.f, SurfaceMode::Wang2019},
        {"Jw-shrunk (ours)", s * R, R, jw, SurfaceMode::Ours},
    };
    for (const IntactCase& c : cases) {
        SurfaceParams params;
        params.mode = c.mode;
        const ParticleFrame frame = affine_frame(mesh, c.A, Vec3(0.2, -1, 3), c.Fe, c.jw);
        const SurfacedFrame out = surface_frame(topo, frame, never, params);
        EXPECT_TRUE(is_closed_oriented(faces_by_index(out.boundary))) << c.name;
        EXPECT_EQ(out.boundary.faces.size(), 6 * mesh.boundary.size()) << c.name;
        EXPECT_TRUE(out.crack.faces.empty()) << c.name;
        EXPECT_EQ(out.fragments, 1);
        // the particles' current volume: sum V0 det(F)
        const double expected = v0 * c.A.determinant();
        EXPECT_NEAR(mesh_volume(out.boundary), expected, 0.01 * expected) << c.name;
        EXPECT_NEAR(mesh_volume(out.boundary), expected, 1e-5 * expected)
            << c.name << " (float round-off only)";
        // attributes carried per vertex
        ASSERT_EQ(out.boundary.saturation.size(), out.boundary.positions.size());
        EXPECT_FLOAT_EQ(out.boundary.saturation[0], 0.5f);
        EXPECT_FLOAT_EQ(out.boundary.alpha[0], -0.01f);
        ASSERT_EQ(out.boundary.normals.size(), out.boundary.positions.size());
        EXPECT_NEAR(out.boundary.normals[0].norm(), 1.0f, kUnitNormal);
    }
}

TEST(SurfaceFrame, NormalsPointOutward) {
    const TetMesh mesh =
        box_lattice(3, 3, 3, 0.1, LatticeUv::Continuous, Vec3(-0.15, -0.15, -0.15));
    const CoreTopology topo = build_core_topology(mesh);
    const SurfacedFrame out =
        surface_frame(topo, affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1),
                      no_edge_breaks(topo), SurfaceParams{});
    // the box is centred at the origin: outward normals point away from it
    for (size_t v = 0; v < out.boundary.positions.size(); ++v)
        EXPECT_GT(out.boundary.normals[v].dot(out.boundary.positions[v]), 0.f) << "vertex " << v;
}

TEST(SurfaceFrame, BoundaryUvsMatchTheInitUvsOnAnUndeformedFrame) {
    for (LatticeUv kind : {LatticeUv::Continuous, LatticeUv::Triplanar}) {
        const TetMesh mesh = box_lattice(3, 2, 4, 0.1, kind);
        const CoreTopology topo = build_core_topology(mesh);
        const SurfacedFrame out = surface_frame(
            topo, affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1),
            no_edge_breaks(topo), SurfaceParams{});
        const TriMesh& b = out.boundary;
        ASSERT_EQ(b.faces.size(), 6 * mesh.boundary.size());
        for (size_t f = 0; f < b.faces.size(); ++f) {
            // skin triangle f lies in boundary face f / 6: interpolate that face's UVs at the
            // vertex
            const Tri& bf = mesh.boundary[f / 6];
            const Vec3 a = mesh.X[bf[0]], e1 = mesh.X[bf[1]] - a, e2 = mesh.X[bf[2]] - a;
            Eigen::Matrix<Real, 3, 2> E;
            E << e1, e2;
            for (int c = 0; c < 3; ++c) {
                const int v = b.faces[f][c];
                const Vec2 w = E.colPivHouseholderQr().solve(b.positions[v].cast<Real>() - a);
                const auto& fuv = mesh.boundary_uv[f / 6];
                const Vec2 expected =
                    (1 - w.x() - w.y()) * fuv[0] + w.x() * fuv[1] + w.y() * fuv[2];
                EXPECT_NEAR((b.uvs[v].cast<Real>() - expected).norm(), 0, tol::kFloat)
                    << "face " << f << " corner " << c;
            }
        }
        // seams split vertices but not the surface: closed by weld key
        EXPECT_TRUE(is_closed_oriented(faces_by_key(b, out.boundary_weld_key)));
        if (kind == LatticeUv::Triplanar) {
            EXPECT_GT(topo.n_skin_out_slots, topo.n_skin_weld_slots);
        }
    }
}

/// Random break history: each edge broken with probability `fraction` at frame 1.
std::vector<int32_t> random_breaks(const CoreTopology& topo, double fraction, unsigned seed) {
    std::mt19937 rng(seed);
    std::bernoulli_distribution coin(fraction);
    std::vector<int32_t> fb = no_edge_breaks(topo);
    for (auto& f : fb)
        if (coin(rng)) f = 1;
    return fb;
}

/// A smooth non-affine deformation with per-particle rotations and Jw.
ParticleFrame wavy_frame(const TetMesh& mesh, int frame, double amplitude) {
    ParticleFrame f;
    f.frame = frame;
    for (const Vec3& X : mesh.X) {
        const Vec3 u =
            amplitude * Vec3(std::sin(7 * X.y()), std::sin(5 * X.z() + 1), std::cos(6 * X.x()));
        f.P.push_back((X + u).cast<float>());
        f.Fe.push_back((rotation(amplitude * 3 * X.x(), Vec3(0, 1, 0)) * (1 + amplitude * X.y()))
                           .cast<float>());
        f.Jw.push_back(float(1 - 0.4 * X.x()));
        f.saturation.push_back(float(X.z()));
        f.alpha.push_back(float(-X.y()));
    }
    return f;
}

TEST(SurfaceFrame, EveryFragmentIsClosedAndCracksAppearExactlyAtBrokenInterfaces) {
    const TetMesh mesh = box_lattice(4, 4, 3, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    for (double fraction : {0.05, 0.3, 0.8}) {
        const std::vector<int32_t> fb = random_breaks(topo, fraction, 7);
        const SurfacedFrame out =
            surface_frame(topo, wavy_frame(mesh, 1, 0.02), fb, SurfaceParams{});
        // crack faces: 2 sides x 2 interface triangles per incident tet of each broken edge
        int64_t expected = 0;
        for (int32_t e = 0; e < topo.n_edges(); ++e)
            if (fb[e] <= 1) expected += 4 * (topo.edge_tet_begin[e + 1] - topo.edge_tet_begin[e]);
        EXPECT_EQ(int64_t(out.crack.faces.size()), expected) << fraction;
        EXPECT_EQ(out.broken_edges, count_broken_edges(fb, 1));
        // crack vertices sit on broken interfaces only: every midpoint vertex is of a broken edge
        for (uint64_t key : out.crack_weld_key)
            if ((key >> 62) == uint64_t(RestPointKind::EdgeMidpoint)) {
                const int32_t e = int32_t((key >> 2) & 0xffffffffu);
                EXPECT_LE(fb[e], 1);
            }
        // fragments: boundary + crack pieces of each, stitched by weld key, are closed
        if (fraction > 0.5) {
            EXPECT_GT(out.fragments, 1) << fraction;
        }
        for (int32_t frag = 0; frag < out.fragments; ++frag) {
            auto faces = faces_by_key(out.boundary, out.boundary_weld_key, frag);
            const auto crack = faces_by_key(out.crack, out.crack_weld_key, frag);
            faces.insert(faces.end(), crack.begin(), crack.end());
            ASSERT_TRUE(is_closed_oriented(faces))
                << "fraction " << fraction << " fragment " << frag;
        }
    }
}

TEST(SurfaceFrame, RigidlySeparatedHalvesKeepTheirVolumes) {
    const TetMesh mesh = box_lattice(6, 2, 3, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    // particles right of x = 0.3 move 0.2 m away: the edges across the cut break
    ParticleFrame frame = affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1);
    for (size_t p = 0; p < mesh.X.size(); ++p)
        if (mesh.X[p].x() > 0.3 + 1e-9) frame.P[p].x() += 0.2f;
    std::vector<int32_t> fb = no_edge_breaks(topo);
    SurfaceParams params;
    params.zeta = 1.5;
    record_edge_breaks(topo, frame, params, fb);
    const SurfacedFrame out = surface_frame(topo, frame, fb, params);
    ASSERT_EQ(out.fragments, 2);
    const std::vector<Real> v0 = particle_rest_volumes(mesh);
    for (int32_t frag = 0; frag < 2; ++frag) {
        double expected = 0;
        for (size_t p = 0; p < mesh.X.size(); ++p)
            if ((mesh.X[p].x() > 0.3 + 1e-9) == (frag == 1)) expected += v0[p];
        double volume = 0;
        for (const TriMesh* m : {&out.boundary, &out.crack}) {
            std::vector<Tri> faces;
            for (size_t f = 0; f < m->faces.size(); ++f)
                if (m->face_fragment[f] == frag) faces.push_back(m->faces[f]);
            volume += enclosed_volume(faces, [&](int v) { return m->positions[v].cast<double>(); });
        }
        EXPECT_NEAR(volume, expected, 1e-5 * expected) << "fragment " << frag;
    }
    // the crack opens: its two sides are 0.2 m apart
    float min_x = 1e9f, max_x = -1e9f;
    for (const Vec3f& x : out.crack.positions) {
        min_x = std::min(min_x, x.x());
        max_x = std::max(max_x, x.x());
    }
    EXPECT_GT(max_x - min_x, 0.2f);
}

// Eq. 13, y = x_p + Jw^(1/3) R_p (y0 - X_p): on a uniformly shrunk and rotated block (x = s R X,
// Fe = R, Jw = s^3) every core is the block's own affine image, so a fragment cut off by broken
// edges keeps Jw times its rest volume. Intact meshes cannot tell: there each welded vertex
// averages the cores on both sides and the core scale cancels; the crack faces use one side only.
TEST(SurfaceFrame, CoresOfSeparatedHalvesShrinkByTheCubeRootOfJw) {
    const TetMesh mesh = box_lattice(6, 2, 3, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    const Mat3 R = rotation(0.4, Vec3(0.3, 1, -0.2));
    const float jw = 0.7f;
    const double s = std::cbrt(double(jw));
    ParticleFrame frame = affine_frame(mesh, s * R, Vec3::Zero(), R, jw);
    for (size_t p = 0; p < mesh.X.size(); ++p)
        if (mesh.X[p].x() > 0.3 + 1e-9) frame.P[p].y() += 0.2f;
    std::vector<int32_t> fb = no_edge_breaks(topo);
    SurfaceParams params;
    params.zeta = 1.5;  // Eq. 14: threshold 0.5 (Jw + Jw) zeta = 1.05 > s, only the cut breaks
    record_edge_breaks(topo, frame, params, fb);
    const SurfacedFrame out = surface_frame(topo, frame, fb, params);
    ASSERT_EQ(out.fragments, 2);
    const std::vector<Real> v0 = particle_rest_volumes(mesh);
    for (int32_t frag = 0; frag < 2; ++frag) {
        double expected = 0;
        for (size_t p = 0; p < mesh.X.size(); ++p)
            if ((mesh.X[p].x() > 0.3 + 1e-9) == (frag == 1)) expected += jw * v0[p];
        double volume = 0;
        for (const TriMesh* m : {&out.boundary, &out.crack}) {
            std::vector<Tri> faces;
            for (size_t f = 0; f < m->faces.size(); ++f)
                if (m->face_fragment[f] == frag) faces.push_back(m->faces[f]);
            volume += enclosed_volume(faces, [&](int v) { return m->positions[v].cast<double>(); });
        }
        EXPECT_NEAR(volume, expected, 1e-5 * expected) << "fragment " << frag;
    }
}

TEST(SurfaceFrame, CracksOffBuildsNoCrackFacesButStillSplitsTheBoundary) {
    const TetMesh mesh = box_lattice(4, 3, 3, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    const std::vector<int32_t> fb = random_breaks(topo, 0.3, 3);
    SurfaceParams on, off;
    off.cracks = false;
    const ParticleFrame frame = wavy_frame(mesh, 1, 0.02);
    const SurfacedFrame a = surface_frame(topo, frame, fb, on),
                        b = surface_frame(topo, frame, fb, off);
    EXPECT_TRUE(b.crack.faces.empty());
    EXPECT_TRUE(b.crack.positions.empty());
    expect_same_mesh(a.boundary, b.boundary);
    const SurfacedFrame intact = surface_frame(topo, frame, no_edge_breaks(topo), off);
    EXPECT_GT(b.boundary.positions.size(), intact.boundary.positions.size());
}

TEST(SurfaceFrame, SmallFragmentsAreCulled) {
    const TetMesh mesh = box_lattice(3, 3, 3, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    // isolate corner particle 0 by breaking all its edges
    std::vector<int32_t> fb = no_edge_breaks(topo);
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (topo.edges[e][0] == 0) fb[e] = 1;
    const ParticleFrame frame =
        affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1);
    SurfaceParams keep, cull;
    cull.min_fragment_particles = 2;
    const SurfacedFrame a = surface_frame(topo, frame, fb, keep),
                        b = surface_frame(topo, frame, fb, cull);
    EXPECT_EQ(a.fragments, 2);
    EXPECT_EQ(b.fragments, 1);
    EXPECT_EQ(b.culled_fragments, 1);
    EXPECT_LT(b.boundary.faces.size(), a.boundary.faces.size());
    EXPECT_LT(b.crack.faces.size(), a.crack.faces.size());
    auto faces = faces_by_key(b.boundary, b.boundary_weld_key);
    const auto crack = faces_by_key(b.crack, b.crack_weld_key);
    faces.insert(faces.end(), crack.begin(), crack.end());
    EXPECT_TRUE(is_closed_oriented(faces));
    for (int32_t id : b.boundary.face_fragment) EXPECT_EQ(id, 0);
}

TEST(SurfaceFrame, RejectsFramesOfAnotherMesh) {
    const TetMesh mesh = box_lattice(2, 2, 2, 0.1);
    const CoreTopology topo = build_core_topology(mesh);
    ParticleFrame frame =
        affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1, 12);
    frame.P.pop_back();
    try {
        surface_frame(topo, frame, no_edge_breaks(topo), SurfaceParams{});
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("frame 12: has 26 particles; the tet mesh has 27"),
                  std::string::npos)
            << e.what();
    }
    frame = affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1, 12);
    frame.Jw.resize(5);
    EXPECT_THROW(surface_frame(topo, frame, no_edge_breaks(topo), SurfaceParams{}), InputError);
    // no moisture and no plasticity cached: Jw = 1, R = I
    frame = affine_frame(mesh, Mat3::Identity(), Vec3::Zero(), Mat3::Identity(), 1, 12);
    frame.Jw.clear();
    frame.Fe.clear();
    frame.saturation.clear();
    frame.alpha.clear();
    const SurfacedFrame out = surface_frame(topo, frame, no_edge_breaks(topo), SurfaceParams{});
    EXPECT_TRUE(out.boundary.saturation.empty());
    EXPECT_NEAR(mesh_volume(out.boundary), rest_volume(mesh), 1e-5 * rest_volume(mesh));
}

/// A drying slab: a smooth stretch field along x, and a dry region (x < half) with Jw = 0.6.
ParticleFrame drying_slab_frame(const TetMesh& mesh, double length, double stretch) {
    ParticleFrame f;
    f.frame = 1;
    const double k = 6 * M_PI / length;
    for (const Vec3& X : mesh.X) {
        // u_x = (stretch / k) sin(k X_x): local stretch 1 + stretch cos(k X_x)
        f.P.push_back(Vec3(X.x() + stretch / k * std::sin(k * X.x()), X.y(), X.z()).cast<float>());
        f.Jw.push_back(X.x() < length / 2 ? 0.6f : 1.0f);
    }
    return f;
}

TEST(EdgeBreaks, OursBreaksMoreInTheDryRegionThanWang2019) {
    const int n = 24;
    const double h = 0.05, length = n * h;
    const TetMesh mesh = box_lattice(n, 3, 4, h);
    const CoreTopology topo = build_core_topology(mesh);
    const ParticleFrame frame = drying_slab_frame(mesh, length, 0.8);
    auto count = [&](SurfaceMode mode, bool dry) {
        SurfaceParams p;
        p.mode = mode;
        p.zeta = 1.6;
        std::vector<int32_t> fb = no_edge_breaks(topo);
        record_edge_breaks(topo, frame, p, fb);
        int64_t c = 0;
        for (int32_t e = 0; e < topo.n_edges(); ++e) {
            const auto [a, b] = topo.edges[e];
            const bool both_dry = mesh.X[a].x() < length / 2 && mesh.X[b].x() < length / 2;
            const bool both_wet = mesh.X[a].x() >= length / 2 && mesh.X[b].x() >= length / 2;
            if ((dry ? both_dry : both_wet) && fb[e] <= 1) ++c;
        }
        return c;
    };
    const int64_t ours_dry = count(SurfaceMode::Ours, true),
                  wang_dry = count(SurfaceMode::Wang2019, true);
    const int64_t ours_wet = count(SurfaceMode::Ours, false),
                  wang_wet = count(SurfaceMode::Wang2019, false);
    EXPECT_GT(wang_dry, 0);             // the stretch alone breaks some edges
    EXPECT_GT(ours_dry, 2 * wang_dry);  // Eq. 14 lowers the threshold where Jw < 1
    EXPECT_EQ(ours_wet, wang_wet);      // and changes nothing where Jw = 1
    EXPECT_GT(ours_dry, ours_wet);
}

/// Frames 1..4 of a slab that stretches more and more, then relaxes (breaks stay broken).
std::vector<ParticleFrame> stretching_sequence(const TetMesh& mesh) {
    std::vector<ParticleFrame> frames;
    const double amplitudes[] = {0.1, 0.5, 0.9, 0.2};
    for (int i = 0; i < 4; ++i) {
        ParticleFrame f = drying_slab_frame(mesh, 16 * 0.05, amplitudes[i]);
        f.frame = i + 1;
        const ParticleFrame w = wavy_frame(mesh, i + 1, 0.01 * (i + 1));
        f.Fe = w.Fe;
        f.saturation = w.saturation;
        f.alpha = w.alpha;
        frames.push_back(f);
    }
    return frames;
}

TEST(FrameOrder, BreakHistoryAndMeshesDoNotDependOnOrderOrThreads) {
    const TetMesh mesh = box_lattice(16, 3, 3, 0.05);
    const CoreTopology topo = build_core_topology(mesh);
    const std::vector<ParticleFrame> frames = stretching_sequence(mesh);
    SurfaceParams params;
    params.zeta = 1.6;
    // history in order, in reverse, and per frame merged
    std::vector<int32_t> forward = no_edge_breaks(topo), reverse = no_edge_breaks(topo),
                         merged = no_edge_breaks(topo);
    for (const auto& f : frames) record_edge_breaks(topo, f, params, forward);
    for (auto it = frames.rbegin(); it != frames.rend(); ++it)
        record_edge_breaks(topo, *it, params, reverse);
    for (const auto& f : frames) {
        std::vector<int32_t> one = no_edge_breaks(topo);
        record_edge_breaks(topo, f, params, one);
        merge_edge_breaks(merged, one);
    }
    EXPECT_EQ(forward, reverse);
    EXPECT_EQ(forward, merged);
    // breaks are permanent: frame 4 relaxes but keeps frame 3's cracks
    EXPECT_GT(count_broken_edges(forward, 3), count_broken_edges(forward, 1));
    EXPECT_EQ(count_broken_edges(forward, 4), count_broken_edges(forward, 3));

    std::vector<SurfacedFrame> in_order;
    for (const auto& f : frames) in_order.push_back(surface_frame(topo, f, forward, params));
    EXPECT_GT(in_order[3].crack.faces.size(), 0u);
    std::vector<SurfacedFrame> reversed(frames.size());
    for (int i = int(frames.size()) - 1; i >= 0; --i)
        reversed[i] = surface_frame(topo, frames[i], reverse, params);
    // frames in parallel (each frame single-threaded inside), and one frame on 1 thread
    std::vector<SurfacedFrame> parallel(frames.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(2)
    for (int i = 0; i < int(frames.size()); ++i)
        parallel[i] = surface_frame(topo, frames[i], merged, params);
    const int threads = thread_count();
    set_thread_count(1);
    const SurfacedFrame serial = surface_frame(topo, frames[2], forward, params);
    set_thread_count(threads);
    for (size_t i = 0; i < frames.size(); ++i) {
        for (const auto* other : {&reversed[i], &parallel[i]}) {
            expect_same_mesh(in_order[i].boundary, other->boundary);
            expect_same_mesh(in_order[i].crack, other->crack);
            EXPECT_EQ(in_order[i].crack_weld_key, other->crack_weld_key);
        }
    }
    expect_same_mesh(in_order[2].boundary, serial.boundary);
    expect_same_mesh(in_order[2].crack, serial.crack);
}

}  // namespace
}  // namespace mudcrack
