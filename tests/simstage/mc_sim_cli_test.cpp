// mc-sim from the command line (MuJoCo's compile_test.sh style): runs the built mc-init and mc-sim
// on tiny inline shots and checks determinism, kill + --resume, failure handling, and that a
// moisture-less shot caches and allocates nothing for moisture.
#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/points_io.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace mudcrack;

namespace {

const fs::path kBin = MUDCRACK_BIN_DIR;

// a 0.2 x 0.1 x 0.2 m elastic block on a 0.025 m lattice (9 x 5 x 9 = 405 particles) dropped
// onto a sticky ground; `extra` is spliced into the top-level object
std::string block_shot(const std::string& frames, const std::string& extra = "",
                       double spacing = 0.025, double h = 0.05) {
    std::ostringstream os;
    os << R"({ "mudcrack": 1,
  "source": { "type": "box", "initial_velocity": [0.2, -0.5, 0.0],
              "box": { "min": [-0.1, 0.05, -0.1], "max": [0.1, 0.15, 0.1], "spacing": )"
       << spacing << R"( } },
  "material": { "density": 1, "youngs_modulus": 2000, "poisson_ratio": 0.35 },
  "plasticity": { "alpha0": -0.04, "beta": 1, "xi": 1, "M": 1.87 },
  "sim": { "h": )"
       << h << R"(, "checkpoint_every": 2 },
  "frames": )"
       << frames << R"(,
  "colliders": { "ground": { "height": 0, "mode": "sticky" } })"
       << extra << "\n}\n";
    return os.str();
}

class McSimCli : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() /
                ("mc_sim_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(m_dir);
    }

    fs::path write_shot(const std::string& name, const std::string& text) {
        const fs::path path = m_dir / (name + ".json");
        std::ofstream(path) << text;
        return path;
    }
    // runs `bin args`, stderr to a file; returns the exit code
    int run(const std::string& bin, const std::string& args) {
        const std::string cmd = (kBin / bin).string() + " " + args + " > /dev/null 2> " +
                                (m_dir / "stderr.txt").string();
        const int status = std::system(cmd.c_str());
        m_stderr = read_text(m_dir / "stderr.txt");
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    void init(const fs::path& shot, const fs::path& out) {
        ASSERT_EQ(run("mc-init", "--quiet --shot " + shot.string() + " --out " + out.string()), 0)
            << m_stderr;
    }
    static std::string read_text(const fs::path& path) {
        std::ifstream is(path, std::ios::binary);
        std::stringstream ss;
        ss << is.rdbuf();
        return ss.str();
    }
    static std::vector<fs::path> frame_files(const fs::path& sim_dir) {
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(sim_dir))
            if (e.path().extension() == ".vdb") files.push_back(e.path().filename());
        std::sort(files.begin(), files.end());
        return files;
    }
    // every frame cache of a and b exists in both and is byte-identical
    void expect_identical_caches(const fs::path& a, const fs::path& b, size_t expected_frames) {
        const std::vector<fs::path> files = frame_files(a);
        EXPECT_EQ(files.size(), expected_frames);
        EXPECT_EQ(files, frame_files(b));
        for (const fs::path& f : files) {
            const std::string x = read_text(a / f), y = read_text(b / f);
            EXPECT_FALSE(x.empty()) << f;
            EXPECT_TRUE(x == y) << f << " differs between " << a << " and " << b;
        }
    }

    fs::path m_dir;
    std::string m_stderr;
};

TEST_F(McSimCli, SameShotTwiceGivesByteIdenticalCaches) {
    // 3 short frames (~12 substeps each) on 2 threads: bitwise determinism is promised per
    // thread count, so test the parallel path; kept small for a loaded 2-core machine
    const fs::path shot =
        write_shot("twice", block_shot(R"({ "start": 1, "end": 3, "fps": 192 })"));
    const fs::path out_a = m_dir / "a", out_b = m_dir / "b";
    init(shot, out_a);
    init(shot, out_b);
    for (const fs::path& out : {out_a, out_b})
        ASSERT_EQ(run("mc-sim", "--threads 2 --shot " + shot.string() + " --out " + out.string()),
                  0)
            << m_stderr;
    expect_identical_caches(out_a / "sim", out_b / "sim", 3);

    // per-frame plain progress lines off a terminal; the manifest's numbers
    EXPECT_NE(m_stderr.find("frame 3/3"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("particle-steps/s"), std::string::npos) << m_stderr;
    EXPECT_EQ(m_stderr.find('\r'), std::string::npos);
    const nlohmann::json m = nlohmann::json::parse(read_text(out_a / "sim" / "manifest.json"));
    EXPECT_EQ(m["stage"], "sim");
    EXPECT_EQ(m["particles"], 405);
    EXPECT_EQ(m["frames"]["first"], 1);
    EXPECT_EQ(m["frames"]["last"], 3);
    EXPECT_GE(m["substeps"].get<int>(), 3);
    EXPECT_EQ(m["retries"], 0);
    EXPECT_GT(m["particle_steps_per_second"].get<double>(), 0);
    // the step loop's wall time by phase: each phase ran, and they sum to at most the loop's time
    double phase_sum = 0;
    for (const char* phase : {"bin", "p2g", "grid", "g2p"}) {
        EXPECT_GT(m.at("step_phase_seconds").at(phase).get<double>(), 0) << phase;
        phase_sum += m.at("step_phase_seconds").at(phase).get<double>();
    }
    EXPECT_LE(phase_sum, m["step_loop_seconds"].get<double>());
    EXPECT_GT(m["dt"]["min"].get<double>(), 0);
    EXPECT_LE(m["dt"]["min"].get<double>(), m["dt"]["max"].get<double>());
    EXPECT_GT(m["peak_memory_bytes"].get<double>(), 0);
    EXPECT_GT(m["bytes_per_particle"].get<double>(), 0);
    EXPECT_EQ(m["allocated"]["plasticity"], true);

    // frame metadata: frame, time = k / fps, substeps, stage
    const PointCloud frame3 = read_points(out_a / "sim" / "particles.0003.vdb");
    EXPECT_EQ(frame3.P.size(), 405u);
    EXPECT_EQ(frame3.meta_int.at("mudcrack:frame"), 3);
    EXPECT_EQ(frame3.meta_double.at("mudcrack:time"), 3.0 / 192);
    EXPECT_GE(frame3.meta_int.at("mudcrack:substeps"), 1);
    EXPECT_EQ(frame3.meta_string.at("mudcrack:stage"), "sim");
    EXPECT_EQ(frame3.meta_int.at("mudcrack:format_version"), kPointsFormatVersion);

    // --quiet silences the progress
    ASSERT_EQ(run("mc-sim", "--quiet --threads 1 --frames 1 --shot " + shot.string() + " --out " +
                                out_b.string()),
              0)
        << m_stderr;
    EXPECT_EQ(m_stderr.find("frame 1/1"), std::string::npos) << m_stderr;
    EXPECT_TRUE(fs::exists(out_b / "sim" / "particles.0001.vdb"));
}

TEST_F(McSimCli, KillThenResumeGivesByteIdenticalCaches) {
    // 2601 particles, h = 0.025: long enough per frame to be killed mid-run (about 0.1 s a frame
    // in the Release build; 6 frames, not 10, since under the sanitizers the test took 115 s)
    const fs::path shot =
        write_shot("kill", block_shot(R"({ "start": 1, "end": 6, "fps": 24 })", "", 0.0125, 0.025));
    const fs::path straight = m_dir / "straight", killed = m_dir / "killed";
    init(shot, straight);
    init(shot, killed);
    ASSERT_EQ(run("mc-sim",
                  "--quiet --threads 1 --shot " + shot.string() + " --out " + straight.string()),
              0)
        << m_stderr;

    // start, wait for frame 3's cache, SIGKILL
    const std::string bin = (kBin / "mc-sim").string(), shot_arg = shot.string(),
                      out_arg = killed.string();
    std::vector<const char*> argv = {bin.c_str(),      "--quiet", "--threads",     "1",    "--shot",
                                     shot_arg.c_str(), "--out",   out_arg.c_str(), nullptr};
    pid_t pid = 0;
    ASSERT_EQ(posix_spawn(&pid, bin.c_str(), nullptr, nullptr,
                          const_cast<char* const*>(argv.data()), environ),
              0);
    const fs::path frame3 = killed / "sim" / "particles.0003.vdb";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!fs::exists(frame3) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(fs::exists(frame3));
    ASSERT_TRUE(WIFSIGNALED(status)) << "mc-sim finished before it could be killed";
    EXPECT_FALSE(fs::exists(killed / "sim" / "manifest.json"));
    EXPECT_FALSE(fs::exists(killed / "sim" / "particles.0006.vdb"));

    ASSERT_EQ(
        run("mc-sim", "--resume --threads 1 --shot " + shot.string() + " --out " + killed.string()),
        0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("resuming from"), std::string::npos) << m_stderr;
    expect_identical_caches(straight / "sim", killed / "sim", 6);
    const nlohmann::json m = nlohmann::json::parse(read_text(killed / "sim" / "manifest.json"));
    EXPECT_TRUE(m["resumed_from_frame"].is_number()) << m.dump(2);
    // the resumed manifest counts every frame's substeps, as the uninterrupted one does
    const nlohmann::json ms = nlohmann::json::parse(read_text(straight / "sim" / "manifest.json"));
    EXPECT_EQ(m["substeps"], ms["substeps"]);
    // only the newest two checkpoints are kept: frames 4 and 6
    EXPECT_EQ(m["checkpoints"], nlohmann::json({"checkpoint.0004.bin", "checkpoint.0006.bin"}));
    EXPECT_FALSE(fs::exists(killed / "sim" / "checkpoint.0002.bin"));
}

TEST_F(McSimCli, UnstableShotStopsWithFrameAndParticle) {
    // a fixed dt the load check allows (below the elastic bound), but a block thrown at 1e300 m/s:
    // the deformation gradient overflows in the first substep
    const fs::path shot = write_shot(
        "unstable", block_shot(R"({ "start": 1, "end": 3, "fps": 96 })", "", 0.025, 0.05));
    std::string text = read_text(shot);
    text.replace(text.find("[0.2, -0.5, 0.0]"), 16, "[0.0, -1e300, 1e300]");
    text.replace(text.find("\"checkpoint_every\": 2"), 21, "\"checkpoint_every\": 2, \"dt\": 2e-4");
    std::ofstream(shot) << text;
    const fs::path out = m_dir / "out";
    init(shot, out);
    EXPECT_EQ(run("mc-sim", "--threads 1 --shot " + shot.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find("error: frame 1 substep 1"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("particle "), std::string::npos) << m_stderr;
    // either the velocity-CFL guard or the finite-ness check stops it, with a reason, once the
    // retries at half the dt each (each one logged) reach their floor
    EXPECT_TRUE(m_stderr.find("non-finite") != std::string::npos ||
                m_stderr.find("unstable") != std::string::npos)
        << m_stderr;
    EXPECT_NE(m_stderr.find("mc-sim: retry: frame 1 substep 1"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("halved 10 times"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out / "sim" / "manifest.json"));
    EXPECT_TRUE(frame_files(out / "sim").empty());
}

TEST_F(McSimCli, FailureKeepsEarlierFramesAndWritesNoManifest) {
    // a NaN injected at frame 3 (the testing aid): frames 1-2 stay, nothing after, no manifest
    const fs::path shot = write_shot("nan", block_shot(R"({ "start": 1, "end": 4, "fps": 96 })"));
    const fs::path out = m_dir / "out";
    init(shot, out);
    EXPECT_EQ(run("mc-sim", "--threads 1 --inject-nan-at-frame 3 --shot " + shot.string() +
                                " --out " + out.string()),
              1);
    EXPECT_NE(m_stderr.find("error: frame 3 substep 1"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("particle 0 "), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("frames 1-2 are kept"), std::string::npos) << m_stderr;
    EXPECT_EQ(frame_files(out / "sim"),
              (std::vector<fs::path>{"particles.0001.vdb", "particles.0002.vdb"}));
    EXPECT_FALSE(fs::exists(out / "sim" / "manifest.json"));
    // the kept frames are complete caches
    EXPECT_EQ(read_points(out / "sim" / "particles.0002.vdb").P.size(), 405u);
}

TEST_F(McSimCli, FrameRangeStartsFromTheShotsFirstFrame) {
    // --frames 3-3 simulates frames 1-2 without writing them, so frame 3 is the same bytes
    const fs::path shot =
        write_shot("range", block_shot(R"({ "start": 1, "end": 3, "fps": 192 })"));
    const fs::path full = m_dir / "full", part = m_dir / "part";
    init(shot, full);
    init(shot, part);
    ASSERT_EQ(
        run("mc-sim", "--quiet --threads 1 --shot " + shot.string() + " --out " + full.string()), 0)
        << m_stderr;
    ASSERT_EQ(run("mc-sim", "--quiet --threads 1 --frames 3 --shot " + shot.string() + " --out " +
                                part.string()),
              0)
        << m_stderr;
    EXPECT_EQ(frame_files(part / "sim"), std::vector<fs::path>{"particles.0003.vdb"});
    EXPECT_TRUE(read_text(full / "sim" / "particles.0003.vdb") ==
                read_text(part / "sim" / "particles.0003.vdb"));
    const nlohmann::json m = nlohmann::json::parse(read_text(part / "sim" / "manifest.json"));
    EXPECT_EQ(m["frames"]["first"], 3);
    EXPECT_EQ(m["frames"]["count"], 1);
}

TEST_F(McSimCli, MissingInitIsAClearError) {
    const fs::path shot =
        write_shot("noinit", block_shot(R"({ "start": 1, "end": 2, "fps": 96 })"));
    EXPECT_EQ(run("mc-sim", "--shot " + shot.string() + " --out " + (m_dir / "out").string()), 1);
    EXPECT_NE(m_stderr.find("run mc-init first"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(m_dir / "out" / "sim" / "manifest.json"));
}

TEST_F(McSimCli, StaleInitIsRefused) {
    const fs::path out = m_dir / "out";
    init(write_shot("stale", block_shot(R"({ "start": 1, "end": 2, "fps": 96 })")), out);
    // the same shot with a different lattice: the init outputs no longer match it
    const fs::path changed =
        write_shot("stale", block_shot(R"({ "start": 1, "end": 2, "fps": 96 })", "", 0.02));
    EXPECT_EQ(run("mc-sim", "--shot " + changed.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find("stale"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("mc-init"), std::string::npos) << m_stderr;
}

TEST_F(McSimCli, MoistureLessShotCachesAndAllocatesNoMoisture) {
    // with surfacing on, a moisture shot would cache saturation and Jw; this one has no moisture
    const fs::path shot = write_shot("dry", block_shot(R"({ "start": 1, "end": 2, "fps": 96 })",
                                                       R"(, "surfacing": { "mode": "ours" })"));
    const fs::path out = m_dir / "out";
    init(shot, out);
    ASSERT_EQ(
        run("mc-sim", "--quiet --threads 1 --shot " + shot.string() + " --out " + out.string()), 0)
        << m_stderr;
    const PointCloud frame = read_points(out / "sim" / "particles.0002.vdb");
    EXPECT_EQ(frame.find_float("theta"), nullptr);
    EXPECT_EQ(frame.find_float("saturation"), nullptr);
    EXPECT_EQ(frame.find_float("Jw"), nullptr);
    EXPECT_NE(frame.find_vec3("v"), nullptr);
    const nlohmann::json m = nlohmann::json::parse(read_text(out / "sim" / "manifest.json"));
    EXPECT_EQ(m["moisture"], false);
    EXPECT_EQ(m["allocated"]["moisture_grid"], false);
    EXPECT_EQ(m["allocated"]["theta"], false);
    EXPECT_EQ(m["cg_iterations"]["max"], 0);
    EXPECT_EQ(m["cg_iterations"]["mean_per_substep"], 0.0);
    EXPECT_EQ(m.at("step_phase_seconds").at("moisture"), 0.0);
    for (const auto& name : m["cached_attributes"]) {
        EXPECT_NE(name, "theta");
        EXPECT_NE(name, "saturation");
    }
}

// the block shot with its state kept in float (/sim/precision)
std::string float_shot(std::string text) {
    const std::string key = R"("checkpoint_every": 2)";
    const size_t at = text.find(key);
    EXPECT_NE(at, std::string::npos);
    return text.replace(at, key.size(), key + R"(, "precision": "float")");
}

// A float shot runs, says so in its manifest, holds fewer bytes per particle than the same shot
// in double, and resumes from its own checkpoint with the same bytes; a double run does not take
// its checkpoints.
TEST_F(McSimCli, FloatShotSavesMemoryAndResumesFromItsOwnCheckpoints) {
    const std::string frames = R"({ "start": 1, "end": 4, "fps": 192 })";
    const fs::path shot = write_shot("float", float_shot(block_shot(frames)));
    const fs::path double_shot = write_shot("double", block_shot(frames));
    const fs::path straight = m_dir / "straight", resumed = m_dir / "resumed",
                   in_double = m_dir / "double";
    init(shot, straight);
    init(shot, resumed);
    init(double_shot, in_double);
    const std::string args = "--quiet --threads 2 --shot ";
    ASSERT_EQ(run("mc-sim", args + shot.string() + " --out " + straight.string()), 0) << m_stderr;
    ASSERT_EQ(run("mc-sim", args + double_shot.string() + " --out " + in_double.string()), 0)
        << m_stderr;
    const nlohmann::json m = nlohmann::json::parse(read_text(straight / "sim" / "manifest.json"));
    const nlohmann::json md = nlohmann::json::parse(read_text(in_double / "sim" / "manifest.json"));
    EXPECT_EQ(m["precision"], "float");
    EXPECT_EQ(md["precision"], "double");
    EXPECT_LT(m["bytes_per_particle"].get<double>(), md["bytes_per_particle"].get<double>() - 150)
        << "x, v, C and Fe in float: 96 bytes fewer a particle in the state and as many in its "
           "rollback copy";

    // frames 1-2 and the frame-2 checkpoint, then --resume for frames 3-4
    ASSERT_EQ(run("mc-sim", args + shot.string() + " --out " + resumed.string() + " --frames 1-2"),
              0)
        << m_stderr;
    const std::string loud = "--threads 2 --shot ";  // "resuming from" is an info line
    ASSERT_EQ(run("mc-sim", "--resume " + loud + shot.string() + " --out " + resumed.string()), 0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("resuming from"), std::string::npos) << m_stderr;
    expect_identical_caches(straight / "sim", resumed / "sim", 4);

    // a float checkpoint is not a double run's: it skips it for its own older one
    fs::remove(in_double / "sim" / "manifest.json");
    fs::copy_file(straight / "sim" / "checkpoint.0004.bin",
                  in_double / "sim" / "checkpoint.0004.bin", fs::copy_options::overwrite_existing);
    ASSERT_EQ(
        run("mc-sim", "--resume " + loud + double_shot.string() + " --out " + in_double.string()),
        0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("checkpoint.0004.bin: precision = \"float\": this run keeps a "
                            "double state"),
              std::string::npos)
        << m_stderr;
    EXPECT_NE(
        m_stderr.find("resuming from " + (in_double / "sim" / "checkpoint.0002.bin").string()),
        std::string::npos)
        << m_stderr;
}

// float far from the origin: refused by key and value, before anything is written
TEST_F(McSimCli, FloatFarFromTheOriginIsRefusedByKeyAndLeavesNothing) {
    std::string text = float_shot(block_shot(R"({ "start": 1, "end": 2, "fps": 96 })"));
    const std::string box = R"("min": [-0.1, 0.05, -0.1], "max": [0.1, 0.15, 0.1])";
    const size_t at = text.find(box);
    ASSERT_NE(at, std::string::npos);
    text.replace(at, box.size(), R"("min": [4999.9, 0.05, -0.1], "max": [5000.1, 0.15, 0.1])");
    const fs::path shot = write_shot("far", text);
    const fs::path out = m_dir / "out";
    init(shot, out);
    EXPECT_EQ(run("mc-sim", "--shot " + shot.string() + " --out " + out.string()), 1);
    EXPECT_NE(m_stderr.find(shot.string() + ": /sim/precision = \"float\": the simulation box "
                                            "reaches"),
              std::string::npos)
        << m_stderr;
    EXPECT_NE(m_stderr.find("h = 0.05 m"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out / "sim"));
}

}  // namespace
