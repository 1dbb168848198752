#pragma once
/// What every stage binary shares: the flag set (--shot, --out, --frames,
/// --threads, --seed, --log-level, --quiet, --keep-partial, --help, --version), exit codes
/// (0 ok, 1 bad input or failure, 2 bad usage, 128 + N stopped by signal N), the one-line error
/// report, the lock of the stage's output folder, the cleanup on SIGTERM/SIGINT, and the closing
/// summary of wall time and peak memory.
#include <functional>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "pipeline/io/stage_lock.h"
#include "pipeline/stages/stage_options.h"

namespace mudcrack {

constexpr int kExitFailure = 1;  // bad input (a shot key, a file) or a failure at run time
constexpr int kExitUsage = 2;    // bad usage: the parser's errors and every flag's bad value
/// --threads above this many per hardware thread is refused: beyond a few, threads only contend
/// (1000 threads took 15 s on a 0.3 s shot) and libgomp fails to start 100,000.
constexpr int kMaxThreadsPerHardwareThread = 4;

/// Parses "A-B" or "N" (1-based, A <= B). Throws UsageError naming the flag otherwise.
FrameRange parse_frame_range(const std::string& text);

/// Parses a flag's frame number ("N", "-N": a sign and at most 9 digits, so it fits an int; the
/// stage checks it against its frames). Throws UsageError naming `flag` and `text` otherwise.
int parse_frame_number(const std::string& flag, const std::string& text);

/// The largest --threads: kMaxThreadsPerHardwareThread x the hardware threads.
int max_thread_count();

/// Parses --threads: 0 (all cores) to max_thread_count(). Throws UsageError naming the flag, the
/// value and the range otherwise.
int parse_thread_count(const std::string& text);

/// How a stage run locks its output folder OUT/<stage>/ (the program's name without "mc-"), or
/// nullopt for a program that writes no stage folder (mc-measure).
using LockModeOf = std::function<std::optional<LockMode>(const StageOptions&)>;

/// What a program does with an argument parser's error: --help and --version print and exit 0;
/// a usage error prints one "program: error: ..." line and returns kExitUsage.
int parse_error_exit(const CLI::App& app, const CLI::ParseError& e, const std::string& program);

/// Throws UsageError naming the first option or argument given an empty value ("--json ''",
/// "--format ''"), in `app` and the subcommands it parsed: an empty value is a mistake, not the
/// option left out.
void refuse_empty_values(const CLI::App& app);

/// Prints one "program: error: ..." line per line of a (possibly multi-line) message, so every
/// problem a validation reports is greppable on its own.
void report_error_lines(const std::string& message);

/// Runs a stage main: builds the CLI with the common flags plus `add_flags`, parses (usage
/// errors, the parser's and UsageError, exit 2 with one "program: error: ..." line; --help and
/// --version exit 0), applies threads/log level, locks the stage folder (`lock_mode`; default
/// exclusive), calls body, and maps InputError/RuntimeError to one "program: error: ..." line
/// and exit 1. SIGTERM and SIGINT remove the .partial folder, the temporary files and the lock,
/// and exit 128 + the signal (pipeline/io/atomic_output.h). First, when the
/// environment sets neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT, re-executes the binary once with
/// GOMP_SPINCOUNT=1000, so idle OpenMP threads bridge the short gaps between parallel regions and
/// sleep through longer ones instead of spinning on a shared node.
/// @param argv main's argv (null-terminated), passed on unchanged to the re-executed binary
int run_stage(const std::string& program, const std::string& description, int argc, char** argv,
              const std::function<void(CLI::App&)>& add_flags,
              const std::function<int(const StageOptions&)>& body,
              const LockModeOf& lock_mode = {});

}  // namespace mudcrack
