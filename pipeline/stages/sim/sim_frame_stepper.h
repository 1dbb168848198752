#pragma once
/// Advancing the simulation frame by frame: frame k covers simulated time
/// ((k-1)/fps, k/fps]; each frame is substepped with the stable dt, clamped so that the frame
/// ends exactly at k/fps, and run-wide counters are accumulated for the manifest.
#include <cstdint>
#include <functional>

#include "sim/model.h"
#include "sim/mpm/simulation.h"
#include "sim/mpm/step_retry.h"

namespace mudcrack {

/// The run's counters, one X(type, name, presence) each with its doc: SimTotals' fields
/// and the checkpoint's "totals.<name>" entries (sim_checkpoint.cpp) both come from this list.
/// presence: Required, or Optional for a counter older checkpoints lack (read as 0).
// clang-format off
#define MC_SIM_TOTALS(X)                                                                        \
    X(int64_t, substeps, Required)            /* MPM steps taken */                             \
    X(double, dt_min, Required)               /* smallest step [s] (0 until the first step) */  \
    X(double, dt_max, Required)               /* largest step [s] */                            \
    X(int64_t, cg_iterations, Required)       /* moisture CG iterations, summed over substeps */\
    X(int64_t, cg_max, Required)              /* most CG iterations in one substep */           \
    X(int64_t, active_nodes_max, Required)    /* most grid nodes with mass in one substep */    \
    X(int64_t, allocated_nodes_max, Required) /* most grid nodes allocated in one substep */    \
    X(double, max_speed, Required)            /* fastest particle seen [m/s] */                 \
    X(int64_t, retries, Optional)             /* substeps redone at a smaller dt after failing  \
                                                 their checks (since step retries) */
// clang-format on

/// Counters of a run (deterministic: they depend on the simulation only, never on wall time),
/// saved in checkpoints so a resumed run's manifest covers every frame.
struct SimTotals {
#define MC_DECLARE_TOTAL(type, name, presence) type name = 0;
    MC_SIM_TOTALS(MC_DECLARE_TOTAL)
#undef MC_DECLARE_TOTAL
};

/// End time of frame k: k / fps [s] (frame 0 ends at t = 0, the initial state).
double frame_end_time(const SimModel& model, int frame);

/// Called after every substep with the frame's substep count so far.
using SubstepCallback = std::function<void(int frame_substeps)>;

/// Called after every accepted substep with its wall time by phase (what the sim manifest's
/// per-phase table sums: wall time, so it stays out of SimTotals and the checkpoints).
using PhaseSecondsCallback = std::function<void(const StepPhaseSeconds& seconds)>;

/// Advances `state` from its current time to the end of `frame` (state.time must lie before it).
/// The last substep lands exactly on k/fps; a step that would leave a sliver shorter than half a
/// stable step is split into two equal halves instead. A substep that fails its checks is rolled
/// back and redone at a smaller dt by `stepper` (sim/mpm/step_retry.h; a fixed /sim/dt is halved
/// the same way and grows back to its value), each retry logged; the stepper restarts at the
/// frame's start, so a frame's steps do not depend on how the run got there. Returns the number
/// of substeps taken (accepted).
/// @throws RuntimeError "frame K substep S (t = ..., dt = ...): <step's message>; retried ..."
///         when a substep still fails at the retries' floor, or when the stable dt collapses
///         (non-finite, or below 1e-9 of the frame length, which would never finish).
template <class S>
int advance_frame(const SimModel& model, SimStateOf<S>& state, int frame,
                  RetryingStepperOf<S>& stepper, SimTotals& totals,
                  const SubstepCallback& on_substep = {},
                  const PhaseSecondsCallback& on_phase_seconds = {});

}  // namespace mudcrack
