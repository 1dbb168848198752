#pragma once
/// Logging to stderr with levels; warnings are deduplicated by kind, counted, and summarised at
/// exit (pbrt, MuJoCo). Results (tables) go to stdout, never through here.
#include <string>

namespace mudcrack::log {

enum class Level { Error = 0, Warning = 1, Info = 2, Debug = 3 };

void set_level(Level level);
Level level();
/// Prefix for every line, e.g. "mc-sim".
void set_program(const std::string& name);

void info(const std::string& msg);
void debug(const std::string& msg);
void error(const std::string& msg);
/// A warning of a given kind: printed the first few times, then only counted.
void warn(const std::string& kind, const std::string& msg);
/// Total warnings issued so far (all kinds).
int warning_count();
/// One line per warning kind with its count; called by mains before exit.
void summarize_warnings();
/// Forget all counts (tests).
void reset_warnings();

}  // namespace mudcrack::log
