#include "pipeline/stages/sim/sim_frame_stepper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "sim/core/error.h"
#include "sim/core/log.h"

namespace mudcrack {
namespace {

std::string step_context(int frame, int substep, double time, double dt) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "frame %d substep %d (t = %.9g s, dt = %.6g s): ", frame,
                  substep, time, dt);
    return buf;
}

// "particle 17 moves at 3.2e+05 m/s": what made the velocity bound of dt collapse
template <class S>
std::string fastest_particle(const SimStateOf<S>& state) {
    size_t fastest = 0;
    double speed2 = -1;
    for (size_t i = 0; i < state.size(); ++i) {
        const double s2 = state.v[i].template cast<double>().squaredNorm();
        if (!(s2 <= speed2)) {  // also catches NaN
            fastest = i;
            speed2 = s2;
            if (!std::isfinite(s2)) break;
        }
    }
    if (speed2 < 0) return "no particles";
    char buf[160];
    std::snprintf(buf, sizeof buf, "particle %d moves at %.6g m/s (J = %.6g)",
                  int(state.id[fastest]), std::sqrt(speed2),
                  state.J.empty() ? 1.0 : state.J[fastest]);
    return buf;
}

}  // namespace

double frame_end_time(const SimModel& model, int frame) { return double(frame) / model.time.fps; }

template <class S>
int advance_frame(const SimModel& model, SimStateOf<S>& state, int frame,
                  RetryingStepperOf<S>& stepper, SimTotals& totals,
                  const SubstepCallback& on_substep, const PhaseSecondsCallback& on_phase_seconds) {
    const double t_end = frame_end_time(model, frame);
    const double frame_length = 1.0 / model.time.fps;
    int substeps = 0;
    stepper.restart(state);
    // what a rollback returns to besides the state: the counters at the rollback point
    int substeps_at_rollback_point = substeps;
    SimTotals totals_at_rollback_point = totals;
    while (state.time < t_end) {
        const int substep = substeps + 1;
        // the stable step (reduced while retries are in force), clamped to land exactly on the
        // frame's end
        double dt = stable_dt(model, state) * stepper.dt_scale();
        if (!std::isfinite(dt) || dt < kCollapsedDtFraction * frame_length)
            throw RuntimeError(step_context(frame, substep, state.time, dt) +
                               "the stable time step collapsed: " + fastest_particle(state) +
                               ": the simulation is unstable");
        const double remaining = t_end - state.time;
        const bool is_last = dt >= remaining;
        if (is_last)
            dt = remaining;
        else if (dt > 0.5 * remaining)
            dt = 0.5 * remaining;  // two equal steps instead of one full step and a sliver
        const double t_start = state.time;
        const double t_next = is_last ? t_end : t_start + dt;
        const int64_t count_before = state.step_count;

        StepAttempt attempt;
        try {
            attempt = stepper.attempt(model, state, dt);
        } catch (const RuntimeError& e) {
            throw RuntimeError(step_context(frame, substep, t_start, dt) + e.what());
        }
        if (!attempt.is_accepted) {
            const int64_t retries = totals.retries + 1;
            substeps = substeps_at_rollback_point;
            totals = totals_at_rollback_point;
            totals.retries = retries;
            char redo[160];
            std::snprintf(redo, sizeof redo,
                          ": rolled back to t = %.9g s, going on from there at %g of the stable dt",
                          state.time, double(stepper.dt_scale()));
            log::info("retry: " + step_context(frame, substep, t_start, dt) + attempt.failure +
                      redo);
            continue;
        }
        const StepStats& stats = attempt.stats;
        // pin the clock: the frame ends at exactly k/fps whatever rounding step() did
        state.time = t_next;
        if (state.step_count == count_before) ++state.step_count;
        ++substeps;

        // run-wide counters for the manifest
        totals.dt_min = totals.substeps == 0 ? dt : std::min(totals.dt_min, dt);
        totals.dt_max = std::max(totals.dt_max, dt);
        ++totals.substeps;
        totals.cg_iterations += stats.cg_iterations;
        totals.cg_max = std::max<int64_t>(totals.cg_max, stats.cg_iterations);
        totals.active_nodes_max = std::max(totals.active_nodes_max, stats.active_nodes);
        totals.allocated_nodes_max = std::max(totals.allocated_nodes_max, stats.allocated_nodes);
        totals.max_speed = std::max<double>(totals.max_speed, stats.max_speed);
        if (attempt.is_rollback_point) {
            substeps_at_rollback_point = substeps;
            totals_at_rollback_point = totals;
        }
        if (on_phase_seconds) on_phase_seconds(stats.seconds);
        if (on_substep) on_substep(substeps);
    }
    return substeps;
}

template int advance_frame(const SimModel&, SimStateOf<double>&, int, RetryingStepperOf<double>&,
                           SimTotals&, const SubstepCallback&, const PhaseSecondsCallback&);
template int advance_frame(const SimModel&, SimStateOf<float>&, int, RetryingStepperOf<float>&,
                           SimTotals&, const SubstepCallback&, const PhaseSecondsCallback&);

}  // namespace mudcrack
