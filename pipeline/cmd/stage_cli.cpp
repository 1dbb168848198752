#include "pipeline/cmd/stage_cli.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <regex>

#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"

namespace mudcrack {
namespace {

// OpenMP threads that spin at barriers (libgomp spins 300,000 times before it sleeps) take the
// cores the working threads need whenever other jobs share the node, and a stage then runs many
// times slower (README, Reliability: 145 s instead of 8 s for six demo frames on a loaded node).
// libgomp reads its wait policy once, when it is loaded, before main runs, so setting it here
// would come too late: a stage whose user set neither variable re-executes itself, once, with
// OMP_WAIT_POLICY=passive. A user's own OMP_WAIT_POLICY or GOMP_SPINCOUNT is kept as it is.
void reexec_with_passive_openmp_threads(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
    if (setenv("OMP_WAIT_POLICY", "passive", /*overwrite=*/0) != 0) return;
    execv("/proc/self/exe", argv);
    // no exec (no /proc?): run on with libgomp's spinning threads, only slower under load
    unsetenv("OMP_WAIT_POLICY");
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
    return e.path1().string() + (e.path2().empty() ? "" : " -> " + e.path2().string()) + ": " + what;
}

}  // namespace

FrameRange parse_frame_range(const std::string& text) {
    static const std::regex range(R"(^\s*(\d+)\s*(?:-\s*(\d+))?\s*$)");
    std::smatch m;
    if (!std::regex_match(text, m, range))
        throw InputError("--frames = \"" + text + "\": expected A-B or N (1-based frame numbers)");
    FrameRange r;
    r.first = std::stoi(m[1]);
    r.last = m[2].matched ? std::stoi(m[2]) : r.first;
    if (r.first < 1 || r.last < r.first)
        throw InputError("--frames = \"" + text + "\": expected 1 <= A <= B");
    return r;
}

void report_error_lines(const std::string& message) {
    size_t begin = 0;
    while (begin <= message.size()) {
        const size_t end = message.find('\n', begin);
        const std::string line = message.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
        if (!line.empty()) log::error(line);
        if (end == std::string::npos) break;
        begin = end + 1;
    }
}

int run_stage(const std::string& program, const std::string& description, int argc, char** argv,
              const std::function<void(CLI::App&)>& add_flags,
              const std::function<int(const StageOptions&)>& body) {
    reexec_with_passive_openmp_threads(argv);
    WallTimer timer;
    log::set_program(program);
    StageOptions opt;
    opt.program = program;
    CLI::App app{description, program};
    app.set_version_flag("--version", std::string(program) + " (mudcrack) " MUDCRACK_VERSION);
    app.add_option("--shot", opt.shot, "shot file (JSON)")->required()->check(CLI::ExistingFile);
    app.add_option("--out", opt.out, "output root of the shot (stages write OUT/<stage>/)")->required();
    app.add_option("--frames", opt.frames, "frame range A-B or a single frame N (default: the shot's)");
    app.add_option("--threads", opt.threads, "worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
    app.add_option("--seed", opt.seed, "random seed (default: the shot's)");
    app.add_option("--log-level", opt.log_level, "error|warning|info|debug")
        ->check(CLI::IsMember({"error", "warning", "info", "debug"}));
    app.add_flag("--quiet", opt.quiet, "print errors and warnings only");
    app.add_flag("--keep-partial", opt.keep_partial, "keep the .partial/ output folder of a failed run");
    if (add_flags) add_flags(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    const log::Level level = opt.quiet ? log::Level::Warning
                             : opt.log_level == "error"   ? log::Level::Error
                             : opt.log_level == "warning" ? log::Level::Warning
                             : opt.log_level == "debug"   ? log::Level::Debug
                                                          : log::Level::Info;
    log::set_level(level);
    set_thread_count(opt.threads);
    int code = 1;
    try {
        if (!opt.frames.empty()) opt.frame_range = parse_frame_range(opt.frames);
        code = body(opt);
    } catch (const InputError& e) {
        report_error_lines(e.what());
        code = 1;
    } catch (const RuntimeError& e) {
        report_error_lines(e.what());
        code = 1;
    } catch (const std::filesystem::filesystem_error& e) {
        log::error(filesystem_error_line(e));
        code = 1;
    } catch (const std::exception& e) {
        log::error(std::string("unexpected failure: ") + e.what());
        code = 1;
    }
    log::summarize_warnings();
    char line[160];
    std::snprintf(line, sizeof line, "%s in %.2f s, peak memory %.1f MiB, %d threads",
                  code == 0 ? "done" : "failed", timer.seconds(), peak_rss_bytes() / 1048576.0,
                  thread_count());
    log::info(line);
    return code;
}

}  // namespace mudcrack
