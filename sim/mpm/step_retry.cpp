#include "sim/mpm/step_retry.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

#include "sim/core/error.h"

namespace mudcrack {

template <class S>
RetryingStepperOf<S>::RetryingStepperOf(const RetryPolicy& policy) : m_policy(policy) {}

template <class S>
void RetryingStepperOf<S>::take_snapshot(const SimStateOf<S>& state) {
    // copy assignment reuses the arrays' capacity: no allocation after the first snapshot
    m_snapshot = state;  // the snapshot holds no workspace (a copy gets its own)
    m_accepted_since = 0;
}

template <class S>
void RetryingStepperOf<S>::restart(const SimStateOf<S>& state) {
    take_snapshot(state);
    m_halvings = 0;
}

template <class S>
Real RetryingStepperOf<S>::dt_scale() const {
    return std::ldexp(Real(1), -m_halvings);
}

template <class S>
StepAttempt RetryingStepperOf<S>::attempt(const SimModel& model, SimStateOf<S>& state, Real dt) {
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

template <class S>
int64_t RetryingStepperOf<S>::memory_bytes() const {
    return state_memory_bytes(m_snapshot);
}

template class RetryingStepperOf<double>;
template class RetryingStepperOf<float>;

}  // namespace mudcrack
