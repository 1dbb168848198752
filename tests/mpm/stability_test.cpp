// Stiff and extreme cases: each run completes with a finite state or stops with a clear
// RuntimeError; none produces a silent NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mpm_test_util.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/mpm/simulation.h"

namespace mudcrack {
namespace {

using test::make_lattice;
using test::plain_model;

// a NACC soil block resting on a sticky ground under gravity, with moisture
using test::soil_model;

bool state_is_finite(const SimState& s) {
    for (size_t p = 0; p < s.size(); ++p) {
        if (!s.x[p].allFinite() || !s.v[p].allFinite() || !s.Fe[p].allFinite() ||
            !std::isfinite(s.J[p]))
            return false;
        if (!s.alpha.empty() && !std::isfinite(s.alpha[p])) return false;
        if (!s.theta.empty() && !std::isfinite(s.theta[p])) return false;
    }
    return true;
}

// runs `steps` adaptive steps; returns "completed" or the error message, and checks the contract
std::string run_checked(const SimModel& model, SimState& s, int steps) {
    try {
        for (int i = 0; i < steps; ++i) step(model, s, stable_dt(model, s));
    } catch (const RuntimeError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("substep"), std::string::npos) << msg;
        EXPECT_NE(msg.find("particle"), std::string::npos) << msg;
        return msg;
    }
    EXPECT_TRUE(state_is_finite(s));
    for (const Vec3& x : s.x) {
        EXPECT_TRUE((x.array() >= s.domain_min.array()).all()) << x.transpose();
        EXPECT_TRUE((x.array() <= s.domain_max.array()).all()) << x.transpose();
    }
    return "completed";
}

SimState soil_block(const SimModel& model) {
    const test::Lattice l = make_lattice(Vec3(0, 0, 0), Vec3i(6, 6, 6), model.h / 2);
    return make_initial_state(model, l.X, l.V0);
}

TEST(Stability, StiffSoilWithAdaptiveDt) {
    SimModel model = soil_model();
    model.elastic.youngs_modulus = 1e7;
    SimState s = soil_block(model);
    EXPECT_EQ(run_checked(model, s, 40), "completed");
    EXPECT_LT(stable_dt(model, s), 1e-3);  // the elastic bound took over
}

TEST(Stability, NearlyIncompressible) {
    SimModel model = soil_model();
    model.elastic.poisson_ratio = 0.49;
    SimState s = soil_block(model);
    EXPECT_EQ(run_checked(model, s, 40), "completed");
}

TEST(Stability, HighPorosityDryingFast) {
    SimModel model = soil_model();
    model.moisture->eta = 0.9;
    model.moisture->lambda = 50;
    model.moisture->D = 1;
    SimState s = soil_block(model);
    EXPECT_EQ(run_checked(model, s, 60), "completed");
    for (size_t p = 0; p < s.size(); ++p) {
        EXPECT_GE(s.theta[p], 0.0);
        EXPECT_LE(s.theta[p], 0.9);
        EXPECT_GE(s.Jw[p], 0.1 - 1e-12);
    }
}

TEST(Stability, HardeningPastSinhOverflow) {
    SimModel model = soil_model();
    model.nacc->alpha0 = -1000;  // xi * max(-alpha, 0) = 3000 > 710: sinh overflows in double
    SimState s = soil_block(model);
    const std::string result = run_checked(model, s, 20);
    SUCCEED() << result;
}

TEST(Stability, HugeDiffusionNumber) {
    SimModel model = soil_model();
    model.time.dt_fixed = 1e-3;
    model.elastic.youngs_modulus = 1e3;
    model.moisture->D = 1e4 * model.h * model.h / model.time.dt_fixed;  // D dt / h^2 = 1e4
    model.moisture->cg_max_iterations = 50;
    SimState s = soil_block(model);
    EXPECT_EQ(run_checked(model, s, 5), "completed");
}

TEST(Stability, ParticlesThrownAtTheWalls) {
    SimModel model = soil_model();
    model.domain.is_auto = false;
    model.domain.min = Vec3(-0.5, -0.5, -0.5);
    model.domain.max = Vec3(0.8, 0.8, 0.8);
    model.initial_velocity = Vec3(300, -200, 100);
    SimState s = soil_block(model);
    EXPECT_EQ(run_checked(model, s, 200), "completed");
}

TEST(Stability, NonPositiveDtIsRefused) {
    SimModel model = soil_model();
    SimState s = soil_block(model);
    EXPECT_THROW(step(model, s, 0), RuntimeError);
    EXPECT_THROW(step(model, s, std::nan("")), RuntimeError);
}

}  // namespace
}  // namespace mudcrack
