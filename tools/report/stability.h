#pragma once
/// The stability matrix of `make report`: stiff and extreme cases, each bounded by a
/// step budget and a wall-time limit, classified as completed / refused / stopped with an error,
/// or as a failure of the product (silent NaN, hang, crash).
#include <string>
#include <vector>

#include "tools/report/report_types.h"

namespace mudcrack::report {

/// A named case of the matrix.
struct StabilityCase {
    std::string name;         // unique, used on the command line (--case)
    std::string group;        // what is pushed to the extreme
    std::string description;  // the setup in one line
};

/// Bounds of one case.
struct StabilityLimits {
    int64_t max_steps = 400;  // substeps
    double max_wall_s = 120;  // the case counts as a hang beyond this
};

/// The limits used at each scale.
StabilityLimits stability_limits(Scale scale);

/// The suffix of a case's name that runs it with a float particle state (/sim/precision).
inline constexpr const char* kFloatCaseSuffix = "/float";

/// Every case of the matrix, in report order: each in double, then as "<name>/float".
std::vector<StabilityCase> stability_cases();

/// Runs one case in this process. A hang inside a single step cannot be interrupted here; use
/// run_stability_case_isolated for that. Throws InputError for an unknown name.
StabilityResult run_stability_case(const std::string& name, Scale scale,
                                   const StabilityLimits& limits);

/// Runs one case in a child process (`exe --case NAME ...`), killed after the wall-time limit
/// plus a grace period (Hang); a child that dies by a signal or prints no result is Crashed.
/// @param exe path of the mc-report executable
StabilityResult run_stability_case_isolated(const std::string& exe, const std::string& name,
                                            Scale scale, const StabilityLimits& limits,
                                            int threads);

/// One line that round-trips a result through a pipe (tab-separated, message last).
std::string serialize_result(const StabilityResult& r);
/// Parses serialize_result's line; false if it is not one.
bool parse_result(const std::string& line, StabilityResult& r);

/// The tag that starts a serialized result line on the child's stdout.
inline const char* result_line_tag() { return "mc-report-case\t"; }

}  // namespace mudcrack::report
