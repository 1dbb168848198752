// mc-shot's command line, run as a user would (MuJoCo's compile_test.sh): exit codes, error
// lines on stderr, the key table, and slices rewritten only on change.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

struct Result {  // of one mc-shot run
    int code;
    std::string out, err;
};

std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

class McShotCli : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() /
                ("mudcrack_mc_shot_cli_" +
                 std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }

    // runs mc-shot with `args`, capturing stdout and stderr in files
    Result mc_shot(const std::string& args) const {
        const fs::path out = m_dir / "stdout.txt", err = m_dir / "stderr.txt";
        const std::string cmd = std::string(MUDCRACK_BIN_DIR) + "/mc-shot " + args + " >" +
                                out.string() + " 2>" + err.string();
        const int status = std::system(cmd.c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read(out), read(err)};
    }

    fs::path write(const std::string& name, const std::string& text) const {
        std::ofstream(m_dir / name) << text;
        return m_dir / name;
    }

    fs::path m_dir;
};

TEST_F(McShotCli, NoArgumentsIsBadUsage) { EXPECT_EQ(mc_shot("").code, 2); }

TEST_F(McShotCli, HelpAndVersionExitZero) {
    const Result help = mc_shot("--help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("validate"), std::string::npos) << help.out;
    const Result version = mc_shot("--version");
    EXPECT_EQ(version.code, 0);
    EXPECT_NE(version.out.find("mudcrack"), std::string::npos) << version.out;
    EXPECT_EQ(mc_shot("slice").code, 2);
    EXPECT_EQ(mc_shot("bogus").code, 2);
}

TEST_F(McShotCli, ValidateBadShotExitsOneNamingEveryKey) {
    const fs::path shot = write("bad.json", R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"youngs_modulus": -300000}, "sim": {"h": -1}})");
    const Result r = mc_shot("validate " + shot.string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("mc-shot: error: " + shot.string() +
                         ": /material/youngs_modulus = -300000: must be > 0 [Pa]"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("mc-shot: error: " + shot.string() + ": /sim/h = -1"), std::string::npos)
        << r.err;
    EXPECT_EQ(r.out.find("ok"), std::string::npos);
    EXPECT_EQ(mc_shot("validate " + (m_dir / "missing.json").string()).code, 1);
}

TEST_F(McShotCli, ValidateGoodShotPrintsOk) {
    const std::string demo = std::string(MUDCRACK_SOURCE_DIR) + "/shots/demo.json";
    const Result r = mc_shot("validate " + demo);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.rfind("ok: " + demo + "\n", 0), 0u) << r.out;
    EXPECT_NE(r.out.find("moisture on"), std::string::npos) << r.out;
}

TEST_F(McShotCli, KeysListsTheSpec) {
    const Result r = mc_shot("keys");
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.out.find("/material/youngs_modulus"), std::string::npos);
    EXPECT_NE(r.out.find("/surfacing/zeta"), std::string::npos);
}

TEST_F(McShotCli, StagesListsWhatTheShotTurnsOn) {
    const std::string shots = std::string(MUDCRACK_SOURCE_DIR) + "/shots/";
    EXPECT_EQ(mc_shot("stages " + shots + "demo.json").out, "init sim surface render\n");
    EXPECT_EQ(mc_shot("stages " + shots + "bench_nacc_cube.json").out, "init sim\n");
}

TEST_F(McShotCli, SummaryReadsTheManifests) {
    fs::create_directories(m_dir / "out" / "init");
    std::ofstream(m_dir / "out" / "init" / "manifest.json")
        << R"({"stage": "init", "wall_seconds": 1.25, "peak_memory_bytes": 10485760,
               "rates": {"particles_per_s": 4805}})";
    fs::create_directories(m_dir / "out" / "sim");
    std::ofstream(m_dir / "out" / "sim" / "manifest.json")
        << R"({"stage": "sim", "wall_seconds": 12.5, "frames": {"first": 1, "last": 48},
               "particle_steps_per_second": 2500000})";
    const Result r = mc_shot("summary " + (m_dir / "out").string());
    EXPECT_EQ(r.code, 0) << r.err;
    // a header, then one row per stage: frames, wall time, throughput, peak memory, outputs
    EXPECT_EQ(r.out.rfind("stage", 0), 0u) << r.out;
    EXPECT_NE(r.out.find("throughput"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("4805 particles/s"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("10.0  1 files"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("1-48"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("12.50"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("2.5e+06 particle-steps/s"), std::string::npos) << r.out;
    EXPECT_EQ(mc_shot("summary " + (m_dir / "empty").string()).code, 1);
    EXPECT_EQ(mc_shot("summary --json " + (m_dir / "empty").string()).code, 1);
}

TEST_F(McShotCli, SummaryAsJsonHasTheTablesNumbers) {
    fs::create_directories(m_dir / "out" / "sim");
    std::ofstream(m_dir / "out" / "sim" / "manifest.json")
        << R"({"stage": "sim", "shot": "shots/fig8_c.json", "wall_seconds": 12.5, "peak_memory_bytes": 20971520,
               "frames": {"first": 1, "last": 48}, "particle_steps_per_second": 2500000})";
    // a manifest written before the key was renamed
    fs::create_directories(m_dir / "out" / "render");
    std::ofstream(m_dir / "out" / "render" / "manifest.json")
        << R"({"stage": "render", "wall_seconds": 3, "peak_rss_bytes": 1048576})";
    const Result r = mc_shot("summary --json " + (m_dir / "out").string());
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json doc = nlohmann::json::parse(r.out);
    ASSERT_EQ(doc.at("stages").size(), 2u) << r.out;  // the stages that ran, in run order
    const nlohmann::json& sim = doc["stages"][0];
    EXPECT_EQ(sim.at("stage"), "sim");
    EXPECT_EQ(sim.at("shot"), "shots/fig8_c.json");
    EXPECT_EQ(sim.at("frames"), (nlohmann::json{{"first", 1}, {"last", 48}}));
    EXPECT_DOUBLE_EQ(sim.at("wall_seconds").get<double>(), 12.5);
    EXPECT_DOUBLE_EQ(sim.at("peak_memory_bytes").get<double>(), 20971520);
    EXPECT_DOUBLE_EQ(sim.at("throughput").at("value").get<double>(), 2.5e6);
    EXPECT_EQ(sim.at("throughput").at("unit"), "particle-steps/s");
    EXPECT_EQ(sim.at("files"), 1);
    EXPECT_TRUE(sim.at("resumed_from_frame").is_null());
    const nlohmann::json& render = doc["stages"][1];
    EXPECT_EQ(render.at("stage"), "render");
    EXPECT_TRUE(render.at("shot").is_null());
    EXPECT_TRUE(render.at("frames").is_null());
    EXPECT_TRUE(render.at("throughput").at("value").is_null());
    EXPECT_DOUBLE_EQ(render.at("peak_memory_bytes").get<double>(), 1048576);
}

// A sim resumed from a checkpoint timed only the frames after it: both forms say so.
TEST_F(McShotCli, SummaryNamesTheFrameASimResumedFrom) {
    fs::create_directories(m_dir / "out" / "sim");
    std::ofstream(m_dir / "out" / "sim" / "manifest.json")
        << R"({"stage": "sim", "wall_seconds": 5.3, "frames": {"first": 1, "last": 96}, "resumed_from_frame": 90})";
    const Result table = mc_shot("summary " + (m_dir / "out").string());
    ASSERT_EQ(table.code, 0) << table.err;
    EXPECT_NE(table.out.find("1-96 from 90"), std::string::npos) << table.out;
    const Result json = mc_shot("summary --json " + (m_dir / "out").string());
    ASSERT_EQ(json.code, 0) << json.err;
    EXPECT_EQ(nlohmann::json::parse(json.out).at("stages")[0].at("resumed_from_frame"), 90)
        << json.out;
}

TEST_F(McShotCli, SliceIsRewrittenOnlyWhenItChanges) {
    const std::string base = R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "render": {"resolution": [%d, 360]}})";
    char text[256];
    std::snprintf(text, sizeof text, base.c_str(), 640);
    const fs::path shot = write("s.json", text);
    const fs::path sim = m_dir / "out" / "sim.params.json",
                   render = m_dir / "out" / "render.params.json";
    ASSERT_EQ(mc_shot("slice " + shot.string() + " sim --out " + sim.string()).code, 0);
    ASSERT_EQ(mc_shot("slice " + shot.string() + " render --out " + render.string()).code, 0);
    const Result printed = mc_shot("slice " + shot.string() + " sim");
    EXPECT_EQ(printed.out, read(sim));
    EXPECT_NE(read(sim).find("\"youngs_modulus\": 2000.0"), std::string::npos);

    // push both mtimes into the past, then edit only the render section
    const auto past = fs::file_time_type::clock::now() - std::chrono::hours(1);
    fs::last_write_time(sim, past);
    fs::last_write_time(render, past);
    std::snprintf(text, sizeof text, base.c_str(), 1280);
    write("s.json", text);
    ASSERT_EQ(mc_shot("slice " + shot.string() + " sim --out " + sim.string()).code, 0);
    ASSERT_EQ(mc_shot("slice " + shot.string() + " render --out " + render.string()).code, 0);
    EXPECT_EQ(fs::last_write_time(sim), past);
    EXPECT_NE(fs::last_write_time(render), past);
    EXPECT_NE(read(render).find("1280"), std::string::npos);
    EXPECT_EQ(mc_shot("slice " + shot.string() + " paint").code, 2);
}

}  // namespace
