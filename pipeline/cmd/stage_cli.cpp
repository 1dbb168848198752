#include "pipeline/cmd/stage_cli.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <regex>
#include <thread>

#include "pipeline/io/atomic_output.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

// How long an idle OpenMP thread spins at a barrier before it sleeps. libgomp's default, 300,000
// spins (about 3 ms), takes the cores the working threads need whenever other jobs share the node,
// and a stage then runs many times slower (docs/reliability.md: 145 s instead of 8 s for six demo
// frames on a loaded node). Sleeping at once (OMP_WAIT_POLICY=passive, our default until
// 2026-11-29) is fair but slow alone: a demo step opens some 55 short parallel regions, each
// sleep and wake is a futex call (slow on a virtual machine), and mc-sim took 1.5x as long on the
// demo, 2 threads, quiet. 1,000 spins (some microseconds) bridge the gap between two
// regions and sleep through anything longer: docs/reliability.md has the measurements.
constexpr const char* kOpenMpSpinCount = "1000";

// libgomp reads its wait settings once, when it is loaded, before main runs, so setting them here
// would come too late: a stage whose user set neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT
// re-executes itself, once, with GOMP_SPINCOUNT=kOpenMpSpinCount. A user's own setting is kept.
void reexec_with_bounded_openmp_spinning(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
    if (setenv("GOMP_SPINCOUNT", kOpenMpSpinCount, /*overwrite=*/0) != 0) return;
    execv("/proc/self/exe", argv);
    // no exec (no /proc?): run on with libgomp's default spinning, only slower under load
    unsetenv("GOMP_SPINCOUNT");
}

// a std::filesystem call that threw (a read-only or full output folder) in the house format,
// "<path>: <operation>: <reason>", instead of libstdc++'s "filesystem error: <operation>: <reason>
// [<path>]"
std::string filesystem_error_line(const std::filesystem::filesystem_error& e) {
    std::string what = e.what();
    const std::string prefix = "filesystem error: ";
    if (what.compare(0, prefix.size(), prefix) == 0) what.erase(0, prefix.size());
    for (const std::filesystem::path& p : {e.path2(), e.path1()}) {
        const std::string suffix = " [" + p.string() + "]";
        if (!p.empty() && what.size() >= suffix.size() &&
            what.compare(what.size() - suffix.size(), suffix.size(), suffix) == 0)
            what.erase(what.size() - suffix.size());
    }
    if (e.path1().empty()) return what;
    return e.path1().string() + (e.path2().empty() ? "" : " -> " + e.path2().string()) + ": " +
           what;
}

// the stage a program writes: "mc-render" -> "render"
std::string stage_of(const std::string& program) {
    return program.rfind("mc-", 0) == 0 ? program.substr(3) : program;
}

// SIGTERM and SIGINT: the handler only writes the signal's number into a pipe; a thread reads it,
// removes what the stage was writing (its .partial folder, temporary files, the lock) and exits
// 128 + the signal, so the cleanup runs outside the handler, with no restriction on what it calls
int g_signal_pipe[2] = {-1, -1};
volatile std::sig_atomic_t g_stop_signal = 0;  // the signal received (0: none)
std::atomic<StageLock*> g_stage_lock{nullptr};

extern "C" void on_stop_signal(int signal_number) {
    g_stop_signal = signal_number;
    const unsigned char byte = 1;
    [[maybe_unused]] const ssize_t n = write(g_signal_pipe[1], &byte, 1);
}

void set_stop_signal_action(void (*handler)(int)) {
    struct sigaction action {};
    action.sa_handler = handler;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGINT, &action, nullptr);
}

[[noreturn]] void clean_up_and_exit(int signal_number) {
    run_interrupt_cleanup();
    StageLock* lock = g_stage_lock.load();
    std::string what = "removed the partial output";
    if (lock) {
        // an exclusive holder's folder holds no one else's temporaries (ffmpeg's movie among them)
        std::error_code ec;
        if (lock->mode() == LockMode::Exclusive)
            for (auto it = fs::directory_iterator(lock->stage_dir(), ec);
                 !ec && it != fs::directory_iterator(); it.increment(ec))
                if (it->path().extension() == ".tmp") fs::remove(it->path(), ec);
        lock->release();
        what += " in " + lock->stage_dir().parent_path().string();
    }
    log::error(std::string("stopped by ") + (signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
               ": " + what + "; exit " + std::to_string(128 + signal_number));
    std::fflush(stderr);
    _exit(128 + signal_number);
}

void handle_stop_signals() {
    if (pipe2(g_signal_pipe, O_CLOEXEC) != 0) return;  // no pipe: signals keep their default action
    std::thread([] {
        // only a signal the handler recorded stops the stage, never a stray byte
        for (;;) {
            unsigned char byte = 0;
            const ssize_t n = read(g_signal_pipe[0], &byte, 1);
            if (n < 0 && errno == EINTR) continue;
            if (n != 1) break;
            if (g_stop_signal != 0) clean_up_and_exit(g_stop_signal);
        }
        set_stop_signal_action(SIG_DFL);  // the pipe failed: signals end the stage as they would
    }).detach();
    set_stop_signal_action(on_stop_signal);
}

// the body under the stage folder's lock, with InputError and RuntimeError mapped to one
// "program: error: ..." line and exit 1 (a UsageError: exit 2)
int run_locked_body(const StageOptions& opt, const std::function<int(const StageOptions&)>& body,
                    const LockModeOf& lock_mode) {
    std::unique_ptr<StageLock> lock;  // released last, after the body's own cleanup
    int code = kExitFailure;
    try {
        const std::optional<LockMode> mode = lock_mode ? lock_mode(opt) : LockMode::Exclusive;
        if (mode)
            lock = std::make_unique<StageLock>(fs::path(opt.out) / stage_of(opt.program),
                                               opt.program, *mode);
        // writers sharing a folder: temporary names unique to this one
        if (mode == LockMode::Shared)
            set_temporary_suffix("." + lock_host_name() + "." + std::to_string(getpid()) + ".tmp");
        g_stage_lock = lock.get();
        code = body(opt);
    } catch (const UsageError& e) {
        report_error_lines(e.what());
        code = kExitUsage;
    } catch (const InputError& e) {
        report_error_lines(e.what());
    } catch (const RuntimeError& e) {
        report_error_lines(e.what());
    } catch (const std::filesystem::filesystem_error& e) {
        log::error(filesystem_error_line(e));
    } catch (const std::exception& e) {
        log::error(std::string("unexpected failure: ") + e.what());
    }
    g_stage_lock = nullptr;
    return code;
}

// CLI11 names a hidden option (an empty group) "": such a flag is named by its long name
std::string flag_name(const CLI::Option& option) {
    const std::string name = option.get_name();
    if (!name.empty() || option.get_lnames().empty()) return name;
    return "--" + option.get_lnames().front();
}

}  // namespace

void refuse_empty_values(const CLI::App& app) {
    for (const CLI::Option* option : app.get_options()) {
        // not given, or a switch
        if (option->count() == 0 || option->get_expected_min() == 0) continue;
        for (const std::string& value : option->results())
            if (value.empty()) throw UsageError(flag_name(*option) + " = \"\": expected a value");
    }
    for (const CLI::App* command : app.get_subcommands()) refuse_empty_values(*command);
}

FrameRange parse_frame_range(const std::string& text) {
    // at most 9 digits: a frame number fits an int
    static const std::regex range(R"(^\s*(\d{1,9})\s*(?:-\s*(\d{1,9}))?\s*$)");
    std::smatch m;
    if (!std::regex_match(text, m, range))
        throw UsageError("--frames = \"" + text + "\": expected A-B or N (1-based frame numbers)");
    FrameRange r;
    r.first = std::stoi(m[1]);
    r.last = m[2].matched ? std::stoi(m[2]) : r.first;
    if (r.first < 1 || r.last < r.first)
        throw UsageError("--frames = \"" + text + "\": expected 1 <= A <= B");
    return r;
}

int parse_frame_number(const std::string& flag, const std::string& text) {
    static const std::regex number(R"(^\s*(-?\d{1,9})\s*$)");
    std::smatch m;
    if (!std::regex_match(text, m, number))
        throw UsageError(flag + " = \"" + text + "\": expected a frame number");
    return std::stoi(m[1]);
}

int max_thread_count() {
    return kMaxThreadsPerHardwareThread * std::max(1, int(std::thread::hardware_concurrency()));
}

int parse_thread_count(const std::string& text) {
    static const std::regex number(R"(^\s*(-?\d{1,12})\s*$)");
    const int hardware = std::max(1, int(std::thread::hardware_concurrency()));
    const std::string expected =
        "expected 0 (all " + std::to_string(hardware) + " hardware threads) or 1 to " +
        std::to_string(max_thread_count()) + " (" + std::to_string(kMaxThreadsPerHardwareThread) +
        " x the hardware threads)";
    std::smatch m;
    if (!std::regex_match(text, m, number))
        throw UsageError("--threads = \"" + text + "\": " + expected);
    const long long n = std::stoll(m[1]);
    if (n < 0) throw UsageError("--threads = " + std::to_string(n) + ": " + expected);
    if (n > max_thread_count())
        throw UsageError("--threads = " + std::to_string(n) +
                         ": more threads than a stage can use here: " + expected);
    return int(n);
}

int parse_error_exit(const CLI::App& app, const CLI::ParseError& e, const std::string& program) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    log::error(std::string(e.what()) + " (" + program + " --help lists the flags)");
    return kExitUsage;
}

void report_error_lines(const std::string& message) {
    size_t begin = 0;
    while (begin <= message.size()) {
        const size_t end = message.find('\n', begin);
        const std::string line =
            message.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
        if (!line.empty()) log::error(line);
        if (end == std::string::npos) break;
        begin = end + 1;
    }
}

int run_stage(const std::string& program, const std::string& description, int argc, char** argv,
              const std::function<void(CLI::App&)>& add_flags,
              const std::function<int(const StageOptions&)>& body, const LockModeOf& lock_mode) {
    reexec_with_bounded_openmp_spinning(argv);
    handle_stop_signals();
    WallTimer timer;
    log::set_program(program);
    StageOptions opt;
    opt.program = program;
    CLI::App app{description, program};
    std::string threads_text;
    app.set_version_flag("--version", std::string(program) + " (mudcrack) " MUDCRACK_VERSION);
    app.add_option("--shot", opt.shot, "shot file (JSON)")->required()->check(CLI::ExistingFile);
    app.add_option("--out", opt.out, "output root of the shot (stages write OUT/<stage>/)")
        ->required();
    app.add_option("--frames", opt.frames,
                   "frame range A-B or a single frame N (default: the shot's)");
    app.add_option("--threads", threads_text,
                   "worker threads, at most " + std::to_string(kMaxThreadsPerHardwareThread) +
                       " x the hardware threads (default: all cores)");
    app.add_option("--seed", opt.seed, "random seed (default: the shot's)");
    app.add_option("--log-level", opt.log_level, "error|warning|info|debug")
        ->check(CLI::IsMember({"error", "warning", "info", "debug"}));
    app.add_flag("--quiet", opt.quiet, "print errors and warnings only");
    app.add_flag("--keep-partial", opt.keep_partial,
                 "keep the .partial/ output folder of a failed run");
    if (add_flags) add_flags(app);
    // usage errors: the parser's and the flag values', one line each, exit 2
    try {
        app.parse(argc, argv);
        refuse_empty_values(app);
        // given, even as "", a value is parsed: an empty one is refused, not taken for the default
        if (app.count("--threads") > 0) opt.threads = parse_thread_count(threads_text);
        if (app.count("--frames") > 0) opt.frame_range = parse_frame_range(opt.frames);
    } catch (const CLI::ParseError& e) {
        return parse_error_exit(app, e, program);
    } catch (const UsageError& e) {
        log::error(e.what());
        return kExitUsage;
    }
    const log::Level level = opt.quiet                    ? log::Level::Warning
                             : opt.log_level == "error"   ? log::Level::Error
                             : opt.log_level == "warning" ? log::Level::Warning
                             : opt.log_level == "debug"   ? log::Level::Debug
                                                          : log::Level::Info;
    log::set_level(level);
    set_thread_count(opt.threads);
    const int code = run_locked_body(opt, body, lock_mode);
    log::summarize_warnings();
    char line[160];
    std::snprintf(line, sizeof line, "%s in %.2f s, peak memory %.1f MiB, %d threads",
                  code == 0 ? "done" : "failed", timer.seconds(), peak_rss_bytes() / 1048576.0,
                  thread_count());
    log::info(line);
    return code;
}

}  // namespace mudcrack
