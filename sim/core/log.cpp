#include "sim/core/log.h"

#include <cstdio>
#include <map>
#include <mutex>

namespace mudcrack::log {
namespace {
Level g_level = Level::Info;
std::string g_program = "mudcrack";
std::mutex g_mutex;
std::map<std::string, int> g_warnings;
constexpr int kPrintedPerKind = 3;

void emit(const char* tag, const std::string& msg) {
    std::fprintf(stderr, "%s: %s%s\n", g_program.c_str(), tag, msg.c_str());
}
}  // namespace

void set_level(Level l) { g_level = l; }
Level level() { return g_level; }
void set_program(const std::string& name) { g_program = name; }

void info(const std::string& msg) {
    if (g_level >= Level::Info) emit("", msg);
}
void debug(const std::string& msg) {
    if (g_level >= Level::Debug) emit("debug: ", msg);
}
void error(const std::string& msg) { emit("error: ", msg); }

void warn(const std::string& kind, const std::string& msg) {
    std::lock_guard<std::mutex> lock(g_mutex);
    const int n = ++g_warnings[kind];
    if (n <= kPrintedPerKind && g_level >= Level::Warning) emit("warning: ", msg);
}

int warning_count() {
    std::lock_guard<std::mutex> lock(g_mutex);
    int total = 0;
    for (const auto& [kind, n] : g_warnings) total += n;
    return total;
}

void summarize_warnings() {
    std::lock_guard<std::mutex> lock(g_mutex);
    for (const auto& [kind, n] : g_warnings)
        if (n > kPrintedPerKind)
            std::fprintf(stderr, "%s: warning: %s x%d\n", g_program.c_str(), kind.c_str(), n);
}

void reset_warnings() {
    std::lock_guard<std::mutex> lock(g_mutex);
    g_warnings.clear();
}

}  // namespace mudcrack::log
