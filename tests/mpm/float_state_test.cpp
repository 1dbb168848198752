// The float particle state (SimStateFloat, /sim/precision "float"): what it stores, that its step
// is the double step rounded, that a copy continues bit for bit, and how far a drying run drifts
// from the double one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mpm_test_util.h"
#include "sim/mpm/simulation.h"

namespace mudcrack {
namespace {

using test::make_lattice;

// a drying NACC soil block with moisture, falling onto a sticky ground (test::soil_model), its
// lattice at h / 2 with the first particle 1.5 cells above the ground
struct DryingBlock {
    SimModel model = test::soil_model();
    test::Lattice lattice = make_lattice(Vec3(0, 0.15, 0), Vec3i(8, 6, 8), 0.05);
    DryingBlock() {
        model.ground->height = 0;
        model.initial_velocity = Vec3(0, -0.5, 0);
    }
};

template <class S>
void step_in_place(const SimModel& model, SimStateOf<S>& s, int steps) {
    for (int i = 0; i < steps; ++i) step(model, s, stable_dt(model, s));
}

// a copy of `s` (without its stress cache) after `steps` steps
template <class S>
SimStateOf<S> run(const SimModel& model, SimStateOf<S> s, int steps) {
    step_in_place(model, s, steps);
    return s;
}

// the positions a float state's step starts from, as doubles: the lattice rounded to float
std::vector<Vec3> rounded_to_float(const std::vector<Vec3>& X) {
    std::vector<Vec3> r(X.size());
    for (size_t p = 0; p < X.size(); ++p) r[p] = X[p].cast<float>().cast<Real>();
    return r;
}

TEST(FloatState, KeepsItsDirectionalArraysInHalfTheBytesAndItsScalarsInDouble) {
    const DryingBlock b;
    const SimState d = make_initial_state(b.model, b.lattice.X, b.lattice.V0);
    const SimStateFloat f = make_initial_state<float>(b.model, b.lattice.X, b.lattice.V0);
    ASSERT_EQ(d.size(), f.size());
    // x, v (3 numbers each), C and Fe (9 each): 24 numbers a particle, 4 bytes fewer each
    const int64_t saved = static_cast<int64_t>(d.size()) * 24 * 4;
    EXPECT_EQ(state_memory_bytes(d) - state_memory_bytes(f), saved);
    static_assert(sizeof(SimStateFloat::StateVec3) == 3 * sizeof(float));
    static_assert(std::is_same_v<decltype(f.J)::value_type, double>);
    static_assert(std::is_same_v<decltype(f.theta)::value_type, double>);
    static_assert(std::is_same_v<decltype(f.alpha)::value_type, double>);
}

// The step computes in double whatever the state keeps: from the same start (a lattice a float
// holds exactly, at rest but for a velocity a float holds), one float step is the double step's
// result rounded to float, bit for bit, and its scalars are the double step's exactly.
TEST(FloatState, OneStepIsTheDoubleStepRounded) {
    const DryingBlock b;
    const std::vector<Vec3> X = rounded_to_float(b.lattice.X);
    const SimState d = run(b.model, make_initial_state(b.model, X, b.lattice.V0), 1);
    const SimStateFloat f = run(b.model, make_initial_state<float>(b.model, X, b.lattice.V0), 1);
    const std::vector<size_t> sd = test::slot_of_id(d), sf = test::slot_of_id(f);
    for (size_t id = 0; id < d.size(); ++id) {
        const size_t i = sd[id], j = sf[id];
        ASSERT_TRUE(f.x[j] == d.x[i].cast<float>()) << "id " << id;
        ASSERT_TRUE(f.v[j] == d.v[i].cast<float>()) << "id " << id;
        ASSERT_TRUE(f.C[j] == d.C[i].cast<float>()) << "id " << id;
        ASSERT_TRUE(f.Fe[j] == d.Fe[i].cast<float>()) << "id " << id;
        ASSERT_EQ(f.J[j], d.J[i]) << "id " << id;
        ASSERT_EQ(f.theta[j], d.theta[i]) << "id " << id;
        ASSERT_EQ(f.alpha[j], d.alpha[i]) << "id " << id;
        ASSERT_EQ(f.mass[j], d.mass[i]) << "id " << id;
    }
}

// A copy has no stress cache (a resumed run, a rollback): its next step computes the stress from
// the stored Fe. The uninterrupted run's cache must be that same stress, so the two continue with
// the same bits; in float that is the stress of the rounded Fe, not of the one G2P had in hand.
TEST(FloatState, ACopyContinuesBitForBit) {
    const DryingBlock b;
    SimStateFloat a = make_initial_state<float>(b.model, b.lattice.X, b.lattice.V0);
    step_in_place(b.model, a, 10);
    SimStateFloat c = a;            // no workspace
    step_in_place(b.model, a, 10);  // with the stress its last step cached
    step_in_place(b.model, c, 10);
    ASSERT_EQ(a.size(), c.size());
    using test::same_bytes;
    EXPECT_TRUE(same_bytes(a.x, c.x));
    EXPECT_TRUE(same_bytes(a.v, c.v));
    EXPECT_TRUE(same_bytes(a.Fe, c.Fe));
    EXPECT_TRUE(same_bytes(a.J, c.J));
    EXPECT_TRUE(same_bytes(a.theta, c.theta));
}

// the largest differences between two runs' states, particle by particle
struct StateGap {
    Real x = 0, J = 0, theta = 0, alpha = 0;
};

template <class A, class B>
StateGap state_gap(const SimStateOf<A>& a, const SimStateOf<B>& b) {
    const std::vector<size_t> sa = test::slot_of_id(a), sb = test::slot_of_id(b);
    StateGap g;
    for (size_t id = 0; id < a.size(); ++id) {
        const size_t i = sa[id], j = sb[id];
        g.x = std::max(g.x, (a.x[i].template cast<Real>() - b.x[j].template cast<Real>()).norm());
        g.J = std::max(g.J, std::abs(a.J[i] - b.J[j]));
        g.theta = std::max(g.theta, std::abs(a.theta[i] - b.theta[j]));
        g.alpha = std::max(g.alpha, std::abs(a.alpha[i] - b.alpha[j]));
    }
    return g;
}

// How far a float state drifts from the double one in a run that falls, lands, yields and dries,
// against how far the double run itself moves when its start moves by float's roundoff (the
// lattice rounded to float): a drying soil amplifies any roundoff (a particle crosses the
// evaporating layer's edge or the yield surface a step earlier), so that is the scale to judge a
// float run by, not float's epsilon.
TEST(FloatState, ADryingRunDriftsNoMoreThanTheDoubleRunUnderFloatRoundoff) {
    const DryingBlock b;
    const int steps = 200;
    const SimState d = run(b.model, make_initial_state(b.model, b.lattice.X, b.lattice.V0), steps);
    const SimState d_rounded = run(
        b.model, make_initial_state(b.model, rounded_to_float(b.lattice.X), b.lattice.V0), steps);
    const SimStateFloat f =
        run(b.model, make_initial_state<float>(b.model, b.lattice.X, b.lattice.V0), steps);
    const StateGap float_gap = state_gap(f, d), roundoff_gap = state_gap(d_rounded, d);
    std::printf(
        "after %d steps, float - double: |x| %.3g m, J %.3g, theta %.3g, alpha %.3g; "
        "double from the rounded start - double: |x| %.3g m, J %.3g, theta %.3g, "
        "alpha %.3g\n",
        steps, float_gap.x, float_gap.J, float_gap.theta, float_gap.alpha, roundoff_gap.x,
        roundoff_gap.J, roundoff_gap.theta, roundoff_gap.alpha);
    EXPECT_GT(roundoff_gap.x, 0);  // the two starts differ
    EXPECT_LT(float_gap.x, 10 * roundoff_gap.x);
    EXPECT_LT(float_gap.J, 10 * roundoff_gap.J);
    EXPECT_LT(float_gap.theta, 10 * roundoff_gap.theta);
    EXPECT_LT(float_gap.alpha, 10 * roundoff_gap.alpha);
}

}  // namespace
}  // namespace mudcrack
