// The paper's claims about its figures, as numbers, on the shipped shots:
// - Fig. 8: NACC alone (fig8_b, eps = 0) shrinks without a horizontal crack, while the full model
//   (fig8_c, eps = 1) peels and curls; without porous shrinkage (fig8_a, eta = 0) nothing compacts
//   or curls.
// - Fig. 6: the larger the hardening rate eps, the more the soil curls and the larger its pieces.
// - Fig. 7: the mossy ground cracks into a network of polygons and curls.
// - Fig. 9: the hardening colormap of fig8_c's cache shows both halves, hardened and softened soil.
// - Fig. 10: on one cache, the moisture-aware edge-stretch criterion breaks more edges than Wang
//   et al. 2019's constant one.
// - The demo: a crack network that wanders (not along the grid) and peels.
// Each on one seed; tools/seed_study.sh holds "another seed draws another network of the same
// statistics".
// Fig. 7 and Fig. 8 run the shots as shipped (70K particles, 1.5 s; 31K particles, 2 s). Fig. 6's
// shots are 233K particles, too big for `make test`, so it runs a 1.2 m patch of each (same
// physics, same resolution, only the slab's extent differs) and checks the trend on those. A
// smaller patch's edges weigh more than the slab's: on the turned grid the shots run on, a 0.5 m
// patch of eps 0.5 hardly cracks (248 broken edges) while the whole slab cracks into a network;
// with the strength field the fig6 shots carry since 2026-11-29, a 1 m patch of eps 0.5 curls
// less than eps 0.2's (3.36 against 3.74 mm) where the whole slabs curl 4.8 and 3.6 mm. The 1.2 m
// patches hold every claim (docs/physics.md §6.5 has the rows): the case took 498 s of a fresh
// clone's ctest on a Zen 5 (711 s on the 1.4 m patches it ran until 2026-12-02). Their thinnest
// margin is the lift from eps 0.2 to 0.5: 0 and 0.07 % of the footprint (1.4 m: 0 and 2.2 %).
// Measures are mc-measure's (pipeline/measure/shape_measures.h): curl = 95th percentile minus
// median of the top surface's rise; split = share of columns with a horizontal gap; surface
// polygons = pieces of the top layer between cracks (mesh_: as the plates mode's meshes cut it).
// Every claim is on a shot's last frame, so the sim runs every frame and mc-surface and mc-measure
// only the last one: a frame's meshes do not depend on the frames surfaced before it (mc-surface
// scans every cached frame for the break history whatever --frames says; tests/surfacing's
// Plates.AFrameIsTheSameWhateverWasSurfacedBefore and McSurfaceCli's frames-in-any-order tests
// hold it to that), and its measures are the same measured alone or with the others (2026-11-26:
// byte-identical meshes and identical measures on fig8_b, fig8_c and the demo, the demo and fig8_c
// again after the plates' shot-wide wall smoothing; every case prints the numbers it printed
// before). On the demo (2 threads) that is 2.7 s of surfacing instead of 24.4 s, and 1.4 s of
// measuring instead of 37.6 s.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Run every stage on 2 threads: results are bitwise reproducible for a fixed thread count, so
// the numbers below do not depend on the machine's core count. (ctest runs the two threads' shares
// of the work one after the other on one core, OMP_THREAD_LIMIT=1: the same bits; see
// tests/figures/CMakeLists.txt for why.)
constexpr int kThreads = 2;

// Shrinkage of the slab's top the eye reads on a 0.3 m slab: 4 mm (fig8_b sinks 7.9 mm).
constexpr double kVisibleShrinkage = 0.004;
// What counts as "no horizontal cracks": under 1 % of the columns split, the jitter of a few
// stray columns at a crack's edge, not a peeling layer (a peel splits tens of percent).
constexpr double kNoSplit = 0.01;
// Curl the eye reads as curling on a 1.2 m slab: 15 mm.
constexpr double kVisibleCurl = 0.015;
// A peeling crust: at least 10 % of the columns split by a horizontal crack whose median height is
// at least 2 cells above the ground (the ground's nodes hold the bottom 1.5 cells: a gap there is
// lift-off, which mc-measure counts apart), with at most 2 % of the footprint lifted off.
constexpr double kPeel = 0.10;
constexpr double kPeelAboveGroundCells = 2.0;
constexpr double kMaxLiftOff = 0.02;
// Fig. 9 colours fig8_c's cache by each particle's hardening state (blue below alpha0, red above;
// shots/fig9.json reuses fig8_c's sim). Both halves show when at least half of the surface
// particles are hardened and at least 5 % softened: the dried crust, and the stretched crack walls
// and peeled undersides (86.1 and 13.8 %, `mc-measure` on fig9, 2026-11-27). fig8_b's cache,
// without the saturation hardening, is 0 % hardened and 68.9 % softened, and fig8_a's, without
// shrinkage, 0.1 and 0 % (docs/gallery.md): either fails it.
constexpr double kFig9Hardened = 0.50;
constexpr double kFig9Softened = 0.05;
// Fig. 10: "our surfacing shows more cracks", in the dry areas. On fig10_ours' whole cache, 96,925
// broken edges against 18,044 with Wang et al. 2019's criterion (2026-11-28); on the test's 2.4 m
// patch 22,536 against 3,400 (2026-12-02; 56 s on one core of a Zen 5). Asked: at least twice as
// many, where the two criteria agree on wet soil and differ only by Eq. 14 where Jw < 1.
constexpr double kFig10MoreBrokenEdges = 2;
// The demo (a Fig. 6 mud that dries through in a round puddle, since 2026-11-29): a closed network
// of plates, as drying mud cracks. At least 6 effective plates with the largest holding at most
// 30 % of the top (issue 31's bar), both by the broken edges (the physics: every path across a
// crack crosses a broken edge) and as its plates meshes cut it (what renders), and at least 20
// polygons of 4 or more top particles. Seeds 1 / 2 / 3 (2 threads, 2026-11-30, the puddle filled
// by Mesh_3 and turned every 5 steps): 8.03, 11.87 and 7.87 effective plates by the broken edges
// (the largest 22.7, 12.3 and 26.4 %), 14.2, 21.9 and 16.5 by the meshes, from 62, 79 and 79
// polygons (the jittered lattice turned every 20 steps, until then: 10.2, 10.8 and 13.1; 20.3,
// 19.7 and 23.8). Until Fig. 6's drying rates with a wet start replaced rates 1.8 times slower,
// the broken edges parted 1.38, 2.04 and 4.84 (the tops held over 4-7 % of the meshes' walls). A
// network that does not draw the grid: at most 40 % of its inland crack length within 15 degrees
// of the grid axes (issue 31's bar; 33 % is isotropic, the fixed grid draws 70-95 %: fig4_bunny
// 70.1, fig6 91-95 on a uniform slab): 33.3, 34.8 and 22.9 % on seeds 1-3 (the lattice: 22.4,
// 33.4 and 41.1). A network of a few dozen cracks is a small sample, so the bars test the claim
// on the shipped seed, not the bits; the other seeds are measured by mc-measure and reported in
// the README. And cracks that come across the shot: half of the last frame's broken edges by a
// frame between 35 and 65 % of the frame range (43, 43 and 46 % on seeds 1-3).
constexpr double kDemoEffectivePlates = 6;
constexpr double kDemoLargestPlate = 0.30;
constexpr int kDemoPolygons = 20;
constexpr double kDemoMaxAxisAligned = 0.40;
constexpr double kDemoPaceEarliest = 0.35;
constexpr double kDemoPaceLatest = 0.65;
// Fig. 6 at eps = 0.2 on a 1.2 m patch, turned as the shot: at most 50 % of its crack length
// along the grid axes (35.6 %, 2026-12-02; the 1.4 m patch 28.6 %; a 1 m patch of the uniform
// slab on the fixed grid: 96 %).
constexpr double kMaxAxisAligned = 0.50;
// The bar a close-up sets for the demo's plates: crack-wall roughness (the area-weighted mean angle
// between neighbouring crack triangles) at most 15 degrees (the peeling demo's 14.1 until
// 2026-11-29, 42.3 with `ours`; the Mesh_3 puddle's 10.5-10.9 on seeds 1-3, 2 threads, the
// lattice's 9.1-9.6).
constexpr double kDemoWallRoughnessDeg = 15;

// Fig. 7, the mossy ground with its strength field: at least 20 crack polygons and 3.5 effective
// plates (as shipped 24 and 3.90, seed 2 25 and 4.42, 2026-11-27; drying 2.5 times faster, as it
// did before, 38 and 5.16, seeds 2 and 3 42 and 35; the uniform layer 11 and 2.80, cut along grid
// lines), and rims that rise at least 8 mm on the 60 mm layer (12.2 and 10.6 mm).
constexpr int kFig7Polygons = 20;
// Fig. 6's eps 0.2 patch cuts its top into polygons (61 by its plates meshes on the 1.2 m patch,
// 2026-12-02; 94 on the 1.4 m patch; 34 on the 1 m patch of the uniform slab, 2026-11-27)
constexpr int kFig6Polygons = 10;
constexpr double kFig7EffectivePlates = 3.5;
constexpr double kFig7Curl = 0.008;
std::string slurp(const fs::path& p) {
    std::ifstream is(p);
    return std::string(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
}

class FigureClaims : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() /
                ("mudcrack_figures_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        std::error_code ec;
        if (!HasFailure()) fs::remove_all(m_dir, ec);
    }

    static json read_shot(const std::string& name) {
        const fs::path path = fs::path(MUDCRACK_SOURCE_DIR) / "shots" / (name + ".json");
        return json::parse(slurp(path), nullptr, /*allow_exceptions=*/true,
                           /*ignore_comments=*/true);
    }

    /// Writes `shot` into the scratch folder as NAME.json.
    fs::path write_shot(const std::string& name, json shot) const {
        shot["name"] = name;
        const fs::path path = m_dir / (name + ".json");
        std::ofstream(path) << shot.dump(2);
        return path;
    }

    /// The last frame of a shot written by write_shot: the frame every claim is on.
    static int last_frame(const fs::path& shot) {
        return json::parse(slurp(shot)).at("frames").at("end").get<int>();
    }

    /// Runs `program` (a stage binary) with `args`; false, with a test failure naming `shot` and
    /// the program's error output, when it fails.
    bool run_stage(const std::string& program, const std::string& args,
                   const fs::path& shot) const {
        const std::string cmd = std::string(MUDCRACK_BIN_DIR) + "/" + program + args + " >" +
                                (m_dir / "stdout.txt").string() + " 2>" +
                                (m_dir / "stderr.txt").string();
        const int status = std::system(cmd.c_str());
        if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
        ADD_FAILURE() << program << " failed on " << shot << ": " << slurp(m_dir / "stderr.txt");
        return false;
    }

    /// The folder the stages write `shot`'s outputs to.
    fs::path out_dir(const fs::path& shot) const { return m_dir / shot.stem(); }

    /// The flags every stage takes for `shot`: its file, its folder, kThreads, quiet.
    std::string stage_flags(const fs::path& shot) const {
        return " --shot " + shot.string() + " --out " + out_dir(shot).string() + " --threads " +
               std::to_string(kThreads) + " --quiet";
    }

    /// The flag that surfaces or measures only `shot`'s last frame.
    static std::string last_frame_only(const fs::path& shot) {
        return " --frames " + std::to_string(last_frame(shot));
    }

    /// Runs init and sim of `shot` into the scratch folder, then surfaces and measures its last
    /// frame; returns that frame's measures.
    json run_and_measure(const fs::path& shot) const {
        const fs::path table = out_dir(shot) / "measure.json";
        const std::string flags = stage_flags(shot);
        const std::string last_frame_only = FigureClaims::last_frame_only(shot);
        if (!run_stage("mc-init", flags, shot) || !run_stage("mc-sim", flags, shot) ||
            !run_stage("mc-surface", flags + last_frame_only, shot) ||
            !run_stage("mc-measure", flags + last_frame_only + " --json " + table.string(), shot))
            return json();
        const json whole = json::parse(slurp(table));
        json last = whole.at("frames").back();
        // the shot's pace (the surfacing's break history over every frame up to the last)
        if (whole.contains("pace")) last["pace"] = whole.at("pace");
        std::printf(
            "%-14s frame %d: curl %.2f mm, median rise %.2f mm, split %.2f %% (%.2f cells up), lifted %.2f %%, "
            "%lld broken edges, %d surface polygons (effective %.2f), weighted mean polygon %.4f m^2, "
            "axis-aligned %.1f %%\n",
            shot.stem().c_str(), last.at("frame").get<int>(), 1e3 * last.at("curl").get<double>(),
            1e3 * last.at("top_rise_median").get<double>(),
            100 * last.at("split_fraction").get<double>(),
            last.at("split_height_median_cells").get<double>(),
            100 * last.at("lifted_fraction").get<double>(),
            last.at("broken_edges").get<long long>(), last.at("surface_polygons").get<int>(),
            last.at("effective_surface_polygons").get<double>(),
            last.at("weighted_mean_polygon_area").get<double>(),
            100 * last.at("axis_aligned_fraction").get<double>());
        if (last.contains("mesh_surface_polygons"))
            std::printf(
                "%-14s as its plates meshes cut it: %d surface polygons (effective %.2f), "
                "weighted mean polygon %.4f m^2, axis-aligned %.1f %%\n",
                shot.stem().c_str(), last.at("mesh_surface_polygons").get<int>(),
                last.at("mesh_effective_surface_polygons").get<double>(),
                last.at("mesh_weighted_mean_polygon_area").get<double>(),
                100 * last.at("mesh_axis_aligned_fraction").get<double>());
        return last;
    }

    fs::path m_dir;
};

TEST_F(FigureClaims, Fig8NaccAloneShrinksWithoutPeelingWhileTheFullModelPeelsAndCurls) {
    const json a = run_and_measure(write_shot("fig8_a", read_shot("fig8_a")));
    const json b = run_and_measure(write_shot("fig8_b", read_shot("fig8_b")));
    const json c = run_and_measure(write_shot("fig8_c", read_shot("fig8_c")));
    ASSERT_FALSE(a.is_null() || b.is_null() || c.is_null());

    // (b) NACC merely: the slab shrinks, but no column splits horizontally. The paper's (b) also
    // cracks vertically into polygons; ours does not (docs/limitations.md: without the
    // saturation hardening the crust keeps Table 1's p0 = 0.04 kappa, yields in tension as it
    // dries and flows instead of storing the stress a crack needs), so that is not asserted.
    EXPECT_LT(b.at("top_rise_median").get<double>(), -kVisibleShrinkage);
    EXPECT_LT(b.at("split_fraction").get<double>(), kNoSplit);
    // (c) the full model peels: a horizontal crack under the crust, clear of the cells the
    // ground holds, with the slab still on its ground, and the rims curl up visibly, more than (b)
    EXPECT_GE(c.at("split_fraction").get<double>(), kPeel);
    EXPECT_GE(c.at("split_height_median_cells").get<double>(), kPeelAboveGroundCells);
    EXPECT_LE(c.at("lifted_fraction").get<double>(), kMaxLiftOff);
    EXPECT_GT(c.at("curl").get<double>(), kVisibleCurl);
    EXPECT_GT(c.at("curl").get<double>(), 1.2 * b.at("curl").get<double>());
    // (a) no porous shrinkage: the slab neither compacts nor curls
    EXPECT_GT(a.at("top_rise_median").get<double>(), -kVisibleShrinkage / 2);
    EXPECT_LT(a.at("curl").get<double>(), 0.2 * kVisibleCurl);
    EXPECT_EQ(a.at("broken_edges").get<long long>(), 0);
    // Fig. 9 is this cache in the hardening colormap: its measures are (c)'s
    ASSERT_EQ(read_shot("fig9").value("reuse", ""), "fig8_c");
    std::printf("fig9 (fig8_c's cache): %.1f %% of the surface hardened, %.1f %% softened\n",
                100 * c.at("surface_compressed_fraction").get<double>(),
                100 * c.at("surface_stretched_fraction").get<double>());
    EXPECT_GE(c.at("surface_compressed_fraction").get<double>(), kFig9Hardened);
    EXPECT_GE(c.at("surface_stretched_fraction").get<double>(), kFig9Softened);
}

TEST_F(FigureClaims, DemoCracksIntoAClosedNetworkOfPlatesAcrossTheShot) {
    // One seed. "Another seed draws another network of the same statistics" (polygon counts
    // within a factor 1.5, axis shares within 10 points) is held by tools/seed_study.sh, which
    // fails outside those bounds, run with the shots a physics change touches: a second demo run
    // here would take minutes of the CI's 45.
    const json one = run_and_measure(write_shot("demo", read_shot("demo")));
    ASSERT_FALSE(one.is_null());
    // the poster effect: a closed network of plates, by the broken edges and as the meshes cut it
    EXPECT_GE(one.at("effective_surface_polygons").get<double>(), kDemoEffectivePlates);
    EXPECT_LE(one.at("largest_polygon_fraction").get<double>(), kDemoLargestPlate);
    EXPECT_GE(one.at("mesh_effective_surface_polygons").get<double>(), kDemoEffectivePlates);
    EXPECT_LE(one.at("mesh_largest_polygon_fraction").get<double>(), kDemoLargestPlate);
    EXPECT_GE(one.at("surface_polygons").get<int>(), kDemoPolygons);
    // cracks that do not draw the grid
    EXPECT_LE(one.at("axis_aligned_fraction").get<double>(), kDemoMaxAxisAligned);
    // and that come across the shot, not in its first frames
    ASSERT_TRUE(one.contains("pace"));
    const double pace = one.at("pace").at("half_broken_range_fraction").get<double>();
    EXPECT_GE(pace, kDemoPaceEarliest);
    EXPECT_LE(pace, kDemoPaceLatest);
    // its plates meshes hold up in a close-up (docs/physics.md §5.7): no particle-sized chips,
    // every piece closed, smooth walls
    EXPECT_EQ(one.at("mesh_chips").get<int>(), 0);
    EXPECT_EQ(one.at("mesh_open_edges").get<long long>(), 0);
    EXPECT_LE(one.at("crack_wall_roughness_deg").get<double>(), kDemoWallRoughnessDeg);
}

TEST_F(FigureClaims, Fig7GroundCracksIntoPolygonsThatCurl) {
    // the whole shot: a 0.8 m patch does not do (its free edges take the shrinkage, and it lifts
    // off its base, 96-100 %, in 1-4 polygons). One seed, as the demo's case: tools/seed_study.sh
    // holds "another seed draws another network of the same statistics" (a second Fig. 7 run took
    // 254 of a ctest's 2,287 seconds on a Zen 3, 2026-11-28)
    const json m = run_and_measure(write_shot("fig7_mossy_ground", read_shot("fig7_mossy_ground")));
    ASSERT_FALSE(m.is_null());
    // cracks into a network of polygons, not a few plates cut along grid lines, and curls
    EXPECT_GE(m.at("surface_polygons").get<int>(), kFig7Polygons);
    EXPECT_GE(m.at("effective_surface_polygons").get<double>(), kFig7EffectivePlates);
    EXPECT_GT(m.at("curl").get<double>(), kFig7Curl);
}

TEST_F(FigureClaims, Fig6LargerHardeningRateCurlsMoreAndBreaksIntoLargerPieces) {
    json measured[3];
    const char* shots[3] = {"fig6_eps_0.2", "fig6_eps_0.5", "fig6_eps_1.0"};
    for (int i = 0; i < 3; ++i) {
        json shot = read_shot(shots[i]);
        shot["source"]["box"]["min"] = {-0.6, 0.0, -0.6};
        shot["source"]["box"]["max"] = {0.6, 0.05, 0.6};
        shot.erase("render");
        measured[i] = run_and_measure(write_shot(std::string(shots[i]) + "_patch", shot));
        ASSERT_FALSE(measured[i].is_null());
    }
    // curl: the top surface's curl and the share of the slab that lifts off its bed both grow
    for (int i = 1; i < 3; ++i) {
        SCOPED_TRACE(std::string(shots[i - 1]) + " vs " + shots[i]);
        EXPECT_GT(measured[i].at("curl").get<double>(), measured[i - 1].at("curl").get<double>());
        EXPECT_GT(measured[i].at("lifted_fraction").get<double>(),
                  measured[i - 1].at("lifted_fraction").get<double>());
        // pieces, as the plates' meshes cut the top: never smaller; and never more cracks
        EXPECT_GE(measured[i].at("mesh_weighted_mean_polygon_area").get<double>(),
                  measured[i - 1].at("mesh_weighted_mean_polygon_area").get<double>());
        EXPECT_LE(measured[i].at("broken_edges").get<long long>(),
                  measured[i - 1].at("broken_edges").get<long long>());
    }
    // eps = 0.2 breaks the top into polygons; eps = 1 leaves pieces at least twice their size
    EXPECT_GE(measured[0].at("mesh_surface_polygons").get<int>(), kFig6Polygons);
    EXPECT_GT(measured[2].at("mesh_weighted_mean_polygon_area").get<double>(),
              2 * measured[0].at("mesh_weighted_mean_polygon_area").get<double>());
    // and its cracks do not draw the grid (the fixed grid put 96 % of a 1 m patch's crack length
    // within 15 degrees of its axes, where an isotropic network has 33 %)
    EXPECT_LE(measured[0].at("axis_aligned_fraction").get<double>(), kMaxAxisAligned);
}

TEST_F(FigureClaims, Fig10OurCriterionBreaksMoreEdgesThanWang2019OnOneCache) {
    // A 2.4 m patch of fig10_ours' 4.74 m slab, a quarter of its footprint (same physics, same
    // resolution, as Fig. 6's patches): the whole shot is 150K particles over 36 frames. Its
    // cache is surfaced twice, with the shot's criterion (ours, Eq. 14) and with Wang et al.
    // 2019's constant threshold (fig10_wang2019 reuses fig10_ours' sim the same way).
    ASSERT_EQ(read_shot("fig10_wang2019").value("reuse", ""), "fig10_ours");
    json shot = read_shot("fig10_ours");
    ASSERT_EQ(shot.at("surfacing").at("mode"), "ours");
    shot["source"]["box"]["min"] = {-1.2, 0.0, -1.2};
    shot["source"]["box"]["max"] = {1.2, 0.15, 1.2};
    shot.erase("render");
    const fs::path path = write_shot("fig10_ours_patch", shot);
    const json ours = run_and_measure(path);
    ASSERT_FALSE(ours.is_null());
    // the surfacing's manifest: the mode it ran in and the broken edges at the last frame
    const fs::path surface_manifest = out_dir(path) / "surface" / "manifest.json";
    const json ours_manifest = json::parse(slurp(surface_manifest));
    const long long ours_broken =
        ours_manifest.at("per_frame").back().at("broken_edges").get<long long>();
    EXPECT_EQ(ours_broken, ours.at("broken_edges").get<long long>());  // mc-measure reads the same
    ASSERT_TRUE(run_stage("mc-surface",
                          stage_flags(path) + last_frame_only(path) + " --mode wang2019", path));
    const json manifest = json::parse(slurp(surface_manifest));
    ASSERT_EQ(manifest.at("mode"), "wang2019");
    const long long wang_broken =
        manifest.at("per_frame").back().at("broken_edges").get<long long>();
    std::printf("fig10 patch: %lld broken edges with ours, %lld with Wang et al. 2019\n",
                ours_broken, wang_broken);
    // the constant threshold breaks some edges too, so the comparison means something
    EXPECT_GT(wang_broken, 0);
    EXPECT_GE(static_cast<double>(ours_broken), kFig10MoreBrokenEdges * wang_broken);
}

}  // namespace
