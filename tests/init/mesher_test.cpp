// The mesh source: input surface checks (CGAL PMP), Mesh_3 tetrahedralization, UV transfer,
// and the bunny at default sizing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "init_test_util.h"
#include "pipeline/init/boundary_uv.h"
#include "pipeline/init/cgal_mesher.h"
#include "pipeline/init/heightfield.h"
#include "pipeline/init/init_builder.h"
#include "pipeline/init/surface_check.h"
#include "sim/core/error.h"
#include "sim/model.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
// Mesh_3's volume of a curved surface vs the enclosed volume
constexpr double kMeshedVolumeRel = 0.03;
constexpr double kOnSphereAbs = 0.01;    // a surface vertex's distance from the sphere [m]
constexpr double kEdgeLengthRel = 0.25;  // mean edge length vs the asked edge length
constexpr double kCubeVolumeAbs = 1e-6;  // a meshed unit cube's volume [m^3]
// bounds and volumes a box gives exactly, summed round-off
constexpr double kBoxExactAbs = 1e-9;
constexpr double kFittedVolumeRel = 0.02;  // the tets' volume vs the input surface's
constexpr double kGroundFitAbs = 0.01;     // fit_to_ground's lowest point vs y = 0 [m]
// a heightfield's closed surface vs its columns' tets: the same tops, other diagonals
constexpr double kHeightfieldVolumeRel = 2e-3;
// a point on a meshed terrain's top vs the formula: the surface's chords between samples 0.025 m
// apart sag below the curved channel and undulations, and Mesh_3's facets cut across them
// (measured: 2.6 mm at most) [m]
constexpr double kOnTerrainAbs = 5e-3;

namespace fs = std::filesystem;

/// Expects check_input_surface to refuse `s`, with a message containing every needle.
void expect_refused(const InputSurface& s, const std::vector<std::string>& needles) {
    try {
        check_input_surface(s, "bad.off");
        ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const std::string& n : needles)
            EXPECT_NE(msg.find(n), std::string::npos) << "message: " << msg << "\nmissing: " << n;
    }
}

/// Appends `b` to `a`, welding vertices at identical positions.
InputSurface merged(const InputSurface& a, const InputSurface& b) {
    InputSurface s = a;
    std::vector<int32_t> id(b.positions.size());
    for (size_t v = 0; v < b.positions.size(); ++v) {
        const auto it = std::find(s.positions.begin(), s.positions.end(), b.positions[v]);
        id[v] = static_cast<int32_t>(it - s.positions.begin());
        if (it == s.positions.end()) s.positions.push_back(b.positions[v]);
    }
    for (const Tri& f : b.faces) s.faces.push_back({id[f[0]], id[f[1]], id[f[2]]});
    return s;
}

InputSurface shifted(InputSurface s, const Vec3& d) {
    for (Vec3& p : s.positions) p += d;
    return s;
}

TEST(InitSurfaceCheck, ClosedCubeAndSpherePassWithTheirVolume) {
    EXPECT_NEAR(check_input_surface(test::unit_cube(), "cube"), 1.0, tol::kRoundoff);
    const InputSurface sphere = test::icosphere(0.5, 3);
    EXPECT_NEAR(check_input_surface(sphere, "sphere"), enclosed_volume(sphere), tol::kRoundoff);
    EXPECT_NEAR(enclosed_volume(sphere), 4.0 / 3 * M_PI * 0.125, 0.02 * 4.0 / 3 * M_PI * 0.125);
}

TEST(InitSurfaceCheck, OpenMeshNamesItsBorderEdgeCount) {
    InputSurface s = test::unit_cube();
    s.faces.erase(s.faces.begin(), s.faces.begin() + 2);  // the z = 0 side: a square hole
    expect_refused(s, {"bad.off", "4 border edges", "not closed", "first at ("});
}

TEST(InitSurfaceCheck, OneFlippedFaceIsInconsistentOrientation) {
    InputSurface s = test::unit_cube();
    std::swap(s.faces[5][1], s.faces[5][2]);
    expect_refused(s, {"bad.off", "3 edges whose two faces have opposite orientations"});
}

TEST(InitSurfaceCheck, InsideOutMeshHasNegativeVolume) {
    InputSurface s = test::unit_cube();
    for (Tri& f : s.faces) std::swap(f[1], f[2]);
    expect_refused(s, {"bad.off", "enclosed volume = -1", "inside out"});
}

TEST(InitSurfaceCheck, OverlappingShellsSelfIntersect) {
    const InputSurface s =
        merged(test::unit_cube(), shifted(test::unit_cube(), Vec3(0.5, 0.3, 0.2)));
    expect_refused(s, {"bad.off", "pairs of self-intersecting faces", "near ("});
}

TEST(InitSurfaceCheck, CubesTouchingAtAnEdgeOrAVertexAreNonManifold) {
    expect_refused(merged(test::unit_cube(), shifted(test::unit_cube(), Vec3(1, 1, 0))),
                   {"bad.off", "non-manifold edges (shared by more than two faces)"});
    expect_refused(merged(test::unit_cube(), shifted(test::unit_cube(), Vec3(1, 1, 1))),
                   {"bad.off", "1 non-manifold vertices", "(1, 1, 1)"});
}

TEST(InitMesher, SphereIsFilledWithPositiveTetsAndAClosedBoundary) {
    const InputSurface sphere = test::icosphere(0.5, 3);
    MesherOptions o;
    o.edge_length = 0.1;
    const InitResult r = finish_tet_mesh(tetrahedralize_surface(sphere, o), &sphere);
    EXPECT_GT(r.quality.particles, 200);
    test::expect_all_tets_positive(r.mesh);
    test::expect_no_unused_vertices(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    EXPECT_EQ(r.uv_method, "box projection");
    EXPECT_NEAR(r.quality.tet_volume / enclosed_volume(sphere), 1.0, kMeshedVolumeRel);
    // the boundary vertices lie on the input sphere (within the facet distance)
    for (const Tri& f : r.mesh.boundary)
        for (int32_t v : f) EXPECT_NEAR(r.mesh.X[v].norm(), 0.5, kOnSphereAbs);
    EXPECT_NEAR(r.quality.mean_edge_length / o.edge_length, 1.0, kEdgeLengthRel);
}

TEST(InitMesher, SameSeedGivesTheSameMesh) {
    const InputSurface sphere = test::icosphere(0.5, 2);
    MesherOptions o;
    o.edge_length = 0.12;
    const TetMesh a = tetrahedralize_surface(sphere, o), b = tetrahedralize_surface(sphere, o);
    EXPECT_EQ(a.X, b.X);
    EXPECT_EQ(a.tets, b.tets);
}

// /init/seed draws another mesh: Mesh_3's domain takes its initial points from a generator of
// its own, which a reseeded default generator does not reach (every seed gave one mesh)
TEST(InitMesher, AnotherSeedGivesAnotherMesh) {
    const InputSurface sphere = test::icosphere(0.5, 2);
    MesherOptions o;
    o.edge_length = 0.12;
    const TetMesh one = tetrahedralize_surface(sphere, o);
    o.seed = 2;
    const TetMesh two = tetrahedralize_surface(sphere, o);
    EXPECT_FALSE(one.X == two.X) << "seed 2 gave seed 1's mesh";
    // both are meshes of the sphere all the same
    EXPECT_NEAR(static_cast<double>(two.X.size()) / one.X.size(), 1.0, 0.2);
}

TEST(InitMesher, CubeKeepsItsSharpCornersAndVolume) {
    MesherOptions o;
    o.edge_length = 0.2;
    const InitResult r = finish_tet_mesh(tetrahedralize_surface(test::unit_cube(), o), nullptr);
    EXPECT_NEAR(r.quality.tet_volume, 1.0, kCubeVolumeAbs);
    EXPECT_NEAR(r.quality.bbox_min.norm(), 0.0, kBoxExactAbs);
    EXPECT_NEAR((r.quality.bbox_max - Vec3(1, 1, 1)).norm(), 0.0, kBoxExactAbs);
    test::expect_closed_outward_boundary(r.mesh);
}

TEST(InitMesher, UVsAreTransferredFromTheInputSurface) {
    // UVs that are a linear function of position are reproduced exactly at the closest point,
    // so each corner's UV must match the function at the corner up to the facet distance
    InputSurface sphere = test::icosphere(0.5, 3);
    auto uv_of = [](const Vec3& p) { return Vec2(p.x() + 0.5, 0.25 * p.z() + 0.5); };
    for (const Tri& f : sphere.faces)
        sphere.face_uv.push_back({uv_of(sphere.positions[f[0]]), uv_of(sphere.positions[f[1]]),
                                  uv_of(sphere.positions[f[2]])});
    MesherOptions o;
    o.edge_length = 0.1;
    const InitResult r = finish_tet_mesh(tetrahedralize_surface(sphere, o), &sphere);
    EXPECT_EQ(r.uv_method, "transferred");
    test::expect_finite_boundary_uvs(r.mesh);
    for (size_t f = 0; f < r.mesh.boundary.size(); ++f)
        for (int c = 0; c < 3; ++c)
            EXPECT_LT((r.mesh.boundary_uv[f][c] - uv_of(r.mesh.X[r.mesh.boundary[f][c]])).norm(),
                      0.01)
                << "face " << f << " corner " << c;
}

/// The unit cube as an OFF file in the temp folder (removed by the caller).
fs::path write_cube_off(const std::string& stem) {
    const fs::path file = fs::temp_directory_path() /
                          ("mudcrack_init_" + stem + "_" + std::to_string(::getpid()) + ".off");
    const InputSurface cube = test::unit_cube();
    std::ofstream os(file);
    os << "OFF\n" << cube.positions.size() << " " << cube.faces.size() << " 0\n";
    for (const Vec3& p : cube.positions) os << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const Tri& f : cube.faces) os << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
    return file;
}

TEST(InitMeshSource, EdgeLengthFarTooSmallOrTooLargeIsAnInputError) {
    const fs::path file = write_cube_off("sizing");
    InitParams p;
    p.type = SourceType::Mesh;
    p.mesh.path = file.string();
    for (Real edge : {1e-4, 5.0}) {
        p.edge_length = edge;
        try {
            build_init(p, 0.05);
            ADD_FAILURE() << "expected InputError for edge_length " << edge;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("/init/edge_length"), std::string::npos)
                << e.what();
        }
    }
    fs::remove(file);
}

// The share of a tet mesh's edge length within `degrees` of the x, y or z axis.
double axis_aligned_edge_share(const TetMesh& m, double degrees) {
    const double cos_limit = std::cos(degrees * kPi / 180);
    double aligned = 0, total = 0;
    for (const Tet& t : m.tets)
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const Vec3 e = m.X[t[b]] - m.X[t[a]];
                const double length = e.norm();
                total += length;
                if (e.cwiseAbs().maxCoeff() >= cos_limit * length) aligned += length;
            }
    return aligned / total;
}

// A box source [lo, hi] with lattice "mesh"
InitParams meshed_box(const Vec3& lo, const Vec3& hi) {
    InitParams p;
    p.type = SourceType::Box;
    p.box.min = lo;
    p.box.max = hi;
    p.box.lattice = Lattice::Mesh;
    return p;
}

// A box with lattice "mesh" is a mesh source of the box's own surface: Mesh_3 tets at the
// derived edge length, the box's volume and corners exact, seeded, and edges that run every way
// (the cracks follow the particles' edges; the Kuhn lattice lays 3 of its 7 edge directions on
// the axes)
TEST(InitBoxSource, MeshLatticeFillsTheBoxWithMesh3TetsAlongNoAxis) {
    const InitParams p = meshed_box(Vec3(-0.2, 0, -0.15), Vec3(0.2, 0.1, 0.15));
    const Real h = 0.05;
    const InitResult r = build_init(p, h);
    const double box_volume = (p.box.max - p.box.min).prod();
    EXPECT_NEAR(r.surface_volume, box_volume, kBoxExactAbs);
    EXPECT_NEAR(r.quality.tet_volume, box_volume, kCubeVolumeAbs);
    EXPECT_NEAR((r.quality.bbox_min - p.box.min).norm(), 0.0, kBoxExactAbs);
    EXPECT_NEAR((r.quality.bbox_max - p.box.max).norm(), 0.0, kBoxExactAbs);
    EXPECT_EQ(r.edge_length, default_edge_length(h));
    EXPECT_NEAR(r.quality.mean_edge_length, default_edge_length(h),
                kEdgeLengthRel * default_edge_length(h));
    test::expect_closed_outward_boundary(r.mesh);
    for (const Tet& t : r.mesh.tets)
        ASSERT_GT(signed_tet_volume(r.mesh.X[t[0]], r.mesh.X[t[1]], r.mesh.X[t[2]], r.mesh.X[t[3]]),
                  0);

    // Mesh_3's edges put 4 % of their length within 5 degrees of the three axes (isotropic
    // directions: 1.1 %; the box's faces and sharp edges add the rest), the lattice's 40 %
    const double mesh_share = axis_aligned_edge_share(r.mesh, 5);
    InitParams lattice = p;
    lattice.box.lattice = Lattice::Regular;
    lattice.box.spacing = 0.025;
    const double lattice_share = axis_aligned_edge_share(build_init(lattice, h).mesh, 5);
    EXPECT_GT(lattice_share, 0.35);
    EXPECT_LT(mesh_share, 0.15) << "against the lattice's " << lattice_share;
    std::printf("edge length within 5 degrees of the axes: mesh %.3f, lattice %.3f\n", mesh_share,
                lattice_share);

    const InitResult again = build_init(p, h);
    EXPECT_EQ(again.mesh.X, r.mesh.X);
    EXPECT_EQ(again.mesh.tets, r.mesh.tets);
}

// A box with an ellipse footprint and lattice "mesh" is Mesh_3's fill of the elliptic cylinder
// inscribed in it (a round puddle with no rows): the ellipse's volume, every point inside it, a
// rim that goes all the way round, and edges that run every way
TEST(InitBoxSource, MeshLatticeFillsAnEllipseFootprintsCylinderAlongNoAxis) {
    InitParams p = meshed_box(Vec3(-0.2, 0, -0.15), Vec3(0.2, 0.06, 0.15));
    p.box.footprint = Footprint::Ellipse;
    const Real h = 0.04;
    const InitResult r = build_init(p, h);
    const double a = 0.2, b = 0.15, thickness = 0.06;
    // the rims' polygons of chords at most half an edge long (93 here) hold all but 0.08 % of the
    // ellipse
    EXPECT_NEAR(r.surface_volume / (kPi * a * b * thickness), 1, 2e-3);
    EXPECT_NEAR(r.quality.tet_volume / r.surface_volume, 1, kFittedVolumeRel);
    test::expect_closed_outward_boundary(r.mesh);
    for (const Tet& t : r.mesh.tets)
        ASSERT_GT(signed_tet_volume(r.mesh.X[t[0]], r.mesh.X[t[1]], r.mesh.X[t[2]], r.mesh.X[t[3]]),
                  0);
    // inside the ellipse, and on its rim in every 10-degree sector
    std::vector<int> rim_points(36, 0);
    for (const Vec3& x : r.mesh.X) {
        const double u = x.x() / a, v = x.z() / b, radius2 = u * u + v * v;
        ASSERT_LE(radius2, 1 + 1e-9) << x.transpose();
        if (radius2 > 0.99) {
            const double degrees = std::atan2(v, u) * 180 / kPi + 180;
            ++rim_points[std::min(35, static_cast<int>(degrees / 10))];
        }
    }
    for (int sector = 0; sector < 36; ++sector)
        EXPECT_GT(rim_points[sector], 0) << "no rim point " << 10 * sector << " degrees round";
    // a cylinder's rims and sides add no axis: about the box's share (4 %)
    EXPECT_LT(axis_aligned_edge_share(r.mesh, 5), 0.15);
    const InitResult again = build_init(p, h);
    EXPECT_EQ(again.mesh.X, r.mesh.X);
    EXPECT_EQ(again.mesh.tets, r.mesh.tets);
}

// A heightfield with lattice "mesh" is Mesh_3's fill of the terrain's closed surface: the top
// sampled on the columns, the bottom flat at y = 0, the footprint's corners exact, and edges that
// run every way where the columns' run in rows along x and z and up each column
TEST(InitHeightfieldSource, MeshLatticeFillsTheTerrainWithMesh3TetsAlongNoAxis) {
    InitParams p;
    p.type = SourceType::Heightfield;
    p.heightfield.size = Vec3(1.2, 0, 1.2);
    p.heightfield.spacing = 0.025;
    p.heightfield.lattice = HeightfieldLattice::Mesh;
    const Real h = 0.1;

    // the surface: closed and outward (check_input_surface refuses anything else), enclosing
    // what the columns enclose (the same tops, triangulated alike or not)
    const InputSurface surface = heightfield_surface(p.heightfield);
    const double surface_volume = check_input_surface(surface, "heightfield");
    InitParams columns = p;
    columns.heightfield.lattice = HeightfieldLattice::Columns;
    const InitResult column_fill = build_init(columns, h);
    EXPECT_NEAR(surface_volume / column_fill.quality.tet_volume, 1.0, kHeightfieldVolumeRel);

    const InitResult r = build_init(p, h);
    EXPECT_NEAR(r.surface_volume, surface_volume, kBoxExactAbs);
    EXPECT_NEAR(r.quality.tet_volume / surface_volume, 1.0, kFittedVolumeRel);
    EXPECT_EQ(r.edge_length, default_edge_length(h));
    EXPECT_NEAR(r.quality.bbox_min.y(), 0.0, kBoxExactAbs);
    for (int d : {0, 2}) {
        EXPECT_NEAR(r.quality.bbox_min[d], -0.6, kBoxExactAbs);
        EXPECT_NEAR(r.quality.bbox_max[d], 0.6, kBoxExactAbs);
    }
    test::expect_closed_outward_boundary(r.mesh);
    for (const Tet& t : r.mesh.tets)
        ASSERT_GT(signed_tet_volume(r.mesh.X[t[0]], r.mesh.X[t[1]], r.mesh.X[t[2]], r.mesh.X[t[3]]),
                  0);
    // every point Mesh_3 put on the top lies on the terrain, and none lies higher above it than
    // the chords between the surface's samples do
    int on_top = 0;
    for (const Vec3& x : r.mesh.X) {
        const Real top = riverbed_height(p.heightfield, x.x(), x.z());
        EXPECT_LT(x.y(), top + kOnTerrainAbs);
        const bool on_wall = std::abs(std::abs(x.x()) - 0.6) < kBoxExactAbs ||
                             std::abs(std::abs(x.z()) - 0.6) < kBoxExactAbs;
        if (!on_wall && x.y() > top - kOnTerrainAbs) ++on_top;
    }
    EXPECT_GT(on_top, 100);

    const double mesh_share = axis_aligned_edge_share(r.mesh, 5);
    const double column_share = axis_aligned_edge_share(column_fill.mesh, 5);
    EXPECT_GT(column_share, 0.2);
    EXPECT_LT(mesh_share, 0.1) << "against the columns' " << column_share;
    std::printf("edge length within 5 degrees of the axes: mesh %.3f, columns %.3f\n", mesh_share,
                column_share);
}

TEST(InitMeshSource, LoadedSurfaceIsScaledTranslatedAndSetOnTheGround) {
    const fs::path file = write_cube_off("cube");
    MeshSource src;
    src.path = file.string();
    src.scale = 2;
    src.translate = Vec3(1, 5, 0);
    src.fit_to_ground = true;
    const InputSurface s = load_placed_surface(src);
    fs::remove(file);
    Vec3 lo = s.positions[0], hi = lo;
    for (const Vec3& p : s.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    EXPECT_NEAR((lo - Vec3(1, 0, 0)).norm(), 0, tol::kRoundoff);
    EXPECT_NEAR((hi - Vec3(3, 2, 2)).norm(), 0, tol::kRoundoff);
    EXPECT_NEAR(check_input_surface(s, src.path), 8.0, kBoxExactAbs);
}

TEST(InitMeshSource, BunnyAtDefaultSizingKeepsItsVolumeWithinTwoPercent) {
    const fs::path bunny = fs::path(MUDCRACK_SOURCE_DIR) / "shots/assets/bunny00.off";
    ASSERT_TRUE(fs::exists(bunny))
        << bunny << " is missing: run `make assets` in " << MUDCRACK_SOURCE_DIR
        << " (extracts it from Debian's libcgal-demo)";
    InitParams p;
    p.type = SourceType::Mesh;
    p.mesh.path = bunny.string();
    p.mesh.scale = 1;   // ~1 m tall
    p.edge_length = 0;  // default: 0.6 h
    const Real h = SimModel{}.h;
    const InitResult r = build_init(p, h);
    EXPECT_DOUBLE_EQ(r.edge_length, default_edge_length(h));
    ASSERT_GT(r.surface_volume, 0);
    EXPECT_NEAR(r.quality.tet_volume / r.surface_volume, 1.0, kFittedVolumeRel)
        << "tet volume " << r.quality.tet_volume << " vs surface " << r.surface_volume;
    test::expect_all_tets_positive(r.mesh);
    test::expect_volume_conserved(r.mesh, r.volume0);
    test::expect_closed_outward_boundary(r.mesh);
    test::expect_finite_boundary_uvs(r.mesh);
    EXPECT_NEAR(r.quality.bbox_min.y(), 0.0, kGroundFitAbs) << "fit_to_ground";
    EXPECT_GT(r.quality.min_dihedral_deg, 0.0);
}

}  // namespace
}  // namespace mudcrack
