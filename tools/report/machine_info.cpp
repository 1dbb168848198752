#include "tools/report/machine_info.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace mudcrack::report {

namespace {

// the first line a shell command prints, without its newline; empty on failure
std::string first_line_of(const std::string& command) {
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return {};
    char buf[512];
    std::string line;
    if (std::fgets(buf, sizeof buf, pipe)) line = buf;
    pclose(pipe);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    return line;
}

// the value after "key\s*:" of the first matching line of a /proc file
std::string proc_value(const char* path, const std::string& key) {
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) {
        if (line.compare(0, key.size(), key) != 0) continue;
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        const size_t start = line.find_first_not_of(" \t", colon + 1);
        return start == std::string::npos ? std::string() : line.substr(start);
    }
    return {};
}

}  // namespace

MachineInfo machine_info(const std::string& source_dir) {
    MachineInfo m;
    m.cpu_model = proc_value("/proc/cpuinfo", "model name");
    if (m.cpu_model.empty()) m.cpu_model = "unknown";
    m.cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
    std::istringstream mem(proc_value("/proc/meminfo", "MemTotal"));
    double kib = 0;
    if (mem >> kib) m.memory_gib = kib / (1024.0 * 1024.0);
    std::ifstream loadavg("/proc/loadavg");
    std::string l1, l5, l15;
    if (loadavg >> l1 >> l5 >> l15)
        m.load_average = l1 + " " + l5 + " " + l15;
    else
        m.load_average = "unknown";
    const std::string git = "git -C '" + source_dir + "' ";
    m.commit = first_line_of(git + "rev-parse HEAD 2>/dev/null");
    if (m.commit.empty()) {
        m.commit = "unknown (not a git checkout)";
    } else if (!first_line_of(git + "status --porcelain --untracked-files=no 2>/dev/null")
                    .empty()) {
        m.commit += " + local changes";
    }
    return m;
}

}  // namespace mudcrack::report
