// Rollback and retry of failed substeps (sim/mpm/step_retry.h): nothing changes while nothing
// fails; a failure restores the rollback point bit for bit; an unstable fixed dt recovers at a
// smaller one, deterministically; a state that fails at every dt stops with the step's message.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "mpm_test_util.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/mpm/simulation.h"
#include "sim/mpm/step_retry.h"

namespace mudcrack {
namespace {

using test::make_lattice;
using test::plain_model;

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// every array of the state and its clock, bit for bit
::testing::AssertionResult same_state(const SimState& a, const SimState& b) {
    if (std::memcmp(&a.time, &b.time, sizeof(double)) != 0 || a.step_count != b.step_count)
        return ::testing::AssertionFailure() << "clock " << a.time << " / " << a.step_count
                                             << " vs " << b.time << " / " << b.step_count;
    if (!same_bits(a.id, b.id) || !same_bits(a.x, b.x) || !same_bits(a.v, b.v) ||
        !same_bits(a.C, b.C) || !same_bits(a.Fe, b.Fe) || !same_bits(a.J, b.J) ||
        !same_bits(a.alpha, b.alpha) || !same_bits(a.V0, b.V0) || !same_bits(a.mass, b.mass) ||
        !same_bits(a.theta, b.theta) || !same_bits(a.Jw, b.Jw))
        return ::testing::AssertionFailure() << "particle arrays differ";
    return ::testing::AssertionSuccess();
}

// a drying NACC soil block dropped on a sticky ground: every part of the step runs
SimModel soil_model() {
    SimModel m = test::soil_model();
    m.initial_velocity = Vec3(0, -1, 0);
    return m;
}

SimState block(const SimModel& model) {
    const test::Lattice l = make_lattice(Vec3(0, 0.05, 0), Vec3i(6, 6, 6), model.h / 2);
    return make_initial_state(model, l.X, l.V0);
}

// runs `steps` accepted substeps through the stepper
void run(const SimModel& model, SimState& s, RetryingStepper& stepper, int steps) {
    stepper.restart(s);
    for (int accepted = 0; accepted < steps;)
        accepted += stepper.attempt(model, s, stable_dt(model, s) * stepper.dt_scale()).is_accepted;
}

TEST(StepRetry, WhileNothingFailsTheStepsAreThoseOfStep) {
    const SimModel model = soil_model();
    SimState plain = block(model), retried = block(model);
    for (int i = 0; i < 150; ++i) step(model, plain, stable_dt(model, plain));
    RetryingStepper stepper;
    run(model, retried, stepper, 150);  // crosses two rollback points (every 64 steps)
    EXPECT_EQ(stepper.retries(), 0);
    EXPECT_EQ(stepper.dt_scale(), 1);
    EXPECT_TRUE(same_state(plain, retried));
}

TEST(StepRetry, AFailedStepRestoresTheRollbackPointBitForBit) {
    const SimModel model = soil_model();
    SimState s = block(model);
    for (int i = 0; i < 20; ++i) step(model, s, stable_dt(model, s));  // a state with history
    RetryingStepper stepper;
    stepper.restart(s);
    const SimState rollback_point = s;
    for (int i = 0; i < 10; ++i)
        ASSERT_TRUE(stepper.attempt(model, s, stable_dt(model, s)).is_accepted);
    // one particle thrown so fast that the next step fails its checks
    const Real dt = stable_dt(model, s);
    s.v[7] = Vec3(0, 0, 1000 * model.h / dt);
    const StepAttempt a = stepper.attempt(model, s, dt);
    EXPECT_FALSE(a.is_accepted);
    EXPECT_NE(a.failure.find("substep"), std::string::npos) << a.failure;
    EXPECT_TRUE(same_state(s, rollback_point));
    EXPECT_EQ(stepper.retries(), 1);
    EXPECT_EQ(stepper.dt_scale(), 0.5);
    EXPECT_EQ(stepper.rollback_time(), rollback_point.time);
}

// dt fixed at 3x the elastic bound, which the shot loader refuses
SimModel unstable_model() {
    SimModel m = soil_model();
    m.time.dt_fixed = 3 * elastic_dt_bound(m);
    return m;
}

TEST(StepRetry, AnUnstableFixedDtRecoversAtASmallerOne) {
    const SimModel model = unstable_model();
    SimState plain = block(model);
    EXPECT_THROW(for (int i = 0; i < 200; ++i) step(model, plain, stable_dt(model, plain)),
                 RuntimeError);

    SimState s = block(model);
    RetryingStepper stepper;
    run(model, s, stepper, 200);
    EXPECT_GT(stepper.retries(), 0);
    for (size_t p = 0; p < s.size(); ++p) {
        ASSERT_TRUE(s.x[p].allFinite() && s.v[p].allFinite() && s.J[p] > 0)
            << "particle " << s.id[p];
    }
    // the same run again takes the same retries, bit for bit
    SimState again = block(model);
    RetryingStepper stepper_again;
    run(model, again, stepper_again, 200);
    EXPECT_EQ(stepper_again.retries(), stepper.retries());
    EXPECT_TRUE(same_state(again, s));
}

TEST(StepRetry, AtTheFloorItStopsWithTheStepsMessage) {
    const SimModel model = soil_model();
    SimState s = block(model);
    s.Fe[17](0, 1) = std::numeric_limits<Real>::quiet_NaN();  // fails at any dt
    RetryPolicy policy;
    policy.max_halvings = 3;
    RetryingStepper stepper(policy);
    stepper.restart(s);
    const Real dt = stable_dt(model, s);
    for (int k = 1; k <= 3; ++k) {
        EXPECT_FALSE(stepper.attempt(model, s, dt * stepper.dt_scale()).is_accepted);
        EXPECT_EQ(stepper.dt_scale(), std::ldexp(1.0, -k));
    }
    try {
        stepper.attempt(model, s, dt * stepper.dt_scale());
        ADD_FAILURE() << "a step failing at the floor was not reported";
    } catch (const RuntimeError& e) {
        const std::string msg = e.what();
        // the NaN reaches its neighbours through the grid in the same step
        EXPECT_NE(msg.find("substep 1: particle "), std::string::npos) << msg;
        EXPECT_NE(msg.find(" has non-finite "), std::string::npos) << msg;
        EXPECT_NE(msg.find("halved 3 times"), std::string::npos) << msg;
        EXPECT_NE(msg.find("1/8 of the stable step"), std::string::npos) << msg;
    }
    EXPECT_EQ(stepper.retries(), 3);
}

}  // namespace
}  // namespace mudcrack
