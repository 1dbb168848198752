#include "sim/mpm/step_retry.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

#include "sim/core/error.h"

namespace mudcrack {

RetryingStepper::RetryingStepper(const RetryPolicy& policy) : m_policy(policy) {}

void RetryingStepper::take_snapshot(const SimState& state) {
    // copy assignment reuses the arrays' capacity: no allocation after the first snapshot
    m_snapshot = state;  // the snapshot holds no workspace (a copy gets its own)
    m_accepted_since = 0;
}

void RetryingStepper::restart(const SimState& state) {
    take_snapshot(state);
    m_halvings = 0;
}

Real RetryingStepper::dt_scale() const { return std::ldexp(Real(1), -m_halvings); }

StepAttempt RetryingStepper::attempt(const SimModel& model, SimState& state, Real dt) {
    StepAttempt a;
    try {
        a.stats = step(model, state, dt);
    } catch (const RuntimeError& e) {
        a.failure = e.what();
    }
    if (a.failure.empty()) {
        a.is_accepted = true;
        ++m_accepted_since;
        // a reduced dt that held for grow_after steps doubles back, from a rollback point here
        const bool is_growing = m_halvings > 0 && m_accepted_since >= m_policy.grow_after;
        if (is_growing || m_accepted_since >= m_policy.snapshot_interval) {
            take_snapshot(state);
            a.is_rollback_point = true;
            if (is_growing) --m_halvings;
        }
        return a;
    }

    // the floor: the step's own message, and how far the retries went
    if (m_halvings >= m_policy.max_halvings) {
        char note[200];
        std::snprintf(
            note, sizeof note,
            "; retried from t = %.9g s with the time step halved %d times, down to dt = %.6g s "
            "(the floor: 1/%d of the stable step)",
            m_snapshot.time, m_halvings, double(dt), 1 << m_policy.max_halvings);
        throw RuntimeError(a.failure + note);
    }

    // roll back: every array and the moisture flux history bit for bit (the workspace stays)
    state = m_snapshot;
    m_accepted_since = 0;
    ++m_halvings;
    ++m_retries;
    return a;
}

int64_t RetryingStepper::memory_bytes() const { return state_memory_bytes(m_snapshot); }

}  // namespace mudcrack
