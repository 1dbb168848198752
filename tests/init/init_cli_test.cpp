// mc-init's command line (docs/architecture.md §10, MuJoCo's compile_test.sh): usage errors exit 2,
// --help exits 0, a bad shot or a bad mesh exits 1 naming the problem and leaves no output, and a
// tiny valid shot produces particles.vdb, tets.vtu and manifest.json.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/io/points_io.h"
#include "pipeline/io/tet_mesh_io.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
// a manifest number that is an exact lattice volume [m^3]
constexpr double kManifestExact = 1e-15;
constexpr double kMeshedVolumeAbs = 1e-6;  // Mesh_3's volume of a cube [m^3]

namespace fs = std::filesystem;

/// A per-test scratch folder, removed at the end.
class InitCli : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() /
                ("mudcrack_init_cli_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(m_dir, ec);
    }

    fs::path write(const std::string& name, const std::string& text) const {
        std::ofstream(m_dir / name) << text;
        return m_dir / name;
    }

    /// Runs mc-init with `args`; returns the exit code, stderr in m_stderr, stdout in m_stdout.
    int run(const std::string& args) { return run_with_env("", args); }

    /// Same, under `env_command` (e.g. "env A=1"), which prefixes the command line.
    int run_with_env(const std::string& env_command, const std::string& args) {
        const fs::path out = m_dir / "stdout.txt", err = m_dir / "stderr.txt";
        const std::string cmd = env_command + " " + std::string(MUDCRACK_BIN_DIR) + "/mc-init " +
                                args + " >" + out.string() + " 2>" + err.string();
        const int status = std::system(cmd.c_str());
        m_stdout = slurp(out);
        m_stderr = slurp(err);
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    static std::string slurp(const fs::path& p) {
        std::ifstream is(p);
        return std::string(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
    }

    /// Neither the stage folder nor its staging folder exists.
    void expect_no_output(const fs::path& out) const {
        EXPECT_FALSE(fs::exists(out / "init")) << out / "init";
        EXPECT_FALSE(fs::exists(out / ".init.partial")) << out / ".init.partial";
    }

    fs::path m_dir;
    std::string m_stdout, m_stderr;
};

constexpr const char* kTinyBox = R"({
  "mudcrack": 1,
  // a 0.2 x 0.1 x 0.2 slab on a 0.05 lattice: 5 x 3 x 5 particles, 4 x 2 x 4 x 6 tets
  "source": { "type": "box", "box": { "min": [0, 0, 0], "max": [0.2, 0.1, 0.2], "spacing": 0.05 } },
  "material": {}
})";

TEST_F(InitCli, NoArgumentsIsAUsageError) { EXPECT_EQ(run(""), 2) << m_stderr; }

TEST_F(InitCli, UnknownFlagIsAUsageError) {
    const fs::path shot = write("box.json", kTinyBox);
    EXPECT_EQ(run("--shot " + shot.string() + " --out " + (m_dir / "out").string() + " --bogus"),
              2);
}

TEST_F(InitCli, HelpExitsZeroAndListsTheCommonFlags) {
    EXPECT_EQ(run("--help"), 0);
    for (const char* flag : {"--shot", "--out", "--threads", "--quiet", "--version"})
        EXPECT_NE(m_stdout.find(flag), std::string::npos) << flag << " missing from:\n" << m_stdout;
}

TEST_F(InitCli, TinyBoxShotProducesParticlesTetsAndManifest) {
    const fs::path shot = write("box.json", kTinyBox), out = m_dir / "out";
    ASSERT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 0) << m_stderr;
    const fs::path dir = out / "init";
    for (const char* f : {"particles.vdb", "tets.vtu", "manifest.json"}) {
        ASSERT_TRUE(fs::exists(dir / f)) << f;
        EXPECT_GT(fs::file_size(dir / f), 0u) << f;
    }
    EXPECT_FALSE(fs::exists(out / ".init.partial"));

    const auto m = nlohmann::json::parse(slurp(dir / "manifest.json"));
    EXPECT_EQ(m.at("stage"), "init");
    EXPECT_EQ(m.at("source"), "box");
    EXPECT_EQ(m.at("counts").at("particles"), 5 * 3 * 5);
    EXPECT_EQ(m.at("counts").at("tets"), 6 * 4 * 2 * 4);
    EXPECT_NEAR(m.at("quality").at("tet_volume").get<double>(), 0.004, kManifestExact);
    EXPECT_FALSE(m.at("shot_slice_hash").get<std::string>().empty());
    EXPECT_GT(m.at("peak_memory_bytes").get<double>(), 0);

    const PointCloud points = read_points(dir / "particles.vdb");
    ASSERT_EQ(points.P.size(), 75u);
    const std::vector<float>* volume0 = points.find_float("volume0");
    ASSERT_NE(volume0, nullptr);
    EXPECT_NEAR(std::accumulate(volume0->begin(), volume0->end(), 0.0) / 0.004, 1.0, tol::kFloat);
    EXPECT_EQ(points.meta_string.at("mudcrack:stage"), "init");

    const TetMesh mesh = read_tet_mesh_vtu(dir / "tets.vtu");
    EXPECT_EQ(mesh.X.size(), 75u);
    EXPECT_EQ(mesh.tets.size(), 192u);
    EXPECT_EQ(mesh.boundary.size(), 2u * 2 * (4 * 2 + 4 * 4 + 2 * 4));
    EXPECT_EQ(mesh.boundary_uv.size(), mesh.boundary.size());

    EXPECT_NE(m_stdout.find("particles"), std::string::npos) << "summary table on stdout:\n"
                                                             << m_stdout;
}

TEST_F(InitCli, BadShotExitsOneNamingTheKeyAndLeavesNoOutput) {
    const fs::path shot = write("bad.json", R"({
      "mudcrack": 1,
      "source": { "type": "box", "box": { "spacing": -0.05 } },
      "material": {}
    })");
    const fs::path out = m_dir / "out";
    EXPECT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find("/source/box/spacing"), std::string::npos) << m_stderr;
    expect_no_output(out);
}

// the shared stage CLI (pipeline/cmd/stage_cli.cpp) through mc-init: idle OpenMP threads spin
// 1,000 times before they sleep unless the user chose otherwise; libgomp prints what it runs with
// (OMP_DISPLAY_ENV)
TEST_F(InitCli, OpenMpThreadsSpinBrieflyAtBarriersUnlessTheUserChoosesOtherwise) {
    auto openmp_settings = [&](const std::string& env) {
        EXPECT_EQ(
            run_with_env("env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT OMP_DISPLAY_ENV=verbose " + env,
                         "--version"),
            0)
            << m_stderr;
        return m_stderr;
    };
    // the default: re-executed once with GOMP_SPINCOUNT=1000 (libgomp's own is 300,000)
    const std::string by_default = openmp_settings("");
    EXPECT_NE(by_default.find("GOMP_SPINCOUNT = '1000'"), std::string::npos) << by_default;
    // the user's own setting, either variable, is kept
    const std::string passive = openmp_settings("OMP_WAIT_POLICY=passive");
    EXPECT_NE(passive.find("OMP_WAIT_POLICY = 'PASSIVE'"), std::string::npos) << passive;
    EXPECT_NE(passive.find("GOMP_SPINCOUNT = '0'"), std::string::npos) << passive;
    const std::string active = openmp_settings("OMP_WAIT_POLICY=active");
    EXPECT_NE(active.find("OMP_WAIT_POLICY = 'ACTIVE'"), std::string::npos) << active;
    EXPECT_EQ(active.find("GOMP_SPINCOUNT = '1000'"), std::string::npos) << active;
    const std::string spin = openmp_settings("GOMP_SPINCOUNT=12345");
    EXPECT_NE(spin.find("GOMP_SPINCOUNT = '12345'"), std::string::npos) << spin;
}

TEST_F(InitCli, QuietPrintsNothingOnSuccess) {
    const fs::path shot = write("box.json", kTinyBox), out = m_dir / "out";
    ASSERT_EQ(run("--quiet --shot " + shot.string() + " --out " + out.string()), 0) << m_stderr;
    EXPECT_TRUE(fs::exists(out / "init" / "manifest.json"));
    EXPECT_EQ(m_stdout, "") << "--quiet prints errors and warnings only";
    EXPECT_EQ(m_stderr, "");
}

// refused before any work, in the format of every other error: file, key, value, expectation
TEST_F(InitCli, TooManyParticlesNamesFileKeyAndAWholeCount) {
    const fs::path shot = write("huge.json", R"({
      "mudcrack": 1,
      "source": { "type": "box", "box": { "min": [0, 0, 0], "max": [1, 1, 1], "spacing": 0.001 } },
      "material": {}
    })");
    const fs::path out = m_dir / "out";
    EXPECT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 1);
    const std::string expected =
        "mc-init: error: " + shot.string() +
        ": /source/box/spacing = 0.001: gives 1003003001 particles; expected at most 50000000";
    EXPECT_NE(m_stderr.find(expected), std::string::npos) << m_stderr;
    EXPECT_EQ(m_stderr.find(".000000"), std::string::npos) << m_stderr;
    expect_no_output(out);
}

// the shot spec is the one place /sim/h is checked: mc-init reports it like any other key
TEST_F(InitCli, NonPositiveGridSpacingNamesFileKeyAndValue) {
    for (const char* h : {"0", "-0.05"}) {
        const fs::path shot = write("flat.json", std::string(R"({
          "mudcrack": 1, "source": { "type": "box" }, "material": {}, "sim": { "h": )") +
                                                     h + " } }");
        const fs::path out = m_dir / "out";
        EXPECT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 1) << h;
        const std::string expected =
            "mc-init: error: " + shot.string() + ": /sim/h = " + h + ": must be > 0 [m]";
        EXPECT_NE(m_stderr.find(expected), std::string::npos) << m_stderr;
        expect_no_output(out);
    }
}

TEST_F(InitCli, OpenMeshExitsOneNamingTheBorderEdgesAndLeavesNoOutput) {
    // a unit cube without its z = 0 side (two triangles): a square hole of 4 border edges
    write("open_cube.off", R"(OFF
8 10 0
0 0 0
1 0 0
0 1 0
1 1 0
0 0 1
1 0 1
0 1 1
1 1 1
3 4 5 7
3 4 7 6
3 0 1 5
3 0 5 4
3 2 6 7
3 2 7 3
3 0 4 6
3 0 6 2
3 1 3 7
3 1 7 5
)");
    const fs::path shot = write("mesh.json", R"({
      "mudcrack": 1,
      "source": { "type": "mesh", "mesh": { "path": "open_cube.off" } },
      "init": { "edge_length": 0.25 },
      "material": {}
    })");
    const fs::path out = m_dir / "out";
    EXPECT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find("open_cube.off"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("4 border edges"), std::string::npos) << m_stderr;
    expect_no_output(out);
}

TEST_F(InitCli, ClosedMeshShotIsTetrahedralized) {
    write("cube.obj",
          "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
          "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n");
    const fs::path shot = write("mesh.json", R"({
      "mudcrack": 1,
      "source": { "type": "mesh", "mesh": { "path": "cube.obj", "scale": 0.5 } },
      "init": { "edge_length": 0.1 },
      "material": {}
    })");
    const fs::path out = m_dir / "out";
    ASSERT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 0) << m_stderr;
    const auto m = nlohmann::json::parse(slurp(out / "init" / "manifest.json"));
    EXPECT_EQ(m.at("source"), "mesh");
    EXPECT_GT(m.at("counts").at("particles").get<int>(), 27);
    // sharp features are protected, so the cube keeps its volume
    EXPECT_NEAR(m.at("quality").at("tet_volume").get<double>(), 0.125, kMeshedVolumeAbs);
    EXPECT_NEAR(m.at("quality").at("surface_volume").get<double>(), 0.125, tol::kRoundoff);
    const TetMesh mesh = read_tet_mesh_vtu(out / "init" / "tets.vtu");
    EXPECT_EQ(static_cast<int>(mesh.X.size()), m.at("counts").at("particles").get<int>());
}

TEST_F(InitCli, MissingMeshFileExitsOne) {
    const fs::path shot = write("mesh.json", R"({
      "mudcrack": 1,
      "source": { "type": "mesh", "mesh": { "path": "no_such_mesh.obj" } },
      "material": {}
    })");
    const fs::path out = m_dir / "out";
    EXPECT_EQ(run("--shot " + shot.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find("no_such_mesh.obj"), std::string::npos) << m_stderr;
    expect_no_output(out);
}

}  // namespace
}  // namespace mudcrack
