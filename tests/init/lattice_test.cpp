// The procedural sources: box (regular, jittered) and heightfield lattices, and the shared
// finishing step (boundary, UVs, rest volumes, quality).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "init_test_util.h"
#include "pipeline/init/boundary_uv.h"
#include "pipeline/init/heightfield.h"
#include "pipeline/init/init_builder.h"
#include "pipeline/init/lattice.h"
#include "pipeline/init/tet_mesh_ops.h"
#include "pipeline/io/image_io.h"
#include "sim/core/error.h"
#include "sim/core/log.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
constexpr double kAngleDeg = 1e-9;              // dihedral angles of exact lattice tets [deg]
constexpr double kHeightfieldVolumeRel = 5e-3;  // column tets' volume vs the heightfield's integral
constexpr double kLatticeExact = 1e-12;  // volumes and bounds a regular lattice gives exactly

InitParams box_params(Vec3 min, Vec3 max, Real spacing, Lattice lattice) {
    InitParams p;
    p.type = SourceType::Box;
    p.box.min = min;
    p.box.max = max;
    p.box.spacing = spacing;
    p.box.lattice = lattice;
    return p;
}

TEST(InitKuhnTets, OneCellIsSixPositiveTetsFillingTheCube) {
    TetMesh m;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) m.X.emplace_back(i, j, k);
    m.tets = kuhn_tets(1, 1, 1);
    ASSERT_EQ(m.tets.size(), 6u);
    for (const Tet& t : m.tets)
        EXPECT_NEAR(signed_tet_volume(m.X[t[0]], m.X[t[1]], m.X[t[2]], m.X[t[3]]), 1.0 / 6,
                    tol::kRoundoff);
}

TEST(InitBoxSource, RegularLatticeHasExactCountsAndVolume) {
    // 0.4 x 0.1 x 0.3 at 0.05: 8 x 2 x 6 cells
    const InitParams p =
        box_params(Vec3(-0.2, 0, -0.15), Vec3(0.2, 0.1, 0.15), 0.05, Lattice::Regular);
    const InitResult r = build_init(p, 0.05);
    EXPECT_EQ(r.quality.particles, 9 * 3 * 7);
    EXPECT_EQ(r.quality.tets, 6 * 8 * 2 * 6);
    // the surface of a 8 x 2 x 6 lattice has 2 triangles per boundary cell face
    EXPECT_EQ(r.quality.boundary_faces, 2 * 2 * (8 * 2 + 8 * 6 + 2 * 6));
    EXPECT_NEAR(r.quality.tet_volume, 0.4 * 0.1 * 0.3, tol::kRoundoff);
    EXPECT_NEAR(r.quality.bbox_min.x(), -0.2, tol::kRoundoff);
    EXPECT_NEAR(r.quality.bbox_max.z(), 0.15, tol::kRoundoff);
    // Kuhn tets: right angles (90) and 45/60-degree wedges, nothing worse
    EXPECT_NEAR(r.quality.min_dihedral_deg, 45.0, kAngleDeg);
    EXPECT_NEAR(r.quality.max_dihedral_deg, 90.0, kAngleDeg);
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    EXPECT_EQ(r.uv_method, "box projection");
}

TEST(InitBoxSource, SpacingIsStretchedToFitTheBoxExactly) {
    // 1.0 / 0.3 rounds to 3 cells of 0.333...; 0.1 / 0.3 rounds to 0, kept at 1 cell
    const InitParams p = box_params(Vec3(0, 0, 0), Vec3(1, 0.1, 1), 0.3, Lattice::Regular);
    const InitResult r = build_init(p, 0.05);
    EXPECT_EQ(r.quality.particles, 4 * 2 * 4);
    EXPECT_NEAR(r.quality.tet_volume, 0.1, tol::kRoundoff);
    EXPECT_EQ(r.quality.bbox_max, Vec3(1, 0.1, 1));
}

TEST(InitBoxSource, JitteredLatticeKeepsCountsVolumeAndPositiveTets) {
    InitParams p = box_params(Vec3(0, 0, 0), Vec3(0.5, 0.25, 0.5), 0.05, Lattice::Jittered);
    p.box.jitter = 0.45;  // near the spec's limit (< 0.5), where unchecked moves would invert tets
    const InitResult r = build_init(p, 0.05);
    const InitResult regular =
        build_init(box_params(p.box.min, p.box.max, 0.05, Lattice::Regular), 0.05);
    EXPECT_EQ(r.quality.particles, 11 * 6 * 11);
    EXPECT_EQ(r.quality.tets, regular.quality.tets);
    EXPECT_NEAR(r.quality.tet_volume / (0.5 * 0.25 * 0.5), 1.0, tol::kRoundoffLoose);
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    // interior points really moved, by at most jitter * spacing, and boundary points did not
    int moved = 0;
    for (size_t v = 0; v < r.mesh.X.size(); ++v) {
        const Real d = (r.mesh.X[v] - regular.mesh.X[v]).norm();
        EXPECT_LE(d, 0.45 * 0.05 + 1e-12);
        const Vec3& x = regular.mesh.X[v];
        const bool is_surface =
            x.x() == 0 || x.x() == 0.5 || x.y() == 0 || x.y() == 0.25 || x.z() == 0 || x.z() == 0.5;
        if (is_surface) {
            EXPECT_EQ(d, 0) << "surface point " << v << " moved";
        }
        moved += d > 0;
    }
    EXPECT_GT(moved, (9 * 4 * 9) / 2) << "most of the 324 interior points should move";
    EXPECT_LT(r.quality.min_dihedral_deg, 45.0);
}

TEST(InitBoxSource, JitterIsSeeded) {
    InitParams p = box_params(Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3), 0.05, Lattice::Jittered);
    const TetMesh a = make_box_tets(p.box, 7), b = make_box_tets(p.box, 7),
                  c = make_box_tets(p.box, 8);
    EXPECT_EQ(a.X, b.X);
    EXPECT_NE(a.X, c.X);
}

TEST(InitBoxSource, EllipseFootprintIsARoundSlabWithItsRimOnTheEllipse) {
    // a 0.6 x 0.4 ellipse, 5 cm deep, jittered at 0.01: 61 x 6 x 41 lattice points before the cut
    InitParams p = box_params(Vec3(-0.3, 0, -0.2), Vec3(0.3, 0.05, 0.2), 0.01, Lattice::Jittered);
    p.box.footprint = Footprint::Ellipse;
    const InitResult r = build_init(p, 0.02);
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_no_unused_vertices(r.mesh);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    // the body is the elliptic cylinder: pi a b H, and pi / 4 of the box's points (the rim's
    // quarter-moves and the staircase's corners leave it within a few tenths of a percent)
    const double pi = std::acos(-1.0);
    EXPECT_NEAR(r.quality.tet_volume / (pi * 0.3 * 0.2 * 0.05), 1.0, 3e-3);
    EXPECT_NEAR(double(r.quality.particles) / (61 * 6 * 41), pi / 4, 0.02);
    // the side wall's points on the ellipse: all within half a spacing, nearly all exactly
    // (the rest where a full move would squash a corner cell or run two rim points together)
    auto ellipse_radius = [](const Vec3& x) { return std::hypot(x.x() / 0.3, x.z() / 0.2); };
    int side_points = 0, on_the_ellipse = 0;
    // the largest distances of a point outside the ellipse and of a side point inside it [m]
    Real worst_outside = 0, worst_inside = 0;
    std::vector<char> is_boundary(r.mesh.X.size(), 0);
    for (const Tri& f : r.mesh.boundary)
        for (int32_t v : f) is_boundary[v] = 1;
    for (size_t v = 0; v < r.mesh.X.size(); ++v) {
        const Vec3& x = r.mesh.X[v];
        const Real rho = ellipse_radius(x);
        worst_outside = std::max(worst_outside, (rho - 1) * 0.2);  // 0.2: the smaller semi-axis
        const bool is_side = is_boundary[v] && x.y() > 0 && x.y() < 0.05;
        if (!is_side) continue;
        ++side_points;
        on_the_ellipse += std::abs(rho - 1) < 1e-9;
        worst_inside = std::max(worst_inside, (1 - rho) * 0.2);  // 0.2: the smaller semi-axis
    }
    EXPECT_GT(side_points, 4 * 150) << "the wall of a 1.6 m rim, 4 rows of side points";
    EXPECT_GT(on_the_ellipse, 0.8 * side_points);
    EXPECT_LT(worst_inside, 0.5 * 0.01);
    EXPECT_LT(worst_outside, 0.5 * 0.01);
    std::printf("side points %d, on the ellipse %d, worst outside %.2g m, inside %.2g m\n",
                side_points, on_the_ellipse, worst_outside, worst_inside);
    // the interior was jittered, as the rectangle's is
    EXPECT_LT(r.quality.min_dihedral_deg, 45.0);
}

TEST(InitBoxSource, EmptyBoxIsAnInputErrorNamingTheKey) {
    InitParams p = box_params(Vec3(0, 0, 0), Vec3(1, 0, 1), 0.1, Lattice::Regular);
    try {
        build_init(p, 0.05);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/source/box"), std::string::npos) << e.what();
    }
}

TEST(InitBoxSource, AbsurdParticleCountIsAnInputErrorNamingTheSpacing) {
    const InitParams p = box_params(Vec3(0, 0, 0), Vec3(10, 10, 10), 0.001, Lattice::Regular);
    try {
        build_init(p, 0.05);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/source/box/spacing"), std::string::npos) << e.what();
    }
}

TEST(InitHeightfield, RiverbedHasAFlatBottomACarvedChannelAndConservesVolume) {
    InitParams p;
    p.type = SourceType::Heightfield;
    p.heightfield.size = Vec3(2, 0, 2);
    p.heightfield.spacing = 0.05;
    const InitResult r = build_init(p, 0.05);
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    // 41 x 41 columns, 7 layers (ceil(max top / spacing) with a top of at most 0.35 m)
    const int nx = 40, nz = 40;
    EXPECT_EQ(r.quality.particles % ((nx + 1) * (nz + 1)), 0);
    EXPECT_NEAR(r.quality.bbox_min.y(), 0.0, tol::kRoundoff);
    EXPECT_LE(r.quality.bbox_max.y(), p.heightfield.base + p.heightfield.amplitude + 1e-12);
    // the channel centre at x = 0 is z = 0 and sits channel_depth below the banks' mean
    const Real centre = riverbed_height(p.heightfield, 0, 0);
    const Real bank = riverbed_height(p.heightfield, 0, 0.9);
    EXPECT_LT(centre, bank - 0.5 * p.heightfield.channel_depth);
    // volume: the tets integrate the piecewise-linear top; compare with a midpoint sum
    Real integral = 0;
    const int n = 400;
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < n; ++i)
            integral +=
                riverbed_height(p.heightfield, -1 + 2 * (i + 0.5) / n, -1 + 2 * (k + 0.5) / n) *
                (4.0 / (n * n));
    EXPECT_NEAR(r.quality.tet_volume / integral, 1.0, kHeightfieldVolumeRel);
}

TEST(InitHeightfield, ChannelThroughTheFloorIsAnInputError) {
    InitParams p;
    p.type = SourceType::Heightfield;
    p.heightfield.channel_depth = 0.3;
    try {
        build_init(p, 0.05);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/source/heightfield"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("channel_depth"), std::string::npos) << e.what();
    }
}

/// A grayscale PNG in the temp folder; the caller removes it.
std::string write_gray_png(const std::string& stem, int width, int height,
                           const std::vector<uint8_t>& gray) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("mudcrack_init_" + stem + "_" + std::to_string(::getpid()) + ".png"))
                                 .string();
    Image image;
    image.width = width;
    image.height = height;
    image.channels = 1;
    image.pixels = gray;
    write_png(path, image);
    return path;
}

TEST(InitHeightfield, PngGradientGivesALinearSlopeAndExactVolume) {
    // left pixels 51 (0.2), right pixels 255 (1.0): top = 0.3 (0.2 + 0.8 u), linear in x, which
    // the lattice represents exactly: volume = 0.3 * 0.6 * 1 m^2
    InitParams p;
    p.type = SourceType::Heightfield;
    p.heightfield.size = Vec3(1, 0, 1);
    p.heightfield.spacing = 0.1;
    p.heightfield.image_height = 0.3;
    p.heightfield.image = write_gray_png("gradient", 2, 2, {51, 255, 51, 255});
    const InitResult r = build_init(p, 0.05);
    std::filesystem::remove(p.heightfield.image);
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    EXPECT_NEAR(r.quality.tet_volume, 0.18, kLatticeExact);
    for (const Vec3& x : r.mesh.X) EXPECT_LE(x.y(), 0.3 * (0.2 + 0.8 * (x.x() + 0.5)) + 1e-12);
    EXPECT_NEAR(r.quality.bbox_max.y(), 0.3, kLatticeExact);
    EXPECT_EQ(r.quality.particles, 11 * 11 * 4);  // ceil(0.3 / 0.1) = 3 layers
}

TEST(InitHeightfield, BlackPngKeepsAThinFloorAndWarns) {
    InitParams p;
    p.type = SourceType::Heightfield;
    p.heightfield.size = Vec3(1, 0, 1);
    p.heightfield.spacing = 0.1;
    p.heightfield.image = write_gray_png("black", 4, 4, std::vector<uint8_t>(16, 0));
    log::reset_warnings();
    const InitResult r = build_init(p, 0.05);
    std::filesystem::remove(p.heightfield.image);
    EXPECT_NEAR(r.quality.tet_volume, 0.25 * 0.1, kLatticeExact);
    EXPECT_EQ(log::warning_count(), 1);
    log::reset_warnings();
    test::expect_all_tets_positive(r.mesh);
}

TEST(InitColumnLattice, SteepColumnsStayPositive) {
    // neighbouring columns 50x apart in height: vertical stretching never flips a Kuhn tet
    std::vector<Real> top(5 * 5);
    for (size_t c = 0; c < top.size(); ++c) top[c] = (c % 3 == 0) ? 1.0 : 0.02;
    const TetMesh m = make_column_lattice_tets(0, 0, 1, 1, 4, 3, 4, top);
    ASSERT_EQ(m.tets.size(), size_t(6 * 4 * 3 * 4))
        << "6 Kuhn tets per cell of the 4 x 3 x 4 lattice";
    test::expect_all_tets_positive(m);
}

TEST(InitBoundaryUV, ProjectionUsesTheDominantAxisPlaneScaledByTheLargestExtent) {
    // a 2 x 1 x 1 box: top faces map x,z / 2; the +x side maps z,y / 2
    const InitParams p = box_params(Vec3(0, 0, 0), Vec3(2, 1, 1), 0.5, Lattice::Regular);
    const InitResult r = build_init(p, 0.05);
    for (size_t f = 0; f < r.mesh.boundary.size(); ++f) {
        const Tri& t = r.mesh.boundary[f];
        const Vec3 n = (r.mesh.X[t[1]] - r.mesh.X[t[0]]).cross(r.mesh.X[t[2]] - r.mesh.X[t[0]]);
        for (int c = 0; c < 3; ++c) {
            const Vec3& x = r.mesh.X[t[c]];
            const Vec2& uv = r.mesh.boundary_uv[f][c];
            Vec2 expected;
            if (std::abs(n.y()) > 0) expected = Vec2(x.x() / 2, x.z() / 2);
            if (std::abs(n.x()) > 0) expected = Vec2(x.z() / 2, x.y() / 2);
            if (std::abs(n.z()) > 0) expected = Vec2(x.x() / 2, x.y() / 2);
            EXPECT_EQ(uv, expected)
                << "face " << f << " corner " << c << " normal " << n.transpose();
            EXPECT_GE(uv.minCoeff(), 0);
            EXPECT_LE(uv.maxCoeff(), 1);
        }
    }
}

TEST(InitTetMeshOps, DropUnusedVerticesRenumbersContiguously) {
    TetMesh m;
    m.X = {Vec3(9, 9, 9), Vec3(0, 0, 0), Vec3(1, 0, 0),
           Vec3(7, 7, 7), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    m.tets = {{1, 2, 4, 5}};
    drop_unused_vertices(m);
    ASSERT_EQ(m.X.size(), 4u);
    EXPECT_EQ(m.tets[0], (Tet{0, 1, 2, 3}));
    EXPECT_EQ(m.X[0], Vec3(0, 0, 0));
    EXPECT_EQ(m.X[3], Vec3(0, 0, 1));
}

TEST(InitTetMeshOps, DihedralAnglesOfTheRegularTetAreArccosOneThird) {
    const Vec3 a(1, 1, 1), b(1, -1, -1), c(-1, 1, -1), d(-1, -1, 1);
    const Real expected = std::acos(1.0 / 3) * 180 / M_PI;  // 70.53 degrees
    for (Real angle : dihedral_angles_deg(a, b, c, d)) EXPECT_NEAR(angle, expected, kAngleDeg);
    // the corner tet of a cube: 90 degrees at the three edges through the corner, and
    // acos(1/sqrt(3)) = 54.74 degrees where the slanted face x+y+z=1 meets the others
    const auto corner =
        dihedral_angles_deg(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1));
    const Real slanted = std::acos(1 / std::sqrt(3.0)) * 180 / M_PI;
    // edges (0,1), (0,2), (0,3)
    for (int e : {0, 1, 2}) EXPECT_NEAR(corner[e], 90, kAngleDeg) << "edge " << e;
    for (int e : {3, 4, 5}) EXPECT_NEAR(corner[e], slanted, kAngleDeg) << "edge " << e;
}

TEST(InitDefaultEdgeLength, IsSixTenthsOfTheGridSpacing) {
    EXPECT_DOUBLE_EQ(default_edge_length(0.05), 0.03);
    InitParams p;
    EXPECT_DOUBLE_EQ(mesher_options(p, 0.04).edge_length, 0.6 * 0.04);
    p.edge_length = 0.01;
    EXPECT_DOUBLE_EQ(mesher_options(p, 0.04).edge_length, 0.01);
}

}  // namespace
}  // namespace mudcrack
