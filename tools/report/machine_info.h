#pragma once
/// The machine and source revision a report was measured on.
#include <string>

namespace mudcrack::report {

struct MachineInfo {
    std::string cpu_model;     // /proc/cpuinfo "model name"
    int cores = 0;             // logical CPUs online
    double memory_gib = 0;     // /proc/meminfo MemTotal
    std::string commit;        // git rev-parse HEAD of the source tree, "+ local changes" if dirty
    std::string load_average;  // /proc/loadavg 1, 5, 15 min at the start (other work skews times)
};

/// Reads /proc and asks git about `source_dir`; fields it cannot find say "unknown".
MachineInfo machine_info(const std::string& source_dir);

}  // namespace mudcrack::report
