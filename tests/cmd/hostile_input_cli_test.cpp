// Hostile input to the stage binaries (the README's exit codes, docs/reliability.md and
// docs/architecture.md §5): every case
// ends in a clear refusal with the right exit code, a message naming the file, key or flag, and
// nothing left behind (no .partial folder, temporary file, lock file or new output folder).
// - Usage: bad --threads / --frames / --log-level values and unknown flags, for every stage:
//   exit 2, one "mc-<stage>: error:" line naming the flag.
// - Shot values inside their ranges that no run survives (a collapsed time step, h below OpenVDB's
//   voxel, a grid or lattice too large, a framebuffer OSMesa cannot allocate, a camera the
//   renderer cannot place, a movie rate ffmpeg cannot write, a number overflow):
//   exit 1 at load, naming the file and the key, before any output folder exists.
// - Non-finite input mesh vertices, named with their index.
// - A mesh body too thin for /sim/h, or a ground at its top or out of its reach: refused by mc-init
//   once it reads the mesh (and a ground edited since, by mc-sim), naming the mesh's extent.
// - One writer per folder: a lock held elsewhere refuses the stage, naming its holder; a lock
//   left by a dead writer is recovered; farm chunks share one.
// - A stage folder that is a symbolic link: refused by every stage, the link and its target kept.
// - Damaged files: a flipped byte anywhere in a sim cache, an init file, a mesh or an image stops
//   its reader naming the file and "damaged" (FlippedByte: 26 offsets across the whole of every
//   kind of file, 12 under AddressSanitizer, each export format, obj's material files and the
//   debris points included);
//   mc-sim --resume simulates a damaged frame again.
// - SIGTERM and SIGINT: the stage removes what it was writing and exits 128 + the signal.
// Shots are tiny edits of shots/fig8_a.json (75 particles, 3 frames; longer or finer where a run
// must be stopped midway).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const fs::path kBin = MUDCRACK_BIN_DIR;
const fs::path kSource = MUDCRACK_SOURCE_DIR;
const std::vector<std::string> kStages = {"init", "sim", "surface", "render", "measure"};

std::string read_text(const fs::path& path) {
    std::ifstream is(path, std::ios::binary);
    std::stringstream ss;
    ss << is.rdbuf();
    return ss.str();
}

// fig8_a cut down: a 0.2 x 0.1 x 0.2 m block at spacing 0.05 (75 particles), 3 frames, a
// 48 x 32 render with a 2-view turntable
json tiny_shot() {
    std::ifstream is(kSource / "shots/fig8_a.json");
    json shot = json::parse(is, nullptr, true, /*ignore_comments=*/true);
    shot["name"] = "hostile";
    shot["source"]["box"] = {
        {"min", {-0.1, 0.0, -0.1}}, {"max", {0.1, 0.1, 0.1}}, {"spacing", 0.05}};
    shot["frames"]["end"] = 3;
    shot["render"] = {{"resolution", {48, 32}}, {"turntable", {{"views", 2}}}};
    return shot;
}

struct Result {
    int code = -1;  // exit code, or 128 + the signal that ended it
    std::string err;
};

// a stage binary run in the background, stderr into a file
class Process {
public:
    Process(const std::string& program, const std::vector<std::string>& args,
            const fs::path& err_file)
        : m_err_file(err_file) {
        std::vector<std::string> all = {(kBin / program).string()};
        all.insert(all.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (std::string& a : all) argv.push_back(a.data());
        argv.push_back(nullptr);
        m_pid = ::fork();
        if (m_pid == 0) {
            const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            const int null = ::open("/dev/null", O_WRONLY);
            if (err < 0 || null < 0 || ::dup2(err, 2) < 0 || ::dup2(null, 1) < 0) ::_exit(126);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
    }
    pid_t pid() const { return m_pid; }
    void signal(int s) const { ::kill(m_pid, s); }
    Result wait() {
        int status = 0;
        while (::waitpid(m_pid, &status, 0) < 0 && errno == EINTR) {
        }
        Result r;
        r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        r.err = read_text(m_err_file);
        return r;
    }

private:
    pid_t m_pid = -1;
    fs::path m_err_file;
};

class HostileInput : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = std::string(info->test_suite_name()) + "_" + info->name();
        for (char& c : name)
            if (c == '/') c = '_';
        m_dir =
            fs::temp_directory_path() / ("mc_hostile_" + name + "_" + std::to_string(::getpid()));
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(m_dir);
    }

    fs::path write_shot(const json& shot, const std::string& name = "shot.json") {
        const fs::path path = m_dir / name;
        std::ofstream(path) << shot.dump(2);
        return path;
    }
    fs::path out() const { return m_dir / "out"; }
    // where write_shot writes by default
    fs::path shot_path() const { return m_dir / "shot.json"; }

    // --shot SHOT --out OUT, one thread unless `extra` says otherwise, then `extra`
    std::vector<std::string> stage_args(const fs::path& shot,
                                        const std::vector<std::string>& extra) const {
        std::vector<std::string> args = {"--shot", shot.string(), "--out", out().string()};
        if (std::find(extra.begin(), extra.end(), "--threads") == extra.end())
            args.insert(args.end(), {"--threads", "1"});
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    }
    Result run(const std::string& stage, const fs::path& shot,
               const std::vector<std::string>& extra = {}) {
        return Process("mc-" + stage, stage_args(shot, extra), m_dir / "stderr.txt").wait();
    }
    Process start(const std::string& stage, const fs::path& shot,
                  const std::vector<std::string>& extra = {}) {
        return Process("mc-" + stage, stage_args(shot, extra),
                       m_dir / ("stderr_" + stage + ".txt"));
    }

    // runs the stages before `stage` (they must succeed)
    void run_before(const std::string& stage, const fs::path& shot) {
        for (const std::string s : {"init", "sim", "surface"}) {
            if (s == stage) return;
            const Result r = run(s, shot);
            ASSERT_EQ(r.code, 0) << s << ": " << r.err;
        }
    }

    // no .partial folder, temporary or lock file anywhere under `dir`
    static void expect_no_debris(const fs::path& dir) {
        if (!fs::exists(dir)) return;
        for (const auto& e : fs::recursive_directory_iterator(dir)) {
            const std::string name = e.path().filename().string();
            EXPECT_EQ(name.find(".partial"), std::string::npos) << e.path();
            EXPECT_NE(e.path().extension(), ".tmp") << e.path();
            EXPECT_NE(e.path().extension(), ".lock") << e.path();
        }
    }
    // one error line, prefixed with the stage, holding every `needle`
    static void expect_error(const Result& r, const std::string& stage,
                             const std::vector<std::string>& needles) {
        EXPECT_NE(r.err.find("mc-" + stage + ": error: "), std::string::npos) << r.err;
        for (const std::string& n : needles)
            EXPECT_NE(r.err.find(n), std::string::npos) << "no \"" << n << "\" in\n" << r.err;
    }

    // mc-init refuses `shot` with exit 1, naming every needle, and leaves no init folder or
    // partial output; the result, for checks of the case's own
    Result expect_init_refused(const json& shot, const std::vector<std::string>& needles) {
        const Result r = run("init", write_shot(shot));
        EXPECT_EQ(r.code, 1) << r.err;
        expect_error(r, "init", needles);
        EXPECT_FALSE(fs::exists(out() / "init"));
        expect_no_debris(out());
        return r;
    }

    // a lock file an exclusive writer has recorded itself in
    static bool has_holder_record(const fs::path& lock) {
        std::error_code ec;
        return fs::file_size(lock, ec) > 0 && !ec;
    }

    // waits up to `seconds` for `ready`; false on timeout
    static bool wait_for(const std::function<bool()>& ready, double seconds) {
        const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (std::chrono::steady_clock::now() < end) {
            if (ready()) return true;
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        return false;
    }

    fs::path m_dir;
};

// ---- usage: every stage, every bad flag value: exit 2, "mc-<stage>: error:", the flag named -----

struct UsageCase {
    std::vector<std::string> args;
    std::string names;  // what the message must hold
};

const UsageCase kUsageCases[] = {
    {{"--threads", "-1"}, "--threads = -1: expected 0"},
    {{"--threads", "0x10"}, "--threads = \"0x10\""},
    {{"--threads", "100000"}, "--threads = 100000: more threads"},
    {{"--threads", "99999999999999999999"}, "--threads = \"99999999999999999999\""},
    {{"--frames", "3-"}, "--frames = \"3-\""},
    {{"--frames", "a-b"}, "--frames = \"a-b\""},
    {{"--frames", "5-2"}, "--frames = \"5-2\": expected 1 <= A <= B"},
    {{"--frames", "0"}, "--frames = \"0\""},
    {{"--frames", "99999999999"}, "--frames = \"99999999999\""},
    {{"--threads", ""}, "--threads = \"\""},
    {{"--frames", ""}, "--frames = \"\""},
    {{"--log-level", "loud"}, "--log-level"},
    {{"--no-such-flag"}, "--no-such-flag"},
};

class UsageErrors : public HostileInput,
                    public ::testing::WithParamInterface<std::tuple<std::string, int>> {};

TEST_P(UsageErrors, ExitTwoNamingTheFlag) {
    const auto& [stage, index] = GetParam();
    const UsageCase& c = kUsageCases[index];
    const fs::path shot = write_shot(tiny_shot());
    const Result r = run(stage, shot, c.args);
    EXPECT_EQ(r.code, 2) << r.err;
    expect_error(r, stage, {c.names});
    EXPECT_LT(r.err.size(), 600u) << "a long message (a 309-digit bound?):\n" << r.err;
    EXPECT_FALSE(fs::exists(out())) << "a usage error must write nothing";
}

INSTANTIATE_TEST_SUITE_P(AllStages, UsageErrors,
                         ::testing::Combine(::testing::ValuesIn(kStages),
                                            ::testing::Range(0, int(std::size(kUsageCases)))),
                         [](const auto& info) {
                             return std::get<0>(info.param) + "_" +
                                    std::to_string(std::get<1>(info.param));
                         });

// a stage's own flags: an empty value or one the stage refuses is a usage error too
struct StageFlagCase {
    std::string stage;
    std::vector<std::string> args;
    std::string names;
};
void PrintTo(const StageFlagCase& c, std::ostream* os) { *os << c.stage << " " << c.names; }

class StageFlags : public HostileInput, public ::testing::WithParamInterface<StageFlagCase> {};

TEST_P(StageFlags, ExitTwoNamingTheFlag) {
    const StageFlagCase& c = GetParam();
    const fs::path shot = write_shot(tiny_shot());
    run_before(c.stage, shot);
    const Result r = run(c.stage, shot, c.args);
    EXPECT_EQ(r.code, 2) << r.err;
    expect_error(r, c.stage, {c.names});
    EXPECT_FALSE(fs::exists(out() / c.stage)) << "a usage error must write nothing";
    EXPECT_FALSE(fs::exists(m_dir / "table.json"));
    expect_no_debris(out());
}

INSTANTIATE_TEST_SUITE_P(
    Stages, StageFlags,
    ::testing::Values(
        StageFlagCase{"surface", {"--format", ""}, "--format = \"\": expected a value"},
        StageFlagCase{"surface", {"--format", "fbx"}, "--format fbx: fbx is not supported"},
        StageFlagCase{"surface", {"--format", "stl"}, "--format stl: "},
        StageFlagCase{"measure", {"--json", ""}, "--json = \"\": expected a value"},
        StageFlagCase{"sim", {"--seed", ""}, "--seed = \"\": expected a value"},
        StageFlagCase{"render", {"--log-level", ""}, "--log-level"}),
    [](const auto& info) { return info.param.stage + "_" + std::to_string(info.index); });

TEST_F(HostileInput, MissingOutIsAUsageErrorWithThePrefix) {
    const fs::path shot = write_shot(tiny_shot());
    const Result r = Process("mc-sim", {"--shot", shot.string()}, m_dir / "err.txt").wait();
    EXPECT_EQ(r.code, 2);
    expect_error(r, "sim", {"--out"});
}

TEST_F(HostileInput, ShotToolUsageErrorsHaveThePrefix) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"validate"}, std::vector<std::string>{"no-such-command"}}) {
        const Result r = Process("mc-shot", args, m_dir / "err.txt").wait();
        EXPECT_EQ(r.code, 2) << r.err;
        expect_error(r, "shot", {"mc-shot --help"});
    }
}

TEST_F(HostileInput, ShotToolRefusesEmptyValues) {
    const fs::path shot = write_shot(tiny_shot());
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"slice", shot.string(), "sim", "--out", ""},
          std::vector<std::string>{"validate", ""}}) {
        const Result r = Process("mc-shot", args, m_dir / "err.txt").wait();
        EXPECT_EQ(r.code, 2) << r.err;
        expect_error(r, "shot", {"= \"\": expected a value"});
    }
}

TEST_F(HostileInput, ThreadsAboveTheCapNameTheCap) {
    const fs::path shot = write_shot(tiny_shot());
    const Result r = run("init", shot, {"--threads", "1000000"});
    EXPECT_EQ(r.code, 2);
    expect_error(r, "init", {"--threads = 1000000", "hardware threads"});
}

// ---- --frames against the shot's frames, in every per-frame stage -----------------------------

class FramesPastTheShot : public HostileInput, public ::testing::WithParamInterface<std::string> {};

// one check in every stage (mc-init included, though its output serves every frame): exit 2
// like any usage error, naming the flag, the frames there are and where they come from
TEST_P(FramesPastTheShot, RefusedAsAUsageError) {
    const std::string stage = GetParam();
    const fs::path shot = write_shot(tiny_shot());
    run_before(stage, shot);
    const fs::path where = stage == "init" || stage == "sim" ? shot
                           : stage == "render"               ? out() / "surface" / "manifest.json"
                                                             : out() / "sim" / "manifest.json";
    for (const std::string frames : {"99-100", "2-4", "3-9"}) {
        const Result r = run(stage, shot, {"--frames", frames});
        EXPECT_EQ(r.code, 2) << r.err;
        expect_error(r, stage,
                     {"--frames " + frames + ": outside the frames 1-3 of " + where.string()});
        EXPECT_FALSE(fs::exists(out() / stage)) << "nothing written";
        expect_no_debris(out());
    }
    // the shot's own frames are accepted
    const Result r = run(stage, shot, {"--frames", "1-3"});
    EXPECT_EQ(r.code, 0) << r.err;
}

INSTANTIATE_TEST_SUITE_P(EveryStage, FramesPastTheShot, ::testing::ValuesIn(kStages));

// mc-sim's hidden testing flag is checked like --frames: a frame the run does not simulate is a
// usage error, not a run that never fails
TEST_F(HostileInput, InjectedNanFrameOutsideTheRunIsAUsageError) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("sim", shot);
    const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
        {{"--inject-nan-at-frame", "4"},
         "--inject-nan-at-frame 4: outside the frames 1-3 this run simulates (" + shot.string() +
             " (/frames/start, /frames/end))"},
        {{"--inject-nan-at-frame", "999999999"},
         "--inject-nan-at-frame 999999999: outside the frames 1-3"},
        {{"--inject-nan-at-frame", "-1"}, "--inject-nan-at-frame -1: outside the frames 1-3"},
        {{"--frames", "1-2", "--inject-nan-at-frame", "3"},
         "--inject-nan-at-frame 3: outside the frames 1-2 this run simulates (--frames 1-2 of " +
             shot.string()},
        {{"--inject-nan-at-frame", "99999999999"},
         "--inject-nan-at-frame = \"99999999999\": expected a frame number"},
        {{"--inject-nan-at-frame", "3x"},
         "--inject-nan-at-frame = \"3x\": expected a frame number"},
        {{"--inject-nan-at-frame", ""}, "--inject-nan-at-frame = \"\": expected a value"},
    };
    for (const auto& [args, names] : cases) {
        const Result r = run("sim", shot, args);
        EXPECT_EQ(r.code, 2) << r.err;
        expect_error(r, "sim", {names});
        EXPECT_FALSE(fs::exists(out() / "sim")) << "nothing written";
        expect_no_debris(out());
    }
}

// the bounds are not the whole story: 0 (all cores) and the cap itself are accepted
TEST_F(HostileInput, ThreadsZeroAndTheCapAreAccepted) {
    const fs::path shot = write_shot(tiny_shot());
    const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
    for (const std::string& threads : {std::string("0"), std::to_string(4 * hardware)}) {
        const Result r = run("init", shot, {"--threads", threads});
        EXPECT_EQ(r.code, 0) << threads << ": " << r.err;
    }
    expect_no_debris(out());
}

// ---- shot values no run survives: exit 1 at load, file and key named, no output ----------------

struct ShotCase {
    std::string name;
    std::function<void(json&)> edit;
    std::string key;
};

const ShotCase kShotCases[] = {
    {"density_1e_300", [](json& s) { s["material"]["density"] = 1e-300; }, "/material/density"},
    {"youngs_modulus_1e300", [](json& s) { s["material"]["youngs_modulus"] = 1e300; },
     "/material/youngs_modulus"},
    {"dt_1e_300", [](json& s) { s["sim"]["dt"] = 1e-300; }, "/sim/dt"},
    {"dt_max_1e_300", [](json& s) { s["sim"]["dt_max"] = 1e-300; }, "/sim/dt_max"},
    {"fps_1e_300", [](json& s) { s["frames"]["fps"] = 1e-300; }, "/frames/fps"},
    {"initial_velocity_1e30",
     [](json& s) {
         s["source"]["initial_velocity"] = {1e30, 0, 0};
     },
     "/source/initial_velocity"},
    {"gravity_1e30",
     [](json& s) {
         s["sim"]["gravity"] = {0, -1e30, 0};
     },
     "/sim/gravity"},
    // a step mc-sim survives, but 3 million of them a frame
    {"poisson_ratio_just_under_half",
     [](json& s) { s["material"]["poisson_ratio"] = 0.4999999999; },
     "/material/poisson_ratio = 0.4999999999: gives a stable time step"},
    {"h_1e_5", [](json& s) { s["sim"]["h"] = 1e-5; }, "/sim/h"},
    {"h_1e_300", [](json& s) { s["sim"]["h"] = 1e-300; }, "/sim/h"},
    {"domain_too_large_for_h",
     [](json& s) {
         s["colliders"]["domain"] = {{"min", {-1e4, -1e4, -1e4}}, {"max", {1e4, 1e4, 1e4}}};
     },
     "/sim/h"},
    {"resolution_16384",
     [](json& s) {
         s["render"]["resolution"] = {16384, 16384};
     },
     "/render/resolution"},
    {"resolution_16384x8192",
     [](json& s) {
         s["render"]["resolution"] = {16384, 8192};
     },
     "/render/resolution"},
    {"samples_64_at_4k",
     [](json& s) {
         s["render"]["resolution"] = {4096, 2160};
         s["render"]["samples"] = 64;
     },
     "/render/resolution"},
    {"camera_on_its_target",
     [](json& s) {
         s["render"]["camera"] = {{"position", {1, 2, 3}}, {"target", {1, 2, 3}}};
     },
     "/render/camera/position = [1,2,3]: is on /render/camera/target"},
    {"camera_beyond_float",
     [](json& s) {
         s["render"]["camera"] = {{"position", {1e300, 0, 0}}};
     },
     "/render/camera/position"},
    {"target_beyond_float",
     [](json& s) {
         s["render"]["camera"] = {{"target", {0, -1e39, 0}}};
     },
     "/render/camera/target"},
    {"fov_1e_300",
     [](json& s) {
         s["render"]["camera"] = {{"fov", 1e-300}};
     },
     "/render/camera/fov"},
    {"render_fps_1e_300", [](json& s) { s["render"]["fps"] = 1e-300; }, "/render/fps"},
    {"render_fps_1e300", [](json& s) { s["render"]["fps"] = 1e300; }, "/render/fps"},
    // h against the body (0.2 x 0.1 x 0.2 m) and a given domain, and the domain's walls
    {"h_5_wider_than_the_body", [](json& s) { s["sim"]["h"] = 5; },
     "/sim/h = 5: is larger than the body (/source/box: 0.2 x 0.1 x 0.2 m)"},
    {"h_5_wider_than_a_box_filled_by_mesh3",
     [](json& s) {
         s["source"]["box"]["lattice"] = "mesh";
         s["sim"]["h"] = 5;
     },
     "/sim/h = 5: is larger than the body (/source/box: 0.2 x 0.1 x 0.2 m)"},
    {"h_larger_than_the_domain",
     [](json& s) {
         s["colliders"]["domain"] = {{"min", {-0.15, -0.05, -0.15}}, {"max", {0.15, 0.15, 0.15}}};
         s["sim"]["h"] = 0.25;
     },
     "/sim/h = 0.25: is larger than the domain"},
    {"padding_fills_the_domain",
     [](json& s) {
         s["colliders"]["domain"] = {
             {"min", {-0.15, -0.05, -0.15}}, {"max", {0.15, 0.15, 0.15}}, {"padding", 2}};
     },
     "/colliders/domain/padding = 2: walls of 2 cells"},
    // a lattice whose count overflows on one axis only needs the others thinner than any cell
    // (h >= 1e-4 m): refused at load by h against the body, before mc-init counts it
    {"box_overflowing_one_axis",
     [](json& s) {
         s["source"]["box"] = {
             {"min", {0, 0, 0}}, {"max", {1e-299, 1e-299, 1}}, {"spacing", 1e-300}};
     },
     "/sim/h = 0.05: is larger than the body (/source/box: 1e-299 x 1e-299 x 1 m)"},
    {"heightfield_overflowing_layers",
     [](json& s) {
         s["source"] = {{"type", "heightfield"},
                        {"heightfield",
                         {{"size", {1e-299, 1e-299}}, {"channel_depth", 0}, {"spacing", 1e-300}}}};
     },
     "/sim/h = 0.05: is larger than the body (/source/heightfield: 1e-299 x 0.35 x 1e-299 m)"},
    // a ground far above or below the body (bottom y = 0, top 0.1, 3 frames of falling)
    {"ground_1e300", [](json& s) { s["colliders"]["ground"]["height"] = 1e300; },
     "/colliders/ground/height = 1e+300: is at or above the top of the body, y = 0.1"},
    {"ground_on_the_top", [](json& s) { s["colliders"]["ground"]["height"] = 0.1; },
     "/colliders/ground/height = 0.1: is at or above the top of the body"},
    {"ground_minus_1e300", [](json& s) { s["colliders"]["ground"]["height"] = -1e300; },
     "/colliders/ground/height = -1e+300: is 1e+300 m below the body's bottom y = 0"},
    {"ground_out_of_reach", [](json& s) { s["colliders"]["ground"]["height"] = -10; },
     "/colliders/ground/height = -10: is 10 m below the body's bottom y = 0 (/source/box), which moves at most"},
    // frame names hold four digits (name.####.ext); an int holds the rest of the integers
    {"frames_end_1e9", [](json& s) { s["frames"]["end"] = 1000000000; },
     "/frames/end = 1000000000: must be in [1, 9999]"},
    {"frames_end_10000", [](json& s) { s["frames"]["end"] = 10000; },
     "/frames/end = 10000: must be in [1, 9999]"},
    {"frames_end_beyond_int", [](json& s) { s["frames"]["end"] = 100000000000LL; },
     "/frames/end = 100000000000"},
    {"padding_beyond_int",
     [](json& s) {
         s["colliders"]["domain"] = {
             {"min", {-1, -1, -1}}, {"max", {1, 1, 1}}, {"padding", 1000000000000LL}};
     },
     "/colliders/domain/padding = 1000000000000: must be <= 2147483647"},
};

// a number too large for a double, written into the shot's text
struct OverflowCase {
    std::string name, from, to, key;
};
const OverflowCase kOverflowCases[] = {
    {"density", "\"density\": 1,", "\"density\": 1e400,", "/material/density"},
    {"negative_youngs", "\"youngs_modulus\": 2000", "\"youngs_modulus\": -1e400",
     "/material/youngs_modulus"},
    {"array_element", "\"h\": 0.05", "\"h\": 0.05, \"gravity\": [0, -1e999, 0]", "/sim/gravity/1"},
    {"fps", "\"fps\": 24", "\"fps\": 24e500", "/frames/fps"},
};

class ShotValues : public HostileInput,
                   public ::testing::WithParamInterface<std::tuple<std::string, int>> {};

TEST_P(ShotValues, RefusedAtLoadNamingTheKey) {
    const auto& [stage, index] = GetParam();
    const ShotCase& c = kShotCases[index];
    json shot = tiny_shot();
    c.edit(shot);
    const fs::path path = write_shot(shot);
    const Result r = run(stage, path);
    EXPECT_EQ(r.code, 1) << r.err;
    expect_error(r, stage, {path.string() + ": " + c.key});
    EXPECT_EQ(r.err.find("unexpected failure"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out())) << "refused at load: no output folder";
}

INSTANTIATE_TEST_SUITE_P(InitSimAndRender, ShotValues,
                         ::testing::Combine(::testing::Values("init", "sim", "render"),
                                            ::testing::Range(0, int(std::size(kShotCases)))),
                         [](const auto& info) {
                             return std::get<0>(info.param) + "_" +
                                    kShotCases[std::get<1>(info.param)].name;
                         });

// a lattice that fits mc-init's own limit (5e7 particles) but not this machine's memory, at the
// loader's estimate of 1 KiB a particle
TEST_F(HostileInput, LatticeBeyondMemoryNamesTheSpacing) {
    const double memory = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGE_SIZE));
    const double particles = 1.5 * memory / 1024;
    if (particles > 4.9e7) GTEST_SKIP() << "this machine's memory holds mc-init's largest lattice";
    const double side = std::cbrt(particles) * 0.01;
    json s = tiny_shot();
    s["source"]["box"] = {{"min", {0, 0, 0}}, {"max", {side, side, side}}, {"spacing", 0.01}};
    const fs::path path = write_shot(s);
    for (const std::string stage : {"init", "sim"}) {
        const Result r = run(stage, path);
        EXPECT_EQ(r.code, 1) << r.err;
        expect_error(r, stage, {path.string() + ": /source/box/spacing", "GiB"});
        EXPECT_FALSE(fs::exists(out()));
    }
}

// a spacing so far below the extent that the lattice's cells overflow an int: refused by its
// count, not wrapped into a lattice of a few particles
struct SpacingCase {
    std::string name;
    std::function<void(json&)> edit;
    std::string key;
};
const SpacingCase kSpacingCases[] = {
    {"box", [](json& s) { s["source"]["box"]["spacing"] = 1e-300; },
     "/source/box/spacing = 1e-300: gives inf"},
    {"heightfield_columns",
     [](json& s) {
         s["source"] = {{"type", "heightfield"}, {"heightfield", {{"spacing", 1e-300}}}};
     },
     "/source/heightfield/spacing = 1e-300: gives inf columns"},
};

class LatticeSpacing : public HostileInput, public ::testing::WithParamInterface<int> {};

TEST_P(LatticeSpacing, BeyondAnIntIsRefusedByItsCount) {
    const SpacingCase& c = kSpacingCases[GetParam()];
    json shot = tiny_shot();
    c.edit(shot);
    expect_init_refused(shot, {shot_path().string() + ": " + c.key, "expected at most 50000000"});
}

INSTANTIATE_TEST_SUITE_P(Init, LatticeSpacing, ::testing::Range(0, int(std::size(kSpacingCases))),
                         [](const auto& info) { return kSpacingCases[info.param].name; });

class NumberOverflow : public HostileInput, public ::testing::WithParamInterface<int> {};

TEST_P(NumberOverflow, NamesTheFileAndTheKey) {
    const OverflowCase& c = kOverflowCases[GetParam()];
    std::string text = tiny_shot().dump();
    // the compact dump has no spaces: match the case's text without them
    auto squeeze = [](std::string s) {
        s.erase(std::remove(s.begin(), s.end(), ' '), s.end());
        return s;
    };
    const size_t at = text.find(squeeze(c.from));
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, squeeze(c.from).size(), c.to);
    const fs::path path = m_dir / "shot.json";
    std::ofstream(path) << text;
    const Result r = run("sim", path);
    EXPECT_EQ(r.code, 1) << r.err;
    expect_error(r, "sim", {path.string() + ": " + c.key, "overflow"});
    EXPECT_FALSE(fs::exists(out()));
}

INSTANTIATE_TEST_SUITE_P(Shot, NumberOverflow, ::testing::Range(0, int(std::size(kOverflowCases))),
                         [](const auto& info) { return kOverflowCases[info.param].name; });

// ---- non-finite mesh vertices: named with their index, before the surface checks --------------

struct MeshCase {
    std::string name, file, text, needle;
};
const char* const kTetrahedronFaces = "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
const MeshCase kMeshCases[] = {
    {"obj_nan", "nan.obj",
     std::string("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\n") + kTetrahedronFaces, "vertex 3"},
    {"obj_inf", "inf.obj",
     std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 -inf\n") + kTetrahedronFaces, "vertex 4"},
    {"obj_overflow", "big.obj",
     std::string("v 0 0 0\nv 1e999 0 0\nv 0 1 0\nv 0 0 1\n") + kTetrahedronFaces, "vertex 2"},
    {"ply_nan", "nan.ply",
     "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
     "element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 nan 0\n0 0 1\n"
     "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n",
     "not finite"},
};

class MeshVertices : public HostileInput, public ::testing::WithParamInterface<int> {};

TEST_P(MeshVertices, NonFiniteVertexNamed) {
    const MeshCase& c = kMeshCases[GetParam()];
    std::ofstream(m_dir / c.file) << c.text;
    json shot = tiny_shot();
    shot["source"] = {{"type", "mesh"}, {"mesh", {{"path", c.file}}}};
    const Result r = expect_init_refused(shot, {(m_dir / c.file).string(), c.needle, "not finite"});
    EXPECT_EQ(r.err.find("degenerate"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("self-intersect"), std::string::npos) << r.err;
}

INSTANTIATE_TEST_SUITE_P(Init, MeshVertices, ::testing::Range(0, int(std::size(kMeshCases))),
                         [](const auto& info) { return kMeshCases[info.param].name; });

// ---- a mesh body against /sim/h and the ground: refused once its file is read -------------------

// a closed box mesh of 0.2 x 0.1 x 0.2 m, its bottom at y = 0 as the tiny shot's box: the loader
// cannot see into a mesh file, so mc-init checks what the loader checks for a box
const char* const kBoxMesh =
    "v -0.1 0 -0.1\nv 0.1 0 -0.1\nv -0.1 0.1 -0.1\nv 0.1 0.1 -0.1\n"
    "v -0.1 0 0.1\nv 0.1 0 0.1\nv -0.1 0.1 0.1\nv 0.1 0.1 0.1\n"
    "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

struct MeshBodyCase {
    std::string name;
    std::function<void(json&)> edit;
    std::string message;  // after "<shot>: "; <mesh> stands for the mesh file's path
};
const MeshBodyCase kMeshBodyCases[] = {
    {"h_5_wider_than_the_mesh", [](json& s) { s["sim"]["h"] = 5; },
     "/sim/h = 5: is larger than the body (<mesh> as placed by /source/mesh: 0.2 x 0.1 x 0.2 m)"},
    {"h_wider_than_the_scaled_mesh", [](json& s) { s["source"]["mesh"]["scale"] = 0.25; },
     "/sim/h = 0.05: is larger than the body (<mesh> as placed by /source/mesh: 0.05 x 0.025 x "
     "0.05 m), which would be less than one cell across: expected at most its thinnest side, "
     "0.025 [m]"},
    // above the top (the mesh's 0.1 is a float, a hair above the double 0.1)
    {"ground_above_the_mesh_top", [](json& s) { s["colliders"]["ground"]["height"] = 0.15; },
     "/colliders/ground/height = 0.15: is at or above the top of the body, y = 0.1 (<mesh> as "
     "placed by /source/mesh)"},
    {"ground_1e300", [](json& s) { s["colliders"]["ground"]["height"] = 1e300; },
     "/colliders/ground/height = 1e+300: is at or above the top of the body, y = 0.1"},
    // fit_to_ground is off: the loader knows no bottom, mc-init does
    {"mesh_far_above_the_ground",
     [](json& s) {
         s["source"]["mesh"]["translate"] = {0, 5, 0};
     },
     "/colliders/ground/height = 0: is 5 m below the body's bottom y = 5 (<mesh> as placed by "
     "/source/mesh), which moves at most"},
};

class MeshBody : public HostileInput, public ::testing::WithParamInterface<int> {
protected:
    // the tiny shot with the box mesh as its source, placed where it is written
    json mesh_shot() {
        std::ofstream(m_dir / "box.obj") << kBoxMesh;
        json shot = tiny_shot();
        shot["source"] = {{"type", "mesh"},
                          {"mesh", {{"path", "box.obj"}, {"fit_to_ground", false}}}};
        return shot;
    }
    std::string mesh_path() const { return (m_dir / "box.obj").string(); }
    static std::string with_mesh(std::string text, const std::string& mesh) {
        const size_t at = text.find("<mesh>");
        return at == std::string::npos ? text : text.replace(at, 6, mesh);
    }
};

TEST_P(MeshBody, RefusedByInitNamingTheKeyAndTheMeshExtent) {
    const MeshBodyCase& c = kMeshBodyCases[GetParam()];
    json shot = mesh_shot();
    c.edit(shot);
    expect_init_refused(shot, {shot_path().string() + ": " + with_mesh(c.message, mesh_path())});
}

INSTANTIATE_TEST_SUITE_P(Init, MeshBody, ::testing::Range(0, int(std::size(kMeshBodyCases))),
                         [](const auto& info) { return kMeshBodyCases[info.param].name; });

// the ground is not in the init slice: one edited after mc-init is checked by mc-sim against the
// mesh's bounds mc-init recorded
TEST_F(MeshBody, GroundEditedAfterInitIsRefusedBySim) {
    json shot = mesh_shot();
    const fs::path path = write_shot(shot);
    ASSERT_EQ(run("init", path).code, 0);
    shot["colliders"]["ground"]["height"] = 0.2;
    write_shot(shot);
    const Result r = run("sim", path);
    EXPECT_EQ(r.code, 1) << r.err;
    const std::string manifest = (out() / "init" / "manifest.json").string();
    expect_error(
        r, "sim",
        {path.string() +
         ": /colliders/ground/height = 0.2: is at or above the top of the body, y = 0.1 (" +
         mesh_path() + " as placed by /source/mesh (" + manifest + "))"});
    EXPECT_FALSE(fs::exists(out() / "sim"));
    expect_no_debris(out());
    // the ground the shot had runs
    shot["colliders"]["ground"]["height"] = 0;
    write_shot(shot);
    const Result ok = run("sim", path, {"--frames", "1-1"});
    EXPECT_EQ(ok.code, 0) << ok.err;
}

// ---- one writer per folder ----------------------------------------------------------------------

// holds a stage folder's lock from this process as another writer would
class HeldLock {
public:
    HeldLock(const fs::path& file, int how, const std::string& record) {
        fs::create_directories(file.parent_path());
        m_fd = ::open(file.c_str(), O_RDWR | O_CREAT, 0644);
        EXPECT_GE(m_fd, 0);
        EXPECT_EQ(::flock(m_fd, how | LOCK_NB), 0);
        if (!record.empty()) {
            EXPECT_EQ(::write(m_fd, record.data(), record.size()), ssize_t(record.size()));
        }
    }
    ~HeldLock() { ::close(m_fd); }

private:
    int m_fd = -1;
};

const char* const kForeignHolder =
    "host=farmnode17\npid=424242\nprogram=mc-x\nstart=2026-11-25 17:30:02 UTC\n";

class SecondWriter : public HostileInput, public ::testing::WithParamInterface<std::string> {};

TEST_P(SecondWriter, RefusedNamingTheHolder) {
    const std::string stage = GetParam();
    const fs::path shot = write_shot(tiny_shot());
    run_before(stage, shot);
    const fs::path lock = out() / ("." + stage + ".lock");
    {
        HeldLock held(lock, LOCK_EX, kForeignHolder);
        const Result r = run(stage, shot);
        EXPECT_EQ(r.code, 1) << r.err;
        expect_error(r, stage,
                     {(out() / stage).string(), "farmnode17", "pid 424242", lock.string()});
        EXPECT_EQ(read_text(lock), kForeignHolder) << "the holder's record is left alone";
        EXPECT_FALSE(fs::exists(out() / ("." + stage + ".partial")));
        EXPECT_FALSE(fs::exists(out() / stage)) << "nothing written";
    }
    // the holder gone (its file left behind, unlocked), the next run takes the lock and removes it
    const Result again = run(stage, shot);
    EXPECT_EQ(again.code, 0) << again.err;
    EXPECT_TRUE(fs::exists(out() / stage / "manifest.json"));
    expect_no_debris(out());
}

INSTANTIATE_TEST_SUITE_P(EveryStage, SecondWriter,
                         ::testing::Values("init", "sim", "surface", "render"));

TEST_F(HostileInput, StaleLockOfADeadWriterIsRecovered) {
    const fs::path shot = write_shot(tiny_shot());
    fs::create_directories(out());
    std::ofstream(out() / ".init.lock")
        << "host=localhost\npid=999999\nprogram=mc-init\nstart=yesterday\n";
    const Result r = run("init", shot);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::exists(out() / "init" / "manifest.json"));
    expect_no_debris(out());
}

TEST_F(HostileInput, KilledWriterLeavesNoLockBehind) {
    json s = tiny_shot();
    s["frames"]["end"] = 400;
    const fs::path shot = write_shot(s);
    run_before("sim", shot);
    Process first = start("sim", shot);
    ASSERT_TRUE(wait_for([&] { return has_holder_record(out() / ".sim.lock"); }, 20));
    // a second writer of the same folder, while the first runs
    const Result second = run("sim", shot, {"--frames", "1-1"});
    EXPECT_EQ(second.code, 1) << second.err;
    expect_error(second, "sim", {"pid " + std::to_string(first.pid()), "mc-sim"});
    first.signal(SIGKILL);
    EXPECT_EQ(first.wait().code, 128 + SIGKILL);
    // the kernel dropped the dead writer's lock: the next run proceeds
    const Result next = run("sim", shot, {"--frames", "1-1"});
    EXPECT_EQ(next.code, 0) << next.err;
    expect_no_debris(out());
}

TEST_F(HostileInput, TwoShotsOneFolderOnlyOneWrites) {
    json a = tiny_shot(), b = tiny_shot();
    a["frames"]["end"] = 400;
    b["name"] = "other";
    b["material"]["youngs_modulus"] = 3000;
    const fs::path shot_a = write_shot(a, "a.json"), shot_b = write_shot(b, "b.json");
    ASSERT_EQ(run("init", shot_a).code, 0);
    Process first = start("sim", shot_a);
    ASSERT_TRUE(wait_for([&] { return has_holder_record(out() / ".sim.lock"); }, 20));
    const Result second = run("sim", shot_b);
    EXPECT_EQ(second.code, 1) << second.err;
    expect_error(second, "sim", {"another writer holds it"});
    first.signal(SIGTERM);
    EXPECT_EQ(first.wait().code, 128 + SIGTERM);
    expect_no_debris(out());
}

TEST_F(HostileInput, RenderChunksShareTheFolderAFullRunDoesNot) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("render", shot);
    const fs::path lock = out() / ".render.lock";
    {
        HeldLock chunk(lock, LOCK_SH, "");
        const Result full = run("render", shot);
        EXPECT_EQ(full.code, 1) << full.err;
        expect_error(full, "render", {"farm chunks", lock.string()});
        const Result other_chunk = run("render", shot, {"--frames", "2-2"});
        EXPECT_EQ(other_chunk.code, 0) << other_chunk.err;
        EXPECT_TRUE(fs::exists(out() / "render" / "frame.0002.png"));
        EXPECT_TRUE(fs::exists(lock)) << "a chunk leaves the lock another chunk shares";
    }
    {
        HeldLock full(lock, LOCK_EX, kForeignHolder);
        const Result chunk = run("render", shot, {"--frames", "1-1"});
        EXPECT_EQ(chunk.code, 1) << chunk.err;
        expect_error(chunk, "render", {"pid 424242"});
    }
}

// ---- a stage folder that is a symbolic link: refused by every writer, the link and its target
// left as they were ---------------------------------------------------------------------------

class SymlinkedStageFolder : public HostileInput,
                             public ::testing::WithParamInterface<std::string> {};

TEST_P(SymlinkedStageFolder, IsRefusedAndLeftAlone) {
    const std::string stage = GetParam();
    const fs::path shot = write_shot(tiny_shot());
    run_before(stage, shot);
    // out/<stage> -> elsewhere/<stage>, a folder of something else
    const fs::path target = m_dir / "elsewhere" / stage, link = out() / stage;
    fs::create_directories(target);
    fs::create_directories(out());
    std::ofstream(target / "keep.txt") << "not the stage's\n";
    fs::remove_all(link);
    fs::create_directory_symlink(target, link);
    const Result r = run(stage, shot);
    EXPECT_EQ(r.code, 1) << r.err;
    expect_error(r, stage, {link.string() + ": a symbolic link", "mc-" + stage});
    EXPECT_TRUE(fs::is_symlink(link)) << "the link is not replaced";
    EXPECT_EQ(read_text(target / "keep.txt"), "not the stage's\n");
    EXPECT_EQ(std::distance(fs::directory_iterator(target), fs::directory_iterator()), 1)
        << "nothing written there";
    expect_no_debris(out());
    expect_no_debris(m_dir / "elsewhere");
}

INSTANTIATE_TEST_SUITE_P(EveryStage, SymlinkedStageFolder,
                         ::testing::Values("init", "sim", "surface", "render"));

// ---- damaged files: any flipped byte is caught by every reader, naming the file and "damaged";
// mc-sim --resume simulates a damaged frame again -------------------------------------------------

// flips every bit of the byte at `offset` of `file`
void flip_byte(const fs::path& file, size_t offset) {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(std::streamoff(offset));
    const int byte = f.get();
    f.seekp(std::streamoff(offset));
    f.put(char(~byte));
}

// offsets in a file of `size` bytes: its first byte, inside its header, the middle, the last
std::vector<size_t> damage_offsets(size_t size) { return {0, 7, 40, size / 2, size - 1}; }

// the file of `dir` whose name starts with `prefix` ("boundary.0002.")
fs::path file_starting(const fs::path& dir, const std::string& prefix) {
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename().string().rfind(prefix, 0) == 0) return e.path();
    return {};
}

// How many offsets sweep_offsets spaces evenly through a file's body. Under AddressSanitizer
// (`make sanitize`) 2, not 16: a damaged body is caught by the same checksum code wherever the
// byte is, every stage run costs several times as much there, and `make test` sweeps all 16 (the
// FlippedByte cases took 600 of the sanitizer run's 1,412 test seconds with 16, 2026-11-26).
#if defined(__SANITIZE_ADDRESS__)
constexpr size_t kEvenlySpacedOffsets = 2;
#else
constexpr size_t kEvenlySpacedOffsets = 16;
#endif

// offsets across the whole of a file of `size` bytes: each of its first 8 (magic numbers and
// versions), kEvenlySpacedOffsets more evenly spaced through the rest, and its last two
std::vector<size_t> sweep_offsets(size_t size) {
    std::vector<size_t> offsets;
    for (size_t i = 0; i < std::min<size_t>(8, size); ++i) offsets.push_back(i);
    for (size_t k = 1; k <= kEvenlySpacedOffsets; ++k)
        offsets.push_back(8 + (size - 8) * k / (kEvenlySpacedOffsets + 1));
    offsets.push_back(size - 2);
    offsets.push_back(size - 1);
    std::sort(offsets.begin(), offsets.end());
    offsets.erase(std::unique(offsets.begin(), offsets.end()), offsets.end());
    while (!offsets.empty() && offsets.back() >= size) offsets.pop_back();
    return offsets;
}

// each offset of `file` damaged in turn (the file restored after each), `read` run on it: it must
// exit 1 naming the file and "damaged", and leave no output behind
void expect_damage_refused(
    const fs::path& file, const std::string& stage, const std::function<Result()>& read,
    const std::function<void()>& expect_nothing_written,
    const std::function<std::vector<size_t>(size_t)>& offsets = damage_offsets) {
    ASSERT_TRUE(fs::is_regular_file(file)) << file;
    const std::string clean = read_text(file);
    for (const size_t offset : offsets(clean.size())) {
        SCOPED_TRACE(file.string() + " byte " + std::to_string(offset));
        flip_byte(file, offset);
        const Result r = read();
        EXPECT_EQ(r.code, 1) << r.err;
        EXPECT_NE(r.err.find("mc-" + stage + ": error: " + file.string() + ": damaged"),
                  std::string::npos)
            << r.err;
        expect_nothing_written();
        std::ofstream(file, std::ios::binary | std::ios::trunc) << clean;
    }
}

TEST_F(HostileInput, DamagedSimCacheIsRefusedBySurfaceAndMeasure) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("surface", shot);
    const fs::path cache = out() / "sim" / "particles.0002.vdb";
    expect_damage_refused(
        cache, "surface", [&] { return run("surface", shot); },
        [&] {
            EXPECT_FALSE(fs::exists(out() / "surface"));
            expect_no_debris(out());
        });
    expect_damage_refused(
        cache, "measure", [&] { return run("measure", shot); }, [] {});
}

TEST_F(HostileInput, DamagedInitFilesAreRefused) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("sim", shot);
    const Result sim = run("sim", shot);
    ASSERT_EQ(sim.code, 0) << sim.err;
    flip_byte(out() / "init" / "particles.vdb", 100);
    const Result r = run("sim", shot);
    EXPECT_EQ(r.code, 1) << r.err;
    expect_error(r, "sim", {(out() / "init" / "particles.vdb").string() + ": damaged"});
    flip_byte(out() / "init" / "tets.vtu", 100);
    const Result s = run("surface", shot);
    EXPECT_EQ(s.code, 1) << s.err;
    expect_error(s, "surface", {(out() / "init" / "tets.vtu").string() + ": damaged"});
}

TEST_F(HostileInput, DamagedMeshIsRefusedByRenderAndMeasure) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("render", shot);
    const fs::path mesh = file_starting(out() / "surface", "boundary.0002.");
    expect_damage_refused(
        mesh, "render", [&] { return run("render", shot); },
        [&] {
            EXPECT_FALSE(fs::exists(out() / "render"));
            expect_no_debris(out());
        });
    expect_damage_refused(
        mesh, "measure", [&] { return run("measure", shot); }, [] {});
    // the farm's merge checks what the chunks moved in with mc-shot verify
    flip_byte(mesh, 12);
    const Result v = Process("mc-shot", {"verify", (out() / "surface" / "manifest.json").string()},
                             m_dir / "verify.txt")
                         .wait();
    EXPECT_EQ(v.code, 1) << v.err;
    expect_error(v, "shot", {mesh.string() + ": damaged"});
}

TEST_F(HostileInput, DamagedImageIsRefusedByTheAssembly) {
    const fs::path shot = write_shot(tiny_shot());
    run_before("render", shot);
    const Result chunk = run("render", shot, {"--frames", "1-3"});
    ASSERT_EQ(chunk.code, 0) << chunk.err;
    const fs::path image = out() / "render" / "frame.0002.png";
    expect_damage_refused(
        image, "render", [&] { return run("render", shot, {"--assemble"}); },
        [&] {
            EXPECT_FALSE(fs::exists(out() / "render" / "manifest.json"));
            EXPECT_FALSE(fs::exists(out() / "render" / "contact_sheet.png"));
            expect_no_debris(out());
        });
    const Result assembled = run("render", shot, {"--assemble"});
    ASSERT_EQ(assembled.code, 0) << assembled.err;
    // a finished render folder: every image its manifest records, checked
    const std::vector<std::string> verify = {"verify",
                                             (out() / "render" / "manifest.json").string()};
    EXPECT_EQ(Process("mc-shot", verify, m_dir / "verify.txt").wait().code, 0);
    flip_byte(out() / "render" / "turntable.0001.png", 30);
    const Result v = Process("mc-shot", verify, m_dir / "verify.txt").wait();
    EXPECT_EQ(v.code, 1) << v.err;
    expect_error(v, "shot", {(out() / "render" / "turntable.0001.png").string() + ": damaged"});
}

// every kind of file a later stage reads, a byte flipped at offsets across the whole file (its
// header and last byte included), each read by a stage that uses it: caught before it is used
struct FlipCase {
    std::string name;
    std::function<void(json&)> edit;               // the shot
    std::vector<std::vector<std::string>> before;  // stage runs that make the files
    std::vector<std::string> files;                // the files, under OUT
    std::string reader;  // its stage; "shot": mc-shot verify of its folder
    std::vector<std::string> reader_args;
};
void PrintTo(const FlipCase& c, std::ostream* os) { *os << c.name; }

// ours with a threshold that breaks edges at rest: crack meshes in 3 frames
std::function<void(json&)> surfaced_as(const std::string& format) {
    return [format](json& s) {
        s["surfacing"] = {{"mode", "ours"}, {"zeta", 0.9}, {"format", format}};
    };
}
const std::vector<std::vector<std::string>> kUpToSurface = {{"init"}, {"sim"}, {"surface"}};

const FlipCase kFlipCases[] = {
    {"sim_cache_by_surface",
     [](json&) {},
     {{"init"}, {"sim"}},
     {"sim/particles.0002.vdb"},
     "surface",
     {}},
    {"sim_cache_by_measure", [](json&) {}, kUpToSurface, {"sim/particles.0002.vdb"}, "measure", {}},
    {"init_particles_by_sim", [](json&) {}, {{"init"}}, {"init/particles.vdb"}, "sim", {}},
    {"init_tets_by_surface", [](json&) {}, {{"init"}, {"sim"}}, {"init/tets.vtu"}, "surface", {}},
    {"glb_by_render",
     surfaced_as("glb"),
     kUpToSurface,
     {"surface/boundary.0002.glb", "surface/crack.0002.glb"},
     "render",
     {"--frames", "2-2"}},
    {"obj_by_render",
     surfaced_as("obj"),
     kUpToSurface,
     {"surface/boundary.0002.obj", "surface/crack.0002.obj"},
     "render",
     {"--frames", "2-2"}},
    // an obj's material file, which the mesh's readers load with it
    {"obj_material_by_render",
     surfaced_as("obj"),
     kUpToSurface,
     {"surface/boundary.0002.mtl", "surface/crack.0002.mtl"},
     "render",
     {"--frames", "2-2"}},
    {"obj_material_by_verify",
     surfaced_as("obj"),
     kUpToSurface,
     {"surface/crack.0002.mtl"},
     "shot",
     {}},
    {"glb_by_measure",
     surfaced_as("glb"),
     kUpToSurface,
     {"surface/boundary.0002.glb"},
     "measure",
     {}},
    {"obj_by_measure", surfaced_as("obj"), kUpToSurface, {"surface/crack.0002.obj"}, "measure", {}},
    {"ply_by_measure",
     surfaced_as("ply"),
     kUpToSurface,
     {"surface/boundary.0002.ply", "surface/crack.0002.ply"},
     "measure",
     {}},
    {"dae_by_measure",
     surfaced_as("dae"),
     kUpToSurface,
     {"surface/boundary.0002.dae", "surface/crack.0002.dae"},
     "measure",
     {}},
    // plates breaking everything at rest: every particle is debris; no stage reads the points, the
    // farm's merge and the Blender add-on verify them
    {"debris_points_by_verify",
     [](json& s) {
         s["surfacing"] = {
             {"mode", "plates"}, {"zeta", 0.9}, {"min_piece_size", 1}, {"debris", "points"}};
     },
     kUpToSurface,
     {"surface/debris.0002.ply"},
     "shot",
     {}},
    {"image_by_assembly",
     [](json&) {},
     {{"init"}, {"sim"}, {"surface"}, {"render", "--frames", "1-3"}},
     {"render/frame.0002.png"},
     "render",
     {"--assemble"}},
};

class FlippedByte : public HostileInput, public ::testing::WithParamInterface<FlipCase> {};

TEST_P(FlippedByte, AtAnyOffsetIsCaughtBeforeUse) {
    const FlipCase& c = GetParam();
    json s = tiny_shot();
    c.edit(s);
    const fs::path shot = write_shot(s);
    for (const std::vector<std::string>& step : c.before) {
        const Result r = run(step[0], shot, std::vector<std::string>(step.begin() + 1, step.end()));
        ASSERT_EQ(r.code, 0) << step[0] << ": " << r.err;
    }
    // what the reader would have written: nothing, its stage folder (or a finished render) absent
    const bool is_assembly =
        std::count(c.reader_args.begin(), c.reader_args.end(), "--assemble") > 0;
    const fs::path written = is_assembly ? out() / "render" / "manifest.json" : out() / c.reader;
    const auto read = [&] {
        if (c.reader != "shot") return run(c.reader, shot, c.reader_args);
        const fs::path manifest = out() / fs::path(c.files.front()).parent_path() / "manifest.json";
        return Process("mc-shot", {"verify", manifest.string()}, m_dir / "verify.txt").wait();
    };
    for (const std::string& name : c.files) {
        const fs::path file = out() / name;
        expect_damage_refused(
            file, c.reader, read,
            [&] {
                if (c.reader != "shot" && c.reader != "measure") {
                    EXPECT_FALSE(fs::exists(written)) << written;
                }
                expect_no_debris(out());
            },
            sweep_offsets);
    }
    // the files restored, the reader runs
    const Result clean = read();
    EXPECT_EQ(clean.code, 0) << clean.err;
}

INSTANTIATE_TEST_SUITE_P(EveryFileKind, FlippedByte, ::testing::ValuesIn(kFlipCases),
                         [](const auto& info) { return info.param.name; });

TEST_F(HostileInput, ResumeSimulatesADamagedFrameAgain) {
    json s = tiny_shot();
    s["frames"]["end"] = 4;
    s["sim"]["checkpoint_every"] = 1;
    const fs::path shot = write_shot(s);
    run_before("sim", shot);
    ASSERT_EQ(run("sim", shot).code, 0);
    const auto cache = [&](int f) {
        return out() / "sim" / ("particles.000" + std::to_string(f) + ".vdb");
    };
    std::vector<std::string> clean;
    for (int f = 1; f <= 4; ++f) clean.push_back(read_text(cache(f)));
    const json clean_manifest = json::parse(read_text(out() / "sim" / "manifest.json"));
    // checkpoints 3 and 4 are kept: frame 2 damaged sends the resume back to t = 0, frame 4 to
    // checkpoint 3
    for (const int damaged : {2, 4}) {
        SCOPED_TRACE("frame " + std::to_string(damaged));
        flip_byte(cache(damaged), clean[size_t(damaged - 1)].size() / 2);
        const Result r = run("sim", shot, {"--resume"});
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.err.find(cache(damaged).string() + ": damaged"), std::string::npos) << r.err;
        for (int f = 1; f <= 4; ++f)
            EXPECT_EQ(read_text(cache(f)), clean[size_t(f - 1)])
                << "frame " << f << " differs from the clean run's";
        const json manifest = json::parse(read_text(out() / "sim" / "manifest.json"));
        EXPECT_EQ(manifest["caches"], clean_manifest["caches"]);
        EXPECT_EQ(run("surface", shot).code, 0);
    }
}

// ---- SIGTERM and SIGINT: nothing left behind, exit 128 + the signal ----------------------------

struct SignalCase {
    std::string stage;
    int signal;
};

void PrintTo(const SignalCase& c, std::ostream* os) { *os << c.stage << " " << c.signal; }

class StoppedBySignal : public HostileInput, public ::testing::WithParamInterface<SignalCase> {};

// a shot whose `stage` runs long enough to be stopped midway
json long_running_shot(const std::string& stage) {
    json s = tiny_shot();
    s["frames"]["end"] = stage == "sim" ? 400 : stage == "surface" ? 100 : 3;
    // a lattice whose files take a while to write (62,500 particles)
    if (stage == "init") s["source"]["box"]["spacing"] = 0.004;
    // the particles (no surfacing), large, many views
    if (stage == "render") {
        s.erase("surfacing");
        s["render"] = {{"resolution", {1024, 1024}}, {"turntable", {{"views", 200}}}};
    }
    return s;
}

TEST_P(StoppedBySignal, CleansUpAndExits128PlusTheSignal) {
    const SignalCase c = GetParam();
    const fs::path shot = write_shot(long_running_shot(c.stage));
    run_before(c.stage == "render" ? "surface" : c.stage, shot);
    Process p = start(c.stage, shot);
    // stopped while it writes: a frame written (sim), its partial folder made (init), a frame in
    // it (surface, render)
    const std::map<std::string, fs::path> signs = {
        {"init", out() / ".init.partial"},
        {"sim", out() / "sim" / "particles.0002.vdb"},
        {"surface", out() / ".surface.partial" / "boundary.0001.glb"},
        {"render", out() / ".render.partial" / "frame.0001.png"}};
    const fs::path sign = signs.at(c.stage);
    ASSERT_TRUE(wait_for([&] { return fs::exists(sign); }, 60)) << sign;
    p.signal(c.signal);
    const Result r = p.wait();
    EXPECT_EQ(r.code, 128 + c.signal) << r.err;
    expect_error(r, c.stage, {c.signal == SIGINT ? "SIGINT" : "SIGTERM"});
    expect_no_debris(out());
    if (c.stage == "sim")
        EXPECT_FALSE(fs::exists(out() / "sim" / "manifest.json"));  // its frames stay for --resume
    else
        EXPECT_FALSE(fs::exists(out() / c.stage)) << "no stage folder from a stopped run";
}

INSTANTIATE_TEST_SUITE_P(
    Stages, StoppedBySignal,
    ::testing::Values(SignalCase{"init", SIGTERM}, SignalCase{"init", SIGINT},
                      SignalCase{"sim", SIGTERM}, SignalCase{"sim", SIGINT},
                      SignalCase{"surface", SIGTERM}, SignalCase{"surface", SIGINT},
                      SignalCase{"render", SIGTERM}, SignalCase{"render", SIGINT}),
    [](const auto& info) {
        return info.param.stage + (info.param.signal == SIGINT ? "_SIGINT" : "_SIGTERM");
    });

}  // namespace
