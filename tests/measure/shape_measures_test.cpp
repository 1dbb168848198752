// The shape measures on layers moved by hand, where the answer is known exactly.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "pipeline/measure/shape_measures.h"
#include "sim/core/error.h"
#include "surfacing/core_topology.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/lattice_mesh.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

constexpr double kSpacing = 0.02;
constexpr int kN = 10;  // columns per side
constexpr int kLayers = 6;

/// A kN x kLayers x kN lattice with particles at cell centres; index (i, j, k) -> (k kLayers + j)
/// kN + i.
std::vector<Vec3> lattice() {
    std::vector<Vec3> x;
    for (int k = 0; k < kN; ++k)
        for (int j = 0; j < kLayers; ++j)
            for (int i = 0; i < kN; ++i) x.push_back(kSpacing * Vec3(i + 0.5, j + 0.5, k + 0.5));
    return x;
}
int index(int i, int j, int k) { return (k * kLayers + j) * kN + i; }
bool on_rim(int i, int k) { return i == 0 || k == 0 || i == kN - 1 || k == kN - 1; }

TEST(RestColumns, GroupsALatticeIntoStacksBottomToTop) {
    const std::vector<Vec3> rest = lattice();
    const RestColumns columns = build_rest_columns(rest, kSpacing);
    ASSERT_EQ(columns.n_columns(), kN * kN);
    for (int c = 0; c < columns.n_columns(); ++c) {
        ASSERT_EQ(columns.begin[c + 1] - columns.begin[c], kLayers);
        for (int k = columns.begin[c] + 1; k < columns.begin[c + 1]; ++k) {
            const Vec3& lo = rest[columns.particle[k - 1]];
            const Vec3& hi = rest[columns.particle[k]];
            EXPECT_NEAR(hi.y() - lo.y(), kSpacing, tol::kRoundoff);
            EXPECT_EQ(lo.x(), hi.x());
            EXPECT_EQ(lo.z(), hi.z());
        }
    }
}

TEST(RestColumns, RejectsANonPositiveWidth) {
    EXPECT_THROW(build_rest_columns(lattice(), 0), InputError);
    EXPECT_THROW(build_rest_columns(lattice(), -kSpacing), InputError);
}

TEST(ParticleSpacing, IsTheCubeRootOfTheMeanVolume) {
    EXPECT_NEAR(particle_spacing(std::vector<Real>(100, 8e-6)), 0.02, tol::kRoundoff);
    EXPECT_NEAR(particle_spacing({1e-6, 15e-6}), 0.02, tol::kRoundoff);
    EXPECT_EQ(particle_spacing({}), 0);
}

TEST(LayerShape, UnmovedLayerHasNoCurlSplitOrLift) {
    const std::vector<Vec3> rest = lattice();
    const LayerShape s =
        measure_layer_shape(build_rest_columns(rest, kSpacing), rest, rest, kSpacing);
    EXPECT_EQ(s.columns, kN * kN);
    EXPECT_EQ(s.curl, 0);
    EXPECT_EQ(s.top_rise_median, 0);
    EXPECT_EQ(s.split_fraction, 0);
    EXPECT_EQ(s.lifted_fraction, 0);
}

TEST(LayerShape, UniformShrinkageIsNotCurl) {
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    for (Vec3& p : x) p = Vec3(0.7 * p.x(), 0.6 * p.y(), 0.7 * p.z());  // dried: shrunk, flat
    const LayerShape s = measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    const double top = kSpacing * (kLayers - 0.5);
    EXPECT_NEAR(s.top_rise_median, -0.4 * top, tol::kRoundoff);
    EXPECT_NEAR(s.curl, 0, tol::kRoundoff);
    EXPECT_EQ(s.split_fraction, 0);
    EXPECT_EQ(s.lifted_fraction, 0);
}

TEST(LayerShape, CurlIsTheRiseOfTheRimOverTheTypicalSurface) {
    // the rim ring (36 of 100 columns) bends up: the top particle rises by d, the one below by d/2
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    const double d = 0.013;
    for (int k = 0; k < kN; ++k)
        for (int i = 0; i < kN; ++i)
            if (on_rim(i, k)) {
                x[index(i, kLayers - 1, k)].y() += d;
                x[index(i, kLayers - 2, k)].y() += d / 2;
            }
    const LayerShape s = measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    EXPECT_NEAR(s.curl, d, tol::kRoundoff);
    EXPECT_NEAR(s.top_rise_p95, d, tol::kRoundoff);
    EXPECT_EQ(s.top_rise_median, 0);
    EXPECT_EQ(s.split_fraction, 0);  // bent, not split: neighbours opened by d/2 < one spacing
}

TEST(LayerShape, AGapInsideAColumnIsAHorizontalSplit) {
    // a crust of two layers peels up by 1.5 spacings in 30 columns
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    int peeled = 0;
    for (int k = 0; k < kN && peeled < 30; ++k)
        for (int i = 0; i < kN && peeled < 30; ++i, ++peeled)
            for (int j = kLayers - 2; j < kLayers; ++j) x[index(i, j, k)].y() += 1.5 * kSpacing;
    const LayerShape s = measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    EXPECT_NEAR(s.split_fraction, 0.30, tol::kRoundoff);
    EXPECT_EQ(s.lifted_fraction, 0);
}

TEST(LayerShape, SidewaysCracksAreNotHorizontalSplits) {
    // vertical cracks: half of the layer moves 3 spacings sideways and every column tilts a little
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    for (int k = 0; k < kN; ++k)
        for (int j = 0; j < kLayers; ++j)
            for (int i = 0; i < kN; ++i) {
                Vec3& p = x[index(i, j, k)];
                if (i >= kN / 2) p.x() += 3 * kSpacing;
                p.z() += 0.3 * kSpacing * j;
            }
    const LayerShape s = measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    EXPECT_EQ(s.split_fraction, 0);
    EXPECT_EQ(s.lifted_fraction, 0);
    EXPECT_EQ(s.curl, 0);
}

TEST(LayerShape, AColumnOffTheGroundIsLiftedNotSplit) {
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    for (int k = 0; k < kN; ++k)
        for (int i = 0; i < kN; ++i)
            if (on_rim(i, k))
                for (int j = 0; j < kLayers; ++j) x[index(i, j, k)].y() += 2 * kSpacing;
    const LayerShape s = measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    EXPECT_NEAR(s.lifted_fraction, 0.36, tol::kRoundoff);
    EXPECT_EQ(s.split_fraction, 0);
}

TEST(LayerShape, AGapInTheGroundBandIsLiftOffAGapAboveIsASplitAtItsHeight) {
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x = rest;
    // half the columns open a gap above their bottom particle (inside a 1.5-spacing band over the
    // ground at y = 0), the other half above their fourth particle (3.5 spacings up)
    for (int k = 0; k < kN; ++k)
        for (int i = 0; i < kN; ++i) {
            const int first_lifted = k < kN / 2 ? 1 : 4;
            for (int j = first_lifted; j < kLayers; ++j) x[index(i, j, k)].y() += 2 * kSpacing;
        }
    GroundBand ground;
    ground.ground_y = 0;
    ground.band = 1.5 * kSpacing;
    ground.cell = 2 * kSpacing;  // heights reported in cells of twice the spacing
    const LayerShape s =
        measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing, ground);
    EXPECT_NEAR(s.lifted_fraction, 0.5, tol::kRoundoff);
    EXPECT_NEAR(s.split_fraction, 0.5, tol::kRoundoff);
    // the split's lower particle sits at 3.5 spacings = 1.75 cells
    EXPECT_NEAR(s.split_height_median, 1.75, tol::kRoundoff);
    EXPECT_NEAR(s.split_height_p10, 1.75, tol::kRoundoff);
    // without a ground band every gap is a split
    const LayerShape no_band =
        measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing);
    EXPECT_NEAR(no_band.split_fraction, 1.0, tol::kRoundoff);
    EXPECT_EQ(no_band.lifted_fraction, 0);
}

TEST(HardeningHalves, CountsSurfaceParticlesOnEachSideOfAlpha0) {
    const std::vector<float> alpha = {-0.5f, -0.1f, -0.1f, 0.2f, 0.0f, 3.0f};
    const HardeningHalves h = measure_hardening_halves({0, 2, 3, 4, 5}, alpha, -0.1);
    EXPECT_EQ(h.surface_particles, 5);
    EXPECT_NEAR(h.compressed_fraction, 1.0 / 5, tol::kRoundoff);
    EXPECT_NEAR(h.stretched_fraction, 3.0 / 5, tol::kRoundoff);
    EXPECT_THROW(measure_hardening_halves({6}, alpha, 0), InputError);
}

TEST(LayerShape, RejectsMismatchedSizes) {
    const std::vector<Vec3> rest = lattice();
    std::vector<Vec3> x(rest.begin(), rest.end() - 1);
    EXPECT_THROW(measure_layer_shape(build_rest_columns(rest, kSpacing), rest, x, kSpacing),
                 InputError);
}

TEST(FragmentSizes, WeightsFragmentsByVolumeAndSkipsCulledParticles) {
    Fragments f;
    f.id = {0, 0, 1, 2, 2, -1};
    f.count = 3;
    const std::vector<Real> volume = {0.5, 0.5, 1.0, 1.5, 0.5, 7.0};
    const FragmentSizes s = measure_fragment_sizes(f, volume);
    EXPECT_EQ(s.count, 3);
    EXPECT_NEAR(s.total_volume, 4.0, tol::kRoundoff);
    EXPECT_NEAR(s.largest_fraction, 0.5, tol::kRoundoff);
    EXPECT_NEAR(s.weighted_mean_volume, (1.0 + 1.0 + 4.0) / 4.0, tol::kRoundoff);
    f.id.pop_back();
    EXPECT_THROW(measure_fragment_sizes(f, volume), InputError);
}

// Surface polygons on a 8 x 4 x 6 cell tet lattice (9 x 5 x 7 particles, spacing 0.1 m, column
// centres off the bin edges), cut by a vertical plane between particle columns 3 and 4.
class SurfacePolygonsTest : public ::testing::Test {
protected:
    static constexpr double kH = 0.1;
    SurfacePolygonsTest()
        : m_mesh(
              test::box_lattice(8, 4, 6, kH, test::LatticeUv::None, Vec3(0.5 * kH, 0, 0.5 * kH))),
          m_topo(build_core_topology(m_mesh)),
          m_columns(build_rest_columns(m_mesh.X, kH)) {}

    /// Edges crossing x = cut, broken when both ends lie below `below_y` [m].
    std::vector<uint8_t> cut(double below_y) const {
        const double x = 0.5 * kH + 3.5 * kH;
        std::vector<uint8_t> broken(m_topo.n_edges(), 0);
        for (int32_t e = 0; e < m_topo.n_edges(); ++e) {
            const Vec3& p = m_topo.X[m_topo.edges[e][0]];
            const Vec3& q = m_topo.X[m_topo.edges[e][1]];
            if ((p.x() - x) * (q.x() - x) < 0 && p.y() < below_y && q.y() < below_y) broken[e] = 1;
        }
        return broken;
    }
    double footprint() const { return m_columns.n_columns() * kH * kH; }

    TetMesh m_mesh;
    CoreTopology m_topo;
    RestColumns m_columns;
};

TEST_F(SurfacePolygonsTest, AnIntactTopIsOnePolygonOfTheWholeFootprint) {
    ASSERT_EQ(m_columns.n_columns(), 9 * 7);
    const SurfacePolygons s =
        measure_surface_polygons(m_topo, std::vector<uint8_t>(m_topo.n_edges(), 0), m_columns, 1);
    EXPECT_EQ(s.count, 1);
    EXPECT_NEAR(s.largest_fraction, 1, tol::kRoundoff);
    EXPECT_NEAR(s.weighted_mean_area, footprint(), tol::kRoundoff);
    EXPECT_NEAR(s.effective_count, 1, tol::kRoundoff);
}

TEST_F(SurfacePolygonsTest, AThroughCrackCutsTheTopIntoTwoPolygonsOfTheirColumnShares) {
    const SurfacePolygons s = measure_surface_polygons(m_topo, cut(1e9), m_columns, 1);
    EXPECT_EQ(s.count, 2);
    // 4 and 5 of the 9 particle columns on either side
    EXPECT_NEAR(s.largest_fraction, 5.0 / 9.0, tol::kRoundoff);
    EXPECT_NEAR(s.weighted_mean_area, footprint() * (16.0 + 25.0) / 81.0, tol::kRoundoff);
    EXPECT_NEAR(s.effective_count, 81.0 / 41.0, tol::kRoundoff);  // (4 + 5)^2 / (4^2 + 5^2)
}

// a chip of two columns cut off a corner counts as a polygon, but barely as a plate: the
// effective count is (61 + 2)^2 / (61^2 + 2^2) of the 63 columns
TEST_F(SurfacePolygonsTest, AChipCountsAsAPolygonButHardlyAsAPlate) {
    std::vector<uint8_t> broken(m_topo.n_edges(), 0);
    // around columns (0, 0) and (0, 1)
    const double x = 0.5 * kH + 0.5 * kH, z = 0.5 * kH + 1.5 * kH;
    const auto in_chip = [&](const Vec3& p) { return p.x() < x && p.z() < z; };
    for (int32_t e = 0; e < m_topo.n_edges(); ++e)
        if (in_chip(m_topo.X[m_topo.edges[e][0]]) != in_chip(m_topo.X[m_topo.edges[e][1]]))
            broken[e] = 1;
    const SurfacePolygons s = measure_surface_polygons(m_topo, broken, m_columns, 1);
    EXPECT_EQ(s.count, 2);
    EXPECT_NEAR(s.largest_fraction, 61.0 / 63.0, tol::kRoundoff);
    EXPECT_NEAR(s.effective_count, 63.0 * 63.0 / (61.0 * 61.0 + 4.0), tol::kRoundoff);
}

TEST_F(SurfacePolygonsTest, ACrackThatStopsBelowTheTopLayerDoesNotCutTheSurface) {
    const SurfacePolygons s = measure_surface_polygons(m_topo, cut(0.15), m_columns, 1);
    EXPECT_EQ(s.count, 1);
    EXPECT_NEAR(s.weighted_mean_area, footprint(), tol::kRoundoff);
}

// The plates mode's walls over the top, against the breaks under them: a wall whose top edges
// broke is open; one cut where only the soil below broke holds, and a uniformly dried top over it
// sits at its dried rest length (Jw^(1/3) of the rest), so its strain is 0, not Jw^(1/3) - 1.
TEST_F(SurfacePolygonsTest,
       UnopenedWallsAreCutTopEdgesThatNeverBrokeAndTheirStrainOverTheDriedRest) {
    const std::vector<uint8_t> wall = cut(1e9);
    const float jw = 0.512f;  // Jw^(1/3) = 0.8
    std::vector<Vec3> dried(m_topo.X.begin(), m_topo.X.end());
    for (Vec3& p : dried) p *= std::cbrt(Real(jw));
    const std::vector<float> Jw(dried.size(), jw);

    const UnopenedWalls open = measure_unopened_walls(m_topo, wall, wall, m_columns, dried, Jw);
    EXPECT_GT(open.wall_edges, 0);
    EXPECT_EQ(open.unopened_edges, 0);
    EXPECT_EQ(open.unopened_fraction, 0);

    // broken only below the top layer (its two particle rows are y = 0.3 and 0.4)
    const std::vector<uint8_t> below = cut(0.25);
    const UnopenedWalls held = measure_unopened_walls(m_topo, below, wall, m_columns, dried, Jw);
    EXPECT_EQ(held.wall_edges, open.wall_edges);
    EXPECT_EQ(held.unopened_edges, held.wall_edges);
    EXPECT_EQ(held.unopened_fraction, 1);
    EXPECT_NEAR(held.unopened_strain_median, 0, tol::kRoundoff);

    // the side beyond the cut moved away by 0.01 m: an edge along x, 0.08 m dried, opens by
    // 0.01 / 0.08; an edge across at an angle opens by less than that share of its length
    std::vector<Vec3> parted = dried;
    for (Vec3& p : parted)
        if (p.x() > 0.8 * 4 * kH) p.x() += 0.01;
    const UnopenedWalls opening =
        measure_unopened_walls(m_topo, below, wall, m_columns, parted, Jw);
    EXPECT_GT(opening.unopened_strain_median, 0.01);
    EXPECT_LE(opening.unopened_strain_median, 0.125 + tol::kRoundoff);

    EXPECT_THROW(measure_unopened_walls(m_topo, below, wall, m_columns, dried, {jw}), InputError);
    EXPECT_THROW(
        measure_unopened_walls(m_topo, below, std::vector<uint8_t>(3, 0), m_columns, dried, Jw),
        InputError);
}

TEST_F(SurfacePolygonsTest, RejectsMismatchedSizes) {
    EXPECT_THROW(measure_surface_polygons(m_topo, std::vector<uint8_t>(3, 0), m_columns, 1),
                 InputError);
    EXPECT_THROW(measure_crack_depth(m_topo, std::vector<uint8_t>(3, 0), m_columns), InputError);
}

TEST_F(SurfacePolygonsTest, CrackDepthIsHowFarTheCutReachesBelowTheTop) {
    const CrackDepth none =
        measure_crack_depth(m_topo, std::vector<uint8_t>(m_topo.n_edges(), 0), m_columns);
    EXPECT_EQ(none.cracked_columns, 0);
    EXPECT_EQ(none.depth_max, 0);
    // a cut through the whole layer (0.4 m thick): the columns beside it are cracked top to bottom
    const CrackDepth through = measure_crack_depth(m_topo, cut(1e9), m_columns);
    EXPECT_EQ(through.cracked_columns, 2 * 7);  // particle columns 3 and 4, 7 rows in z
    EXPECT_NEAR(through.cracked_fraction, 14.0 / 63.0, tol::kRoundoff);
    EXPECT_NEAR(through.depth_median, 4 * kH, tol::kRoundoff);
    EXPECT_NEAR(through.thickness_median, 4 * kH, tol::kRoundoff);
    EXPECT_NEAR(through.through_fraction, 1, tol::kRoundoff);
    // a cut from the top down to y = 0.15 (edges with both ends above it): particles at y = 0.4,
    // 0.3, 0.2 are cracked, so it reaches 0.2 m below the top
    std::vector<uint8_t> top_cut = cut(1e9), below = cut(0.15);
    for (size_t e = 0; e < top_cut.size(); ++e) {
        const Vec3& p = m_topo.X[m_topo.edges[e][0]];
        const Vec3& q = m_topo.X[m_topo.edges[e][1]];
        top_cut[e] = top_cut[e] && p.y() > 0.15 && q.y() > 0.15;
    }
    const CrackDepth partial = measure_crack_depth(m_topo, top_cut, m_columns);
    EXPECT_EQ(partial.cracked_columns, 14);
    EXPECT_NEAR(partial.depth_max, 2 * kH, tol::kRoundoff);
    EXPECT_NEAR(partial.depth_p90, 2 * kH, tol::kRoundoff);
    EXPECT_EQ(partial.through_fraction, 0);
    // a crack below the top that does not open it has no depth from the top
    EXPECT_EQ(measure_crack_depth(m_topo, below, m_columns).cracked_columns, 0);
}

// The crack network of a 30 x 2 x 30 cell tet lattice cut by vertical planes through chosen
// lines of the x-z plane (segments from a to b): the answer is known from the lines drawn.
class CrackNetworkTest : public ::testing::Test {
protected:
    static constexpr double kH = 0.1;
    CrackNetworkTest()
        : m_mesh(
              test::box_lattice(30, 2, 30, kH, test::LatticeUv::None, Vec3(0.5 * kH, 0, 0.5 * kH))),
          m_topo(build_core_topology(m_mesh)),
          m_columns(build_rest_columns(m_mesh.X, kH)) {}

    /// Breaks the edges that cross the segment a-b (x-z) into `broken`.
    void cut(Vec2 a, Vec2 b, std::vector<uint8_t>& broken) const {
        auto side = [](const Vec2& o, const Vec2& d, const Vec2& p) {
            return d.x() * (p.y() - o.y()) - d.y() * (p.x() - o.x());
        };
        for (int32_t e = 0; e < m_topo.n_edges(); ++e) {
            const Vec3& p3 = m_topo.X[m_topo.edges[e][0]];
            const Vec3& q3 = m_topo.X[m_topo.edges[e][1]];
            const Vec2 p(p3.x(), p3.z()), q(q3.x(), q3.z());
            if (side(a, b - a, p) * side(a, b - a, q) < 0 &&
                side(p, q - p, a) * side(p, q - p, b) < 0)
                broken[e] = 1;
        }
    }
    std::vector<uint8_t> none() const { return std::vector<uint8_t>(m_topo.n_edges(), 0); }
    /// Two cracks along x and two along z, cutting the 3 m square into 3 x 3 plates.
    std::vector<uint8_t> three_by_three() const {
        std::vector<uint8_t> broken = none();
        for (double at : {1.03, 2.03}) {
            cut(Vec2(at, -1), Vec2(at, 4), broken);
            cut(Vec2(-1, at), Vec2(4, at), broken);
        }
        return broken;
    }

    TetMesh m_mesh;
    CoreTopology m_topo;
    RestColumns m_columns;
};

TEST_F(CrackNetworkTest, CracksAlongTheGridAreAxisAlignedOnesAcrossItAreNot) {
    std::vector<uint8_t> along = none(), across = none();
    cut(Vec2(1.53, -1), Vec2(1.53, 4), along);  // x = const
    // 30 degrees, ending inside
    cut(Vec2(0.2, 0.1), Vec2(2.8, 0.1 + 2.6 * std::tan(0.52)), across);
    const CrackNetwork a = measure_crack_network(m_topo, along, m_columns, 1);
    const CrackNetwork b = measure_crack_network(m_topo, across, m_columns, 1);
    ASSERT_GT(a.crack_points, 20);
    ASSERT_GT(b.crack_points, 20);
    EXPECT_GT(a.axis_aligned_fraction, 0.95);
    EXPECT_LT(b.axis_aligned_fraction, 0.1);
    EXPECT_EQ(a.junctions, 0);
    // the direction histogram holds all the oriented length, in the bin of the line's direction:
    // x = const runs along z (90 degrees, bin 6), the other at 30 degrees (bin 2)
    const auto sum = [](const auto& h) { return std::accumulate(h.begin(), h.end(), 0.0); };
    EXPECT_NEAR(sum(a.direction_histogram), a.oriented_length, tol::kRoundoff);
    EXPECT_NEAR(sum(b.direction_histogram), b.oriented_length, tol::kRoundoff);
    EXPECT_GT(a.direction_histogram[6], 0.95 * a.oriented_length);
    EXPECT_GT(b.direction_histogram[2], 0.9 * b.oriented_length);
}

// A fan of straight cracks 1.6 m long through the square's centre, one a degree from 0 to 179,
// inside its inland part (six column widths from the edge): a network with no preferred
// direction, whose cracks are measured one at a time.
// - Every crack reads the same length. The Kuhn lattice's tets put 1.8 times as many broken edges
//   on a crack square to their face diagonals as on one along them (135 against 75 points here),
//   so a count of points would not (that is what the histogram held until 2026-11-30).
// - The fan's share on the axes is what an isotropic network reads at this resolution: 62 of
//   its 180 directions lie within 15 degrees of an axis (34.4 %), and the measure reads 30 %: on
//   a lattice a crack is a staircase of rows, whose steps tilt the local direction (four column
//   widths around a point) by up to 14 degrees, so a crack 4 to 6 degrees off an axis reads 66-81
//   % aligned and one 13 to 15 off 41 %, while one 16 to 18 off reads 11 %.
TEST_F(CrackNetworkTest, AFanOfCracksInEveryDirectionReadsOneLengthAndNoPreferredDirection) {
    constexpr double kPi = 3.14159265358979323846, kHalfLength = 0.8;
    std::vector<double> length;
    double aligned = 0, total = 0, cos4 = 0, sin4 = 0;
    for (int degrees = 0; degrees < 180; ++degrees) {
        const double t = degrees * kPi / 180;
        const Vec2 centre(1.5, 1.5), d(std::cos(t), std::sin(t));
        std::vector<uint8_t> broken = none();
        cut(centre - kHalfLength * d, centre + kHalfLength * d, broken);
        const CrackNetwork n = measure_crack_network(m_topo, broken, m_columns, 1);
        ASSERT_GT(n.oriented_points, 20) << degrees << " degrees";
        // a crack along an axis reads aligned, one 20 degrees or more off it does not; in
        // between, a staircase's steps tilt the local direction by up to 14 degrees
        const int off_axis = std::min(degrees % 90, 90 - degrees % 90);
        if (off_axis <= 3) {
            EXPECT_GT(n.axis_aligned_fraction, 0.95) << degrees << " degrees";
        }
        if (off_axis >= 20) {
            EXPECT_LT(n.axis_aligned_fraction, 0.05) << degrees << " degrees";
        }
        // one crack: one direction, order near 1 (its staircase's steps spread it)
        EXPECT_GT(n.square_order, 0.85) << degrees << " degrees";
        const double four_phase = 4 * n.square_phase_deg * kPi / 180;
        cos4 += n.oriented_length * n.square_order * std::cos(four_phase);
        sin4 += n.oriented_length * n.square_order * std::sin(four_phase);
        length.push_back(n.oriented_length);
        aligned += n.axis_aligned_fraction * n.oriented_length;
        total += n.oriented_length;
    }
    // each crack's length within 10 % of the fan's mean (by points: 0.72 to 1.3 of it); the
    // crack's ends, where a disc holds half a crack, read 1.4 times theirs, so all read 1.2 times
    // 1.6 m
    const double mean = total / 180;
    EXPECT_NEAR(mean / (2 * kHalfLength), 1.2, 0.1);
    for (int degrees = 0; degrees < 180; ++degrees)
        EXPECT_NEAR(length[degrees] / mean, 1, 0.1) << degrees << " degrees";
    EXPECT_NEAR(aligned / total, 0.30, 0.02);
    // the whole fan prefers no pair of perpendicular directions: the cracks' right-angle orders
    // added as vectors at four times their phases cancel
    EXPECT_LT(std::hypot(cos4, sin4) / total, 0.02);
}

// Cracks that meet at right angles have right-angle order, whatever way they run: a pair along
// the axes and a pair turned 30 degrees read order near 1, and the phase says which way the pair
// runs. The axis share tells the two apart only by its phase: 100 % and 0 %.
TEST_F(CrackNetworkTest, TheRightAngleOrderAndPhaseFindThePairOfDirectionsCracksFollow) {
    constexpr double kPi = 3.14159265358979323846;
    const CrackNetwork along = measure_crack_network(m_topo, three_by_three(), m_columns, 1);
    EXPECT_GT(along.square_order, 0.9);
    EXPECT_NEAR(along.square_phase_deg, 0, 2);
    EXPECT_GT(along.axis_aligned_fraction, 0.95);
    std::vector<uint8_t> turned = none();
    const Vec2 centre(1.5, 1.5);
    for (double degrees : {30.0, 120.0}) {
        const Vec2 d(std::cos(degrees * kPi / 180), std::sin(degrees * kPi / 180));
        cut(centre - 3 * d, centre + 3 * d, turned);
    }
    const CrackNetwork pair = measure_crack_network(m_topo, turned, m_columns, 1);
    EXPECT_GT(pair.square_order, 0.9);
    EXPECT_NEAR(pair.square_phase_deg, 30, 3);
    EXPECT_LT(pair.axis_aligned_fraction, 0.05);
}

// The axis share's standard error is over cracks, not points: a crack's points all share its
// direction, so one crack is one draw however long it is. One crack: no spread. Two through
// cracks that cross, one along z and one at 30 degrees, part four polygons along four cracks,
// two aligned and two not: an error near that of a 4-sample share (sqrt(p (1 - p) / 4), 0.25 at
// p = 1/2), many times what the same share over its hundreds of points would claim.
TEST_F(CrackNetworkTest, TheAxisShareIsASampleOfCracksWhoseErrorTheCrackCountSets) {
    std::vector<uint8_t> one = none(), crossed = none();
    cut(Vec2(1.53, -1), Vec2(1.53, 4), one);
    cut(Vec2(1.53, -1), Vec2(1.53, 4), crossed);
    cut(Vec2(-1, 0.5), Vec2(4, 0.5 + 5 * std::tan(0.5236)), crossed);
    const CrackNetwork a = measure_crack_network(m_topo, one, m_columns, 1);
    EXPECT_EQ(a.oriented_cracks, 1);
    EXPECT_EQ(a.axis_aligned_fraction_stderr, 0);

    const CrackNetwork b = measure_crack_network(m_topo, crossed, m_columns, 1);
    ASSERT_EQ(b.oriented_cracks, 4);
    const double p = b.axis_aligned_fraction;
    ASSERT_GT(p, 0.2);
    ASSERT_LT(p, 0.8);
    const double by_points = std::sqrt(p * (1 - p) / b.oriented_points);
    EXPECT_GT(b.axis_aligned_fraction_stderr, 0.12);
    EXPECT_LT(b.axis_aligned_fraction_stderr, 0.4);
    EXPECT_GT(b.axis_aligned_fraction_stderr, 3 * by_points) << b.oriented_points << " points";
    std::printf("aligned %.3f over %d points in %d cracks: stderr %.3f (over points %.3f)\n", p,
                b.oriented_points, b.oriented_cracks, b.axis_aligned_fraction_stderr, by_points);
    // a fixed seed: the same network, the same figure
    EXPECT_EQ(measure_crack_network(m_topo, crossed, m_columns, 1).axis_aligned_fraction_stderr,
              b.axis_aligned_fraction_stderr);
}

TEST_F(CrackNetworkTest, ACrackEndingOnAnotherIsATJunctionThreeFromAPointAreAY) {
    std::vector<uint8_t> t = none(), y = none();
    cut(Vec2(1.53, -1), Vec2(1.53, 4), t);    // a through crack
    cut(Vec2(1.53, 1.47), Vec2(4, 1.47), t);  // one that ends on it
    const Vec2 c(1.53, 1.47);
    for (int k = 0; k < 3; ++k) {
        const double angle = 0.3 + k * 2 * 3.14159265358979 / 3;
        cut(c, c + 3 * Vec2(std::cos(angle), std::sin(angle)), y);
    }
    const CrackNetwork nt = measure_crack_network(m_topo, t, m_columns, 1);
    const CrackNetwork ny = measure_crack_network(m_topo, y, m_columns, 1);
    ASSERT_EQ(nt.junctions, 1);
    EXPECT_EQ(nt.t_fraction, 1);
    EXPECT_EQ(nt.y_fraction, 0);
    ASSERT_EQ(ny.junctions, 1);
    EXPECT_EQ(ny.y_fraction, 1);
    EXPECT_EQ(ny.t_fraction, 0);
    // the angles between the branches: a T's 90, 90 and 180 degrees (bins 6 and 12), a Y's
    // three of 120 (bin 8), give or take a bin where the lattice's edges draw the cut lines
    std::array<int32_t, kJunctionAngleBins> t_angles{};
    t_angles[6] = 2, t_angles[12] = 1;
    EXPECT_EQ(nt.junction_angle_histogram, t_angles);
    const auto& y_angles = ny.junction_angle_histogram;
    EXPECT_EQ(y_angles[7] + y_angles[8] + y_angles[9], 3);
    EXPECT_NEAR(nt.junction_right_angle_fraction, 2.0 / 3, tol::kRoundoff);
    EXPECT_EQ(ny.junction_right_angle_fraction, 0);
}

TEST_F(CrackNetworkTest, AGridOfCracksCutsFourSidedPlatesAndOnlyInlandOnesCount) {
    // of the 3 x 3 plates only the middle one stays off the rim, and it borders four plates along
    // a side (the corner ones at a point)
    const std::vector<uint8_t> broken = three_by_three();
    const PolygonSides sides = measure_polygon_sides(m_topo, broken, m_columns, 1);
    EXPECT_EQ(sides.inland_plates, 1);
    EXPECT_EQ(sides.mean_sides, 4);
    EXPECT_EQ(sides.histogram[4], 1);
    // uncut, the top is one plate on the rim: none inland
    EXPECT_EQ(measure_polygon_sides(m_topo, none(), m_columns, 1).inland_plates, 0);
}

// A heightfield's lattice has layers thinner than its pitch, so the spacing mc-measure takes from
// the particle volume lies below the pitch (kH 0.6^(1/3) here). Cells of that spacing left an
// empty one every few cells, so no crack point was inland and no plate either; the columns now
// follow the lattice, and the crack network reads as on the cubic lattice.
TEST_F(CrackNetworkTest, ALatticeOfThinLayersKeepsOneColumnPerLatticeColumnAndNoHoles) {
    TetMesh thin = m_mesh;
    for (Vec3& x : thin.X) x.y() *= 0.6;
    const CoreTopology topo = build_core_topology(thin);
    const RestColumns columns = build_rest_columns(thin.X, kH * std::cbrt(0.6));
    EXPECT_EQ(columns.n_columns(), 31 * 31);
    EXPECT_NEAR(columns.pitch.x(), kH, tol::kRoundoff);
    EXPECT_NEAR(columns.pitch.y(), kH, tol::kRoundoff);
    for (int c = 0; c < columns.n_columns(); ++c)
        ASSERT_EQ(columns.begin[c + 1] - columns.begin[c], 3);
    std::vector<uint8_t> along = none();
    cut(Vec2(1.53, -1), Vec2(1.53, 4), along);
    const CrackNetwork a = measure_crack_network(topo, along, columns, 1);
    EXPECT_GT(a.oriented_points, 20);
    EXPECT_GT(a.axis_aligned_fraction, 0.95);
    EXPECT_EQ(measure_polygon_sides(topo, three_by_three(), columns, 1).inland_plates, 1);
}

// Off a lattice (here a jittered one: every particle its own x and z), the cells are the given
// spacing wide from 0, as before.
TEST(RestColumns, OffALatticeTheCellsAreTheSpacingWideFromZero) {
    std::vector<Vec3> rest = lattice();
    for (size_t p = 0; p < rest.size(); ++p)
        rest[p] += kSpacing * Vec3(0.3 * std::sin(1.7 * p), 0, 0.3 * std::cos(2.3 * p));
    const RestColumns columns = build_rest_columns(rest, kSpacing);
    EXPECT_EQ(columns.pitch, Vec2(kSpacing, kSpacing));
    EXPECT_EQ(columns.origin, Vec2::Zero());
    EXPECT_EQ(columns.cell_of(rest[0].x(), rest[0].z()),
              ColumnCell(std::floor(rest[0].x() / kSpacing), std::floor(rest[0].z() / kSpacing)));
}

TEST(CrackPace, FirstCrackAndTheFrameByWhichHalfOfTheLastFramesBreaksExist) {
    // a shot of frames 1-41: 1 edge breaks in frame 5, 3 in frame 10, 4 in frame 20 and 2 in
    // frame 30; one never breaks
    std::vector<int32_t> first_break = {kNeverBroken, 10, 20, 5, 20, 10, 30, 20, 10, 20, 30};
    const CrackPace at_41 = measure_crack_pace(first_break, 1, 41, 41);
    EXPECT_EQ(at_41.first_crack_frame, 5);
    EXPECT_EQ(at_41.half_broken_frame, 20);  // 4 by frame 10 of 10, 8 by frame 20
    EXPECT_NEAR(at_41.half_broken_range_fraction, 19.0 / 40, tol::kRoundoff);
    // measured up to frame 15: half of the 4 edges broken by then exist by frame 10
    const CrackPace at_15 = measure_crack_pace(first_break, 1, 41, 15);
    EXPECT_EQ(at_15.first_crack_frame, 5);
    EXPECT_EQ(at_15.half_broken_frame, 10);
    // before any crack, and an edge broken before the range starts counts at its start
    EXPECT_EQ(measure_crack_pace(first_break, 1, 41, 4).first_crack_frame, -1);
    EXPECT_EQ(measure_crack_pace({0, kNeverBroken}, 1, 41, 41).half_broken_frame, 1);
}

}  // namespace
}  // namespace mudcrack
