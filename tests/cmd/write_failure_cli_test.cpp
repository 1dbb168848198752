// What every stage does when it cannot write: a full disk and a read-only output folder
// end mc-init, mc-sim, mc-surface and mc-render with exit 1 and one error line naming the path,
// leave no .partial folder, temporary or half-written file behind, and mc-sim --resume after space
// is freed gives caches byte-identical to an uninterrupted run.
//
// How the faults are made, so that the tests run as root (CI) and as a user alike:
// - A full disk: RLIMIT_FSIZE, set in the forked child before exec with SIGXFSZ ignored, makes
//   write() fail with EFBIG past the limit, through the same write() calls a full disk fails with
//   ENOSPC; it needs no privilege. It limits each file, not their sum, so one more test fills a
//   real, small tmpfs mid-run (ENOSPC) when the test may mount one (root with CAP_SYS_ADMIN, as
//   in CI's container), and is skipped otherwise.
// - A read-only folder: the output tree loses its write bits. root ignores them, so as root the
//   child drops to uid/gid 65534 (nobody) before exec.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/io/points_io.h"
#include "render/movie_encoder.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace mudcrack;

namespace {

const fs::path kBin = MUDCRACK_BIN_DIR;

// a 405-particle block (9 x 5 x 9) dropped on the ground, 6 short frames, a checkpoint every 2,
// surfaced to OBJ and rendered at 48 x 32: the whole chain takes about 2 s
const char* kShot = R"({ "mudcrack": 1, "name": "write_failure",
  "source": { "type": "box", "initial_velocity": [0.2, -0.5, 0.0],
              "box": { "min": [-0.1, 0.05, -0.1], "max": [0.1, 0.15, 0.1], "spacing": 0.025 } },
  "material": { "density": 1, "youngs_modulus": 2000, "poisson_ratio": 0.35 },
  "plasticity": { "alpha0": -0.04, "beta": 1, "xi": 1, "M": 1.87 },
  "sim": { "h": 0.05, "checkpoint_every": 2 },
  "frames": { "start": 1, "end": 6, "fps": 192 },
  "colliders": { "ground": { "height": 0, "mode": "sticky" } },
  "surfacing": { "format": "obj" },
  "render": { "resolution": [48, 32], "turntable": { "views": 2 } }
}
)";

const std::vector<std::string> kStages = {"init", "sim", "surface", "render"};

constexpr int kCannotDropRoot = 125;  // the child's exit code when root without CAP_SETUID

struct Fault {
    long long file_size_limit = 0;  // RLIMIT_FSIZE [bytes], 0 = none
    bool as_nobody = false;         // drop root to uid/gid 65534 before exec
    fs::path path_prefix;           // a folder put first on PATH (a wrapped ffmpeg)
};
Fault file_size_limit(std::uintmax_t bytes) {
    Fault f;
    f.file_size_limit = (long long)bytes;
    return f;
}
Fault as_nobody() {
    Fault f;
    f.as_nobody = true;
    return f;
}
Fault first_on_path(const fs::path& dir) {
    Fault f;
    f.path_prefix = dir;
    return f;
}

class WriteFailureCli : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() / ("mc_write_failure_" + std::string(info->name()) + "_" +
                                             std::to_string(::getpid()));
        make_writable(m_dir);
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
        // nobody must reach the shot and the inputs whatever the umask
        fs::permissions(m_dir, fs::perms::owner_all | fs::perms::group_read |
                                   fs::perms::group_exec | fs::perms::others_read |
                                   fs::perms::others_exec);
        m_shot = m_dir / "shot.json";
        std::ofstream(m_shot) << kShot;
        fs::permissions(m_shot, fs::perms::others_read, fs::perm_options::add);
    }
    void TearDown() override {
        if (!m_mount.empty()) ::umount2(m_mount.c_str(), MNT_DETACH);
        make_writable(m_dir);
        if (!HasFailure()) fs::remove_all(m_dir);
    }

    static void make_writable(const fs::path& dir) {
        std::error_code ec;
        if (!fs::exists(dir, ec)) return;
        fs::permissions(dir, fs::perms::owner_write, fs::perm_options::add, ec);
        for (auto it = fs::recursive_directory_iterator(dir, ec);
             !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
            fs::permissions(it->path(), fs::perms::owner_write, fs::perm_options::add, ec);
    }
    static void make_read_only(const fs::path& dir) {
        const auto no_write =
            fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write;
        for (const auto& e : fs::recursive_directory_iterator(dir))
            fs::permissions(e.path(), no_write, fs::perm_options::remove);
        fs::permissions(dir, no_write, fs::perm_options::remove);
    }

    // runs mc-<stage> --threads 2 --shot SHOT --out OUT [extra...] under `fault`; stderr is kept
    // in m_stderr; returns the exit code (-1 when it did not exit)
    int run(const std::string& stage, const fs::path& out, const Fault& fault = {},
            const std::vector<std::string>& extra = {}) {
        const std::string bin = (kBin / ("mc-" + stage)).string();
        const std::string err_file = (m_dir / "stderr.txt").string();
        std::vector<std::string> args = {bin,     "--threads", "2", "--shot", m_shot.string(),
                                         "--out", out.string()};
        args.insert(args.end(), extra.begin(), extra.end());
        std::vector<char*> argv;
        for (std::string& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        std::vector<std::string> env;
        for (char** e = environ; *e; ++e) env.emplace_back(*e);
        if (!fault.path_prefix.empty()) {
            for (std::string& e : env)
                if (e.rfind("PATH=", 0) == 0) e.insert(5, fault.path_prefix.string() + ":");
        }
        std::vector<char*> envp;
        for (std::string& e : env) envp.push_back(e.data());
        envp.push_back(nullptr);
        const bool drop_root = fault.as_nobody && ::geteuid() == 0;
        const pid_t pid = ::fork();
        if (pid == 0) {
            // the child: only async-signal-safe calls until exec
            const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            const int null = ::open("/dev/null", O_WRONLY);
            if (err < 0 || null < 0 || ::dup2(err, 2) < 0 || ::dup2(null, 1) < 0) ::_exit(126);
            if (fault.file_size_limit > 0) {
                ::signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG instead of killing
                const rlimit limit{rlim_t(fault.file_size_limit), rlim_t(fault.file_size_limit)};
                if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(126);
            }
            if (drop_root &&
                (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0))
                ::_exit(kCannotDropRoot);
            ::execve(argv[0], argv.data(), envp.data());
            ::_exit(127);
        }
        int status = 0;
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        m_stderr = read_text(err_file);
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    static std::string read_text(const fs::path& path) {
        std::ifstream is(path, std::ios::binary);
        std::stringstream ss;
        ss << is.rdbuf();
        return ss.str();
    }
    static std::vector<std::string> listing(const fs::path& dir) {
        std::vector<std::string> names;
        for (const auto& e : fs::recursive_directory_iterator(dir))
            names.push_back(fs::relative(e.path(), dir).string());
        std::sort(names.begin(), names.end());
        return names;
    }
    static std::uintmax_t smallest_file(const fs::path& dir, const std::string& ext) {
        std::uintmax_t smallest = 0;
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().extension() == ext && (smallest == 0 || e.file_size() < smallest))
                smallest = e.file_size();
        return smallest;
    }

    // the whole chain, fault-free, into DIR/good: the reference outputs and every stage's inputs
    void run_good_chain() {
        for (const std::string& stage : kStages)
            ASSERT_EQ(run(stage, good(), {}), 0) << stage << ": " << m_stderr;
    }
    // a fresh output root holding what `stage` reads (the good outputs of the stages before it)
    fs::path inputs_for(const std::string& stage, const std::string& name) {
        const fs::path out = m_dir / name;
        fs::create_directories(out);
        for (const std::string& before : kStages) {
            if (before == stage) break;
            fs::copy(good() / before, out / before, fs::copy_options::recursive);
        }
        fs::permissions(out, fs::perms::others_read | fs::perms::others_exec,
                        fs::perm_options::add);
        return out;
    }

    // exit 1 with one "mc-<stage>: error: <path>: ... <reason>" line naming a path under `out`
    void expect_one_error_line(const std::string& stage, int code, const fs::path& out,
                               const std::string& reason) {
        EXPECT_EQ(code, 1) << m_stderr;
        const std::string head = "mc-" + stage + ": error: " + out.string();
        size_t lines = 0;
        for (size_t at = m_stderr.find(": error: "); at != std::string::npos;
             at = m_stderr.find(": error: ", at + 1))
            ++lines;
        EXPECT_EQ(lines, 1u) << m_stderr;
        EXPECT_NE(m_stderr.find(head), std::string::npos) << "expected \"" << head << "...\" in:\n"
                                                          << m_stderr;
        EXPECT_NE(m_stderr.find(reason), std::string::npos) << m_stderr;
    }
    // nothing of the stage is left: no .partial folder, no output folder, no temporaries
    void expect_no_output(const std::string& stage, const fs::path& out) {
        EXPECT_FALSE(fs::exists(out / ("." + stage + ".partial"))) << stage;
        EXPECT_FALSE(fs::exists(out / stage)) << stage;
        for (const std::string& name : listing(out))
            EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    }
    // mc-sim keeps its finished frames for --resume, each whole, and no manifest or temporary
    void expect_only_whole_frames(const fs::path& sim_dir) {
        EXPECT_FALSE(fs::exists(sim_dir / "manifest.json"));
        for (const auto& e : fs::directory_iterator(sim_dir)) {
            EXPECT_NE(e.path().extension(), ".tmp") << e.path();
            if (e.path().extension() == ".vdb") {
                EXPECT_NO_THROW(read_points(e.path())) << e.path();
                EXPECT_TRUE(read_text(e.path()) == read_text(good() / "sim" / e.path().filename()))
                    << e.path() << " differs from the uninterrupted run's";
            }
        }
    }
    void expect_identical_sim_caches(const fs::path& sim_dir) {
        for (int f = 1; f <= 6; ++f) {
            const fs::path a = frame_path(good() / "sim", "particles", f, "vdb"),
                           b = frame_path(sim_dir, "particles", f, "vdb");
            ASSERT_TRUE(fs::exists(b)) << b;
            EXPECT_TRUE(read_text(a) == read_text(b)) << b << " differs from " << a;
        }
        EXPECT_TRUE(fs::exists(sim_dir / "manifest.json"));
    }

    fs::path good() const { return m_dir / "good"; }

    fs::path m_dir, m_shot, m_mount;
    std::string m_stderr;
};

TEST_F(WriteFailureCli, FullDiskFailsEachStageWithThePathAndLeavesNothing) {
    run_good_chain();
    // each stage's limit is half its smallest main output, so that file cannot be written whole
    const std::vector<std::pair<std::string, std::uintmax_t>> limits = {
        {"init", fs::file_size(good() / "init" / "particles.vdb") / 2},
        {"sim", smallest_file(good() / "sim", ".vdb") / 2},
        {"surface", smallest_file(good() / "surface", ".obj") / 2},
        {"render", smallest_file(good() / "render", ".png") / 2}};
    for (const auto& [stage, limit] : limits) {
        SCOPED_TRACE("mc-" + stage + " with files limited to " + std::to_string(limit) + " bytes");
        ASSERT_GT(limit, 0u);
        const fs::path out = inputs_for(stage, "full_" + stage);
        const int code = run(stage, out, file_size_limit(limit));
        expect_one_error_line(stage, code, out, "File too large");
        if (stage == "sim") {
            expect_only_whole_frames(out / "sim");
        } else {
            expect_no_output(stage, out);
        }
    }
}

TEST_F(WriteFailureCli, FullDiskUnderFfmpegFailsTheRender) {
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty()) GTEST_SKIP() << "no ffmpeg on PATH: mc-render writes no movies";
    run_good_chain();
    // the movies (about 2 KiB) are written by ffmpeg itself: a wrapper limits only its files to
    // 1 KiB, as a disk that fills while it writes (ffmpeg 5.1 exits 0 then unless given -xerror)
    ASSERT_GT(fs::file_size(good() / "render" / "preview.mp4"), 1024u);
    const fs::path wrapper_dir = m_dir / "bin";
    fs::create_directories(wrapper_dir);
    std::ofstream(wrapper_dir / "ffmpeg")
        << "#!/bin/sh\ntrap '' XFSZ\nulimit -f 1\nexec " << ffmpeg << " \"$@\"\n";
    fs::permissions(wrapper_dir / "ffmpeg", fs::perms::owner_exec, fs::perm_options::add);
    const fs::path out = inputs_for("render", "ffmpeg_full");
    const int code = run("render", out, first_on_path(wrapper_dir));
    expect_one_error_line("render", code, out, "preview.mp4: ffmpeg failed (exit code 1");
    expect_no_output("render", out);
    // ffmpeg's own message is folded into that line, not printed beside it
    std::istringstream lines(m_stderr);
    for (std::string line; std::getline(lines, line);) {
        if (!line.empty()) {
            EXPECT_EQ(line.rfind("mc-render: ", 0), 0u) << "a line not from mc-render: " << line;
        }
    }
    EXPECT_NE(m_stderr.find("File too large"), std::string::npos) << "ffmpeg's reason is missing:\n"
                                                                  << m_stderr;
}

TEST_F(WriteFailureCli, FullDiskFailsARenderChunkAndLeavesNoFolder) {
    run_good_chain();
    // a farm chunk (--frames) into an output root without render/: its PNG cannot be written
    const fs::path out = inputs_for("render", "chunk_full");
    const int code =
        run("render", out, file_size_limit(smallest_file(good() / "render", ".png") / 2),
            {"--frames", "1-2"});
    expect_one_error_line("render", code, out, "File too large");
    expect_no_output("render", out);
}

TEST_F(WriteFailureCli, FullDiskAtACheckpointThenResumeGivesTheSameCaches) {
    run_good_chain();
    // frames fit, checkpoints do not: frame 1 and 2 are written, checkpoint 2 fails half-way
    const std::uintmax_t frame_max = fs::file_size(good() / "sim" / "particles.0002.vdb");
    const std::uintmax_t checkpoint = fs::file_size(good() / "sim" / "checkpoint.0004.bin");
    ASSERT_LT(frame_max * 5 / 4, checkpoint);
    const fs::path out = inputs_for("sim", "checkpoint_full");
    const int code = run("sim", out, file_size_limit(frame_max * 5 / 4));
    expect_one_error_line("sim", code, out / "sim" / "checkpoint.0002.bin.tmp", "File too large");
    EXPECT_NE(m_stderr.find("frames 1-2 are kept in"), std::string::npos) << m_stderr;
    expect_only_whole_frames(out / "sim");
    EXPECT_FALSE(fs::exists(out / "sim" / "checkpoint.0002.bin"));

    // space freed: the half-written checkpoint was never renamed into place, so nothing is resumed
    ASSERT_EQ(run("sim", out, {}, {"--resume"}), 0) << m_stderr;
    expect_identical_sim_caches(out / "sim");
}

TEST_F(WriteFailureCli, ResumeDoesNotKeepATruncatedFrame) {
    // a frame cut short before a checkpoint (as builds that did not check their VDB writes left
    // them on a full disk): its checksum no longer matches the one the checkpoints record, so
    // --resume does not keep it: it starts over and matches
    run_good_chain();
    const fs::path out = inputs_for("sim", "truncated");
    fs::copy(good() / "sim", out / "sim", fs::copy_options::recursive);
    fs::remove(out / "sim" / "manifest.json");
    const fs::path frame1 = out / "sim" / "particles.0001.vdb";
    fs::resize_file(frame1, fs::file_size(frame1) / 2);
    ASSERT_EQ(run("sim", out, {}, {"--resume"}), 0) << m_stderr;
    EXPECT_NE(m_stderr.find("particles.0001.vdb: damaged"), std::string::npos) << m_stderr;
    EXPECT_EQ(m_stderr.find("resuming from"), std::string::npos) << m_stderr;
    expect_identical_sim_caches(out / "sim");
}

TEST_F(WriteFailureCli, DiskFillsMidRunThenResumeGivesTheSameCaches) {
    run_good_chain();
    const fs::path out = inputs_for("sim", "tmpfs");
    const fs::path sim_dir = out / "sim";
    fs::create_directories(sim_dir);
    // a tmpfs holding frames 1-3 and checkpoint 2 and half of frame 4 (tmpfs counts whole pages)
    const std::uintmax_t page = std::uintmax_t(::sysconf(_SC_PAGESIZE));
    auto pages = [&](const fs::path& f) { return (fs::file_size(f) + page - 1) / page * page; };
    const fs::path g = good() / "sim";
    const std::uintmax_t size = pages(g / "particles.0001.vdb") + pages(g / "particles.0002.vdb") +
                                pages(g / "particles.0003.vdb") + pages(g / "checkpoint.0004.bin") +
                                fs::file_size(g / "particles.0004.vdb") / 2 / page * page;
    const std::string options = "size=" + std::to_string(size) + ",mode=0755";
    if (::mount("tmpfs", sim_dir.c_str(), "tmpfs", 0, options.c_str()) != 0)
        GTEST_SKIP() << "cannot mount a tmpfs here (" << std::strerror(errno)
                     << "): the full-disk tests above use RLIMIT_FSIZE instead";
    m_mount = sim_dir;

    const int code = run("sim", out);
    expect_one_error_line("sim", code, sim_dir / "particles.0004.vdb.tmp",
                          "No space left on device");
    EXPECT_NE(m_stderr.find("frames 1-3 are kept in"), std::string::npos) << m_stderr;
    expect_only_whole_frames(sim_dir);
    EXPECT_TRUE(fs::exists(sim_dir / "checkpoint.0002.bin"));
    EXPECT_FALSE(fs::exists(sim_dir / "particles.0004.vdb"));

    // space freed: resume from checkpoint 2, byte for byte the uninterrupted run
    ASSERT_EQ(::mount("tmpfs", sim_dir.c_str(), "tmpfs", MS_REMOUNT, "size=64m"), 0)
        << std::strerror(errno);
    ASSERT_EQ(run("sim", out, {}, {"--resume"}), 0) << m_stderr;
    EXPECT_NE(m_stderr.find("checkpoint.0002.bin"), std::string::npos) << m_stderr;
    expect_identical_sim_caches(sim_dir);
}

TEST_F(WriteFailureCli, ReadOnlyFolderFailsEachStageWithThePathAndLeavesNothing) {
    run_good_chain();
    for (const std::string& stage : kStages) {
        SCOPED_TRACE("mc-" + stage + " into a read-only folder");
        const fs::path out = inputs_for(stage, "read_only_" + stage);
        make_read_only(out);
        const std::vector<std::string> before = listing(out);
        const int code = run(stage, out, as_nobody());
        if (code == kCannotDropRoot)
            GTEST_SKIP() << "root here cannot become uid 65534, and ignores 0555";
        expect_one_error_line(stage, code, out, "Permission denied");
        EXPECT_EQ(listing(out), before);
    }
}

}  // namespace
