#pragma once
/// Writes the report: data files, gnuplot scripts and their PNGs, and report.md.
#include <filesystem>
#include <string>
#include <vector>

#include "tools/report/machine_info.h"
#include "tools/report/report_types.h"
#include "tools/report/stability.h"

namespace mudcrack::report {

/// The error at CG cap 5 (relative to eta) under which the paper's "5 iterations suffice" holds.
constexpr Real kCgClaimTolerance = 1e-3;

/// Everything the report states.
struct ReportContent {
    MachineInfo machine;
    std::string command;  // the command line that produced the report
    int threads = 0;
    Scale scale = Scale::Full;
    std::vector<Sweep> sweeps;
    std::vector<StabilityCase> cases;  // same order as stability
    std::vector<StabilityResult> stability;
    double accuracy_wall_s = 0;
    double stability_wall_s = 0;
    double total_wall_s = 0;
};

/// One Pareto plot: its script, its PNG and the command that made it.
struct Figure {
    std::string sweep_id;
    std::filesystem::path script;  // relative to the report folder
    std::filesystem::path png;     // relative to the report folder
    std::string command;           // run in the report folder
    bool is_made = false;          // gnuplot ran and wrote the PNG
};

/// Writes data/<id>.dat and plots/<id>.gp for every sweep into `dir` and runs gnuplot on each
/// script when `gnuplot` is on the PATH.
std::vector<Figure> write_figures(const std::filesystem::path& dir,
                                  const std::vector<Sweep>& sweeps);

/// The markdown text of the report.
std::string report_markdown(const ReportContent& content, const std::vector<Figure>& figures);

/// Writes a text file through a temporary name and a rename.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace mudcrack::report
