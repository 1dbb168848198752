#pragma once
/// Results of the accuracy sweeps and the stability matrix of `make report`.
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "sim/core/types.h"
#include "sim/model.h"
#include "sim/mpm/simulation.h"

namespace mudcrack::report {

/// How much work a sweep or case does: Full for `make report` (< 30 min on 2 cores), Reduced
/// for the gtest version in `make test` (small grids, few steps, < 60 s in total).
enum class Scale { Reduced, Full };

/// One run of a sweep: the knob's value, the error against the analytic solution and the wall
/// time of the run (initial state and step loop).
struct SweepPoint {
    Real knob = 0;
    Real error = 0;
    double wall_s = 0;
    std::string note;  // extra measured numbers of this run (steps, particles, secondary error)
};

/// The suffix of a float sweep's id ("" in double): the writer plots "<id>" and "<id>_float" on
/// one figure.
inline constexpr const char* kFloatSweepSuffix = "_float";

template <class S>
const char* precision_suffix() {
    return std::is_same_v<S, float> ? kFloatSweepSuffix : "";
}
template <class S>
const char* precision_title() {
    return std::is_same_v<S, float> ? " (float state)" : "";
}

/// One knob swept against one analytic solution.
struct Sweep {
    std::string id;             // file stem of its data and plot, e.g. "diffusion_1d_h"
    std::string title;          // one line for the table
    std::string knob;           // knob name with units, e.g. "h [m]"
    std::string error_measure;  // what `error` is
    std::vector<SweepPoint> points;
    std::string precision = "double";  // of the particle state: "double" or "float"
    Real order = 0;                    // least-squares slope of log(error) against log(knob)
    std::string order_note;            // how to read the slope (expected order, what limits it)
};

/// What a stability case ended with. The last three are failures of the product.
enum class Outcome {
    Completed,         // ran its step budget with a finite state
    Refused,           // InputError before stepping, with its message
    StoppedWithError,  // RuntimeError during stepping, with its message
    SilentNaN,         // a non-finite state that no error reported
    Hang,              // exceeded its wall-time bound
    Crashed,           // the process died (signal, abort) or threw something unexpected
    Diverged,          // ran its budget with a finite state but its energy became non-finite
                       //   (an inverted Fe) or grew past kDivergedEnergyGrowth: flagged, not failed
};

/// Energy growth (in units of the energy scale) beyond which a completed run is "diverged".
constexpr double kDivergedEnergyGrowth = 10;

/// Printable name of an outcome.
const char* outcome_name(Outcome outcome);

/// Silent NaN, hang and crash are failures of the product; the rest are acceptable endings.
inline bool is_product_failure(Outcome outcome) {
    return outcome == Outcome::SilentNaN || outcome == Outcome::Hang || outcome == Outcome::Crashed;
}

/// One row of the stability matrix.
struct StabilityResult {
    std::string name;
    Outcome outcome = Outcome::Crashed;
    std::string message;     // the error text (refused / stopped) or what went wrong
    int64_t steps = 0;       // substeps taken (accepted)
    int64_t retries = 0;     // substeps that failed their checks and were retried at a smaller dt
    double sim_time = 0;     // simulated time reached [s]
    Real max_speed = 0;      // max |v| over the run [m/s]
    Real energy_drift = 0;   // (E_end - E_0) / E_scale
    Real energy_growth = 0;  // (max E - E_0) / E_scale: > 0 means energy was created
    double wall_s = 0;
};

}  // namespace mudcrack::report
