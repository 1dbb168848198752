#pragma once
/// Recovering from a failed substep: a substep that fails its checks (an inverted
/// particle, J <= 0; a non-finite state; a particle moved more than 2 cells) is rolled back and
/// retried with half the time step, down to a floor, after which the run stops with the step's
/// own message. After enough accepted steps the time step doubles back.
///
/// The rollback point is a copy of the state taken at restart() (the frame stepper calls it at
/// every frame start), every RetryPolicy::snapshot_interval accepted steps, and before dt grows
/// back; a failure rolls back to it and redoes the steps since then at the smaller dt. A copy
/// per substep would cost a pass over every particle array on every step; one every 64 steps
/// costs a 64th of that (measured in docs/reliability.md). Rolling back the whole interval also
/// undoes an instability that built up over several steps before a particle inverted.
///
/// Deterministic: a rollback restores every SimState array bit for bit and forgets the step
/// history (the moisture CG's initial guess), so the redone steps are a function of the state
/// alone, like those of a run resumed from a checkpoint.
#include <cstdint>
#include <string>

#include "sim/core/types.h"
#include "sim/model.h"
#include "sim/mpm/simulation.h"

namespace mudcrack {

/// How failed substeps are retried.
struct RetryPolicy {
    int max_halvings = 10;       // dt floor = the stable dt / 2^max_halvings; a failure there stops
    int grow_after = 16;         // accepted steps at a reduced dt before it doubles back
    int snapshot_interval = 64;  // accepted steps between rollback points
};

/// What one attempt at a substep did.
struct StepAttempt {
    bool is_accepted = false;        // false: `state` was rolled back to the rollback point
    bool is_rollback_point = false;  // accepted, and `state` is now the rollback point
    StepStats stats;                 // of the accepted step
    std::string failure;             // rejected: the step's message (what failed, where)
};

/// Steps a state with rollback and retry (see the file comment). One per run; restart() at
/// each frame start makes a frame's steps independent of the frames before it, so a run
/// resumed from a frame's checkpoint retries exactly as an uninterrupted one. S: the state's
/// precision (SimStateOf).
template <class S>
class RetryingStepperOf {
public:
    explicit RetryingStepperOf(const RetryPolicy& policy = {});

    /// Makes a copy of `state` the rollback point and forgets any reduced time step.
    void restart(const SimStateOf<S>& state);

    /// The factor on the stable time step: 1, or 2^-k while k halvings are in force.
    Real dt_scale() const;

    /// Advances `state` by one substep of `dt` (the caller's stable dt times dt_scale(), possibly
    /// shortened to land on a frame end). When step() fails its checks, restores the rollback
    /// point into `state`, halves the time step and returns is_accepted = false: the caller
    /// restores its own counters saved at the last is_rollback_point (or restart) and goes on.
    /// @throws RuntimeError with step()'s message and the retries it took, when the time step
    ///         is already at its floor
    StepAttempt attempt(const SimModel& model, SimStateOf<S>& state, Real dt);

    /// Simulated time of the rollback point [s].
    double rollback_time() const { return m_snapshot.time; }
    /// Rollbacks since construction.
    int64_t retries() const { return m_retries; }
    /// Bytes held by the rollback point's copy of the state.
    int64_t memory_bytes() const;

private:
    void take_snapshot(const SimStateOf<S>& state);

    RetryPolicy m_policy;
    SimStateOf<S> m_snapshot;  // the rollback point (no workspace)
    int m_halvings = 0;        // dt = stable dt / 2^m_halvings
    int m_accepted_since = 0;  // accepted steps since the rollback point
    int64_t m_retries = 0;
};

using RetryingStepper = RetryingStepperOf<double>;

}  // namespace mudcrack
