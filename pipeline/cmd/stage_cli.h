#pragma once
/// What every stage binary shares: the flag set (--shot, --out, --frames,
/// --threads, --seed, --log-level, --quiet, --keep-partial, --help, --version), exit codes
/// (0 ok, 1 bad input or failure, 2 bad usage), the one-line error report, and the closing
/// summary of wall time and peak memory.
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

namespace mudcrack {

struct FrameRange {
    int first = 0;  // 0 = from the shot
    int last = 0;   // 0 = from the shot
    bool is_set() const { return first > 0; }
};

struct StageOptions {
    std::string program;       // e.g. "mc-sim"
    std::string shot;          // --shot
    std::string out;           // --out: the shot's output root (stages write DIR/<stage>/)
    std::string frames;        // --frames A-B or N (as given)
    FrameRange frame_range;    // parsed --frames
    int threads = 0;           // --threads (0 = all cores)
    unsigned seed = 0;         // --seed (0 = the shot's)
    bool quiet = false;        // --quiet: errors and warnings only
    bool keep_partial = false; // --keep-partial: keep .partial/ folders of a failed run
    std::string log_level = "info";
};

/// Parses "A-B" or "N" (1-based, A <= B). Throws InputError naming the flag otherwise.
FrameRange parse_frame_range(const std::string& text);

/// Prints one "program: error: ..." line per line of a (possibly multi-line) message, so every
/// problem a validation reports is greppable on its own.
void report_error_lines(const std::string& message);

/// Runs a stage main: builds the CLI with the common flags plus `add_flags`, parses (usage
/// errors exit 2, --help/--version exit 0), applies threads/log level, calls body, and maps
/// InputError/RuntimeError to one "program: error: ..." line and exit 1. First, when the
/// environment sets neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT, re-executes the binary once with
/// OMP_WAIT_POLICY=passive, so idle OpenMP threads sleep instead of spinning on a shared node.
/// @param argv main's argv (null-terminated), passed on unchanged to the re-executed binary
int run_stage(const std::string& program, const std::string& description, int argc, char** argv,
              const std::function<void(CLI::App&)>& add_flags,
              const std::function<int(const StageOptions&)>& body);

}  // namespace mudcrack
