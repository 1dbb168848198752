// The reduced `make report`: the accuracy sweeps at small scale with their fitted
// orders asserted, and every stability case asserted to end without a silent NaN, hang or crash.
// The bounds below were set from measured orders (mc-report --quick, see tools/report) with margin.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <string>

#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "tolerance.h"
#include "tools/report/accuracy.h"
#include "tools/report/fit.h"
#include "tools/report/report_writer.h"
#include "tools/report/stability.h"

namespace mudcrack::report {
namespace {

// measured 1.98 on h = 0.04, 0.02, 0.01 (lumped-mass quadratic B-splines, dt ~ h^2: 2)
constexpr Real kMinDiffusion1dOrderInH = 1.7;
// measured 0.99 on the time error (backward Euler: 1)
constexpr Real kMinDiffusionOrderInDt = 0.8;
constexpr Real kMaxDiffusionOrderInDt = 1.2;
// measured 1.62 on 4, 6, 8 cells per side (the pre-asymptotic coarse end of a second-order scheme)
constexpr Real kMinDiffusion3dOrderInH = 1.3;
// measured 1.09 (the free top surface is resolved to O(h))
constexpr Real kMinColumnOrderInH = 0.8;
// measured 1.4e-2 at h = 0.025 (H = 0.5 m, 20 cells)
constexpr Real kMaxColumnErrorFinest = 0.03;
// the moisture solved every k steps against every step: the difference per step of k - 1 at
// k = 4 and 8 within this factor of k = 2's (measured 1.00 and 1.00, double and float), and
// k = 2's RMS theta difference under this share of eta (measured 7.9e-4)
constexpr Real kIntervalLinearity = 1.5;
constexpr Real kMaxIntervalTwoError = 2e-3;
// a free block that dries fully ends at (1 - eta) V0 within 1 % (measured <= 3e-4)
constexpr Real kMaxShrinkageError = 0.01;

Real last_error(const Sweep& s) { return s.points.back().error; }

TEST(ReportFit, LogLogSlopeRecoversAPowerLaw) {
    const std::vector<Real> x = {0.1, 0.05, 0.025, 0.0125};
    std::vector<Real> y;
    for (Real v : x) y.push_back(3.0 * std::pow(v, 1.5));
    EXPECT_NEAR(log_log_slope(x, y), 1.5, tol::kRoundoffLoose);
    // zero errors (a converged reference) are left out, a single point has no slope
    y.back() = 0;
    EXPECT_NEAR(log_log_slope(x, y), 1.5, tol::kRoundoffLoose);
    EXPECT_TRUE(std::isnan(log_log_slope({0.1}, {1.0})));
}

// every accuracy claim holds with a double and with a float particle state
class ReportAccuracy : public ::testing::TestWithParam<StatePrecision> {};

TEST_P(ReportAccuracy, Diffusion1dConvergesInHAndDt) {
    const Sweep h = sweep_diffusion_1d_h(Scale::Reduced, GetParam());
    EXPECT_GE(h.order, kMinDiffusion1dOrderInH);
    EXPECT_LT(last_error(h), 1e-3);  // of a jump of 0.25
    const Sweep dt = sweep_diffusion_1d_dt(Scale::Reduced, GetParam());
    EXPECT_GE(dt.order, kMinDiffusionOrderInDt);
    EXPECT_LE(dt.order, kMaxDiffusionOrderInDt);
}

TEST_P(ReportAccuracy, Diffusion3dConvergesInH) {
    const Sweep s = sweep_diffusion_3d_h(Scale::Reduced, GetParam());
    EXPECT_GE(s.order, kMinDiffusion3dOrderInH);
    EXPECT_LT(last_error(s), s.points.front().error);
}

// The grid operator (/moisture/diffusion_operator "grid") converges to the same solutions at the
// same orders: it is another discretisation of the same equation, not a coarser one.
TEST_P(ReportAccuracy, GridOperatorDiffusionConvergesInH) {
    const Sweep bar = sweep_diffusion_1d_h(Scale::Reduced, GetParam(), DiffusionOperator::Grid);
    EXPECT_GE(bar.order, kMinDiffusion1dOrderInH);
    EXPECT_LT(last_error(bar), 1e-3);
    const Sweep cube = sweep_diffusion_3d_h(Scale::Reduced, GetParam(), DiffusionOperator::Grid);
    EXPECT_GE(cube.order, kMinDiffusion3dOrderInH);
    EXPECT_LT(last_error(cube), cube.points.front().error);
}

TEST_P(ReportAccuracy, FreeDryingBlockEndsAtDryVolume) {
    for (const Sweep& s : {sweep_shrinkage_h(Scale::Reduced, GetParam()),
                           sweep_shrinkage_ppc(Scale::Reduced, GetParam())})
        for (const SweepPoint& p : s.points)
            EXPECT_LT(p.error, kMaxShrinkageError) << s.id << " knob " << p.knob;
}

TEST_P(ReportAccuracy, ColumnSettlementConvergesInH) {
    const Sweep s = sweep_column_h(Scale::Reduced, GetParam());
    EXPECT_GE(s.order, kMinColumnOrderInH);
    EXPECT_LT(last_error(s), kMaxColumnErrorFinest);
}

TEST_P(ReportAccuracy, FiveCgIterationsSufficeInThePapersRegime) {
    const std::vector<Sweep> sweeps = sweep_cg_caps(Scale::Reduced, GetParam());
    ASSERT_FALSE(sweeps.empty());
    for (const Sweep& s : sweeps) {
        // more iterations never move further from the converged solve
        for (size_t i = 1; i < s.points.size(); ++i)
            EXPECT_LE(s.points[i].error, s.points[i - 1].error * (1 + 1e-9) + tol::kRoundoff)
                << s.id;
        EXPECT_EQ(s.points.back().error, 0) << "the converged reference is the last point";
    }
    const Sweep& paper = sweeps.front();  // D dt / h^2 = 0.01, the paper's regime
    bool has_cap5 = false;
    for (const SweepPoint& p : paper.points) {
        if (p.knob != 5) continue;
        has_cap5 = true;
        EXPECT_LT(p.error, kCgClaimTolerance);
    }
    EXPECT_TRUE(has_cap5);
}

// A solve every k-th step (/moisture/interval) is backward Euler over k dt, its increment applied
// over the k steps after it: both that and the window's lag are first order in time, so the
// difference from a solve every step grows as (k - 1) dt.
TEST_P(ReportAccuracy, MoistureIntervalErrorGrowsAsTheIntervalLessOne) {
    const Sweep s = sweep_moisture_interval(Scale::Reduced, GetParam());
    ASSERT_EQ(s.points.size(), 4u);
    EXPECT_EQ(s.points.front().knob, 1);
    EXPECT_EQ(s.points.front().error, 0) << "the reference is a solve every step";
    const Real per_step_of_k2 = s.points[1].error / (s.points[1].knob - 1);
    EXPECT_GT(per_step_of_k2, 0);
    EXPECT_LT(s.points[1].error, kMaxIntervalTwoError) << "k = 2";
    for (size_t i = 2; i < s.points.size(); ++i) {
        const Real per_step = s.points[i].error / (s.points[i].knob - 1);
        EXPECT_GT(per_step, per_step_of_k2 / kIntervalLinearity) << "k = " << s.points[i].knob;
        EXPECT_LT(per_step, per_step_of_k2 * kIntervalLinearity) << "k = " << s.points[i].knob;
    }
}

INSTANTIATE_TEST_SUITE_P(Precisions, ReportAccuracy,
                         ::testing::Values(StatePrecision::Double, StatePrecision::Float),
                         [](const ::testing::TestParamInfo<StatePrecision>& info) {
                             return std::string(info.param == StatePrecision::Float ? "Float"
                                                                                    : "Double");
                         });

// a float sweep is its double twin's knobs with the state in float, named to be drawn beside it
TEST(ReportSweeps, AFloatSweepIsItsTwinInFloat) {
    const Sweep d = sweep_column_h(Scale::Reduced, StatePrecision::Double);
    const Sweep f = sweep_column_h(Scale::Reduced, StatePrecision::Float);
    EXPECT_EQ(d.precision, "double");
    EXPECT_EQ(f.precision, "float");
    EXPECT_EQ(f.id, d.id + kFloatSweepSuffix);
    ASSERT_EQ(f.points.size(), d.points.size());
    for (size_t i = 0; i < d.points.size(); ++i) {
        EXPECT_EQ(f.points[i].knob, d.points[i].knob);
        EXPECT_NE(f.points[i].error, d.points[i].error) << "the same error: not a float run";
    }
}

class StabilityMatrix : public ::testing::TestWithParam<std::string> {};

TEST_P(StabilityMatrix, EndsWithoutSilentNanHangOrCrash) {
    const StabilityLimits limits = stability_limits(Scale::Reduced);
    const StabilityResult r = run_stability_case(GetParam(), Scale::Reduced, limits);
    EXPECT_FALSE(is_product_failure(r.outcome)) << outcome_name(r.outcome) << ": " << r.message;
    // a failed substep is retried at a smaller dt (sim/mpm/step_retry.h): every case completes
    // or is refused at load
    EXPECT_NE(r.outcome, Outcome::StoppedWithError) << r.message;
    EXPECT_LE(r.steps, limits.max_steps);
    if (r.outcome == Outcome::Refused || r.outcome == Outcome::StoppedWithError) {
        EXPECT_FALSE(r.message.empty()) << "an error must say what went wrong";
    }
    if (r.outcome == Outcome::Completed) {
        EXPECT_EQ(r.steps, limits.max_steps);
        EXPECT_TRUE(std::isfinite(r.max_speed));
    }
    // the result survives the pipe of the isolated runner
    StabilityResult back;
    ASSERT_TRUE(parse_result(serialize_result(r), back));
    EXPECT_EQ(back.name, r.name);
    EXPECT_EQ(back.outcome, r.outcome);
    EXPECT_EQ(back.steps, r.steps);
    EXPECT_EQ(back.retries, r.retries);
    EXPECT_EQ(back.message, r.message);
}

std::vector<std::string> case_names() {
    std::vector<std::string> names;
    for (const StabilityCase& c : stability_cases()) names.push_back(c.name);
    return names;
}

INSTANTIATE_TEST_SUITE_P(Cases, StabilityMatrix, ::testing::ValuesIn(case_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string n = info.param;
                             for (char& ch : n)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return n;
                         });

// the cases that stopped with "J <= 0" before substeps were retried: they complete, with retries
TEST(StabilityRecovery, InvertingCasesCompleteThroughRetries) {
    for (const char* name : {"wall_impact_200", "sinh_overflow_drying", "dt_past_bound_forced"}) {
        const StabilityResult r =
            run_stability_case(name, Scale::Reduced, stability_limits(Scale::Reduced));
        EXPECT_EQ(r.outcome, Outcome::Completed) << name << ": " << r.message;
        EXPECT_GT(r.retries, 0) << name;
    }
}

// every case also runs as "<case>/float", with its state in float
TEST(StabilityPrecision, EachCaseRunsInBothPrecisions) {
    const std::vector<StabilityCase> cases = stability_cases();
    ASSERT_EQ(cases.size() % 2, 0u);
    for (size_t i = 0; i < cases.size(); i += 2)
        EXPECT_EQ(cases[i + 1].name, cases[i].name + kFloatCaseSuffix);
    const StabilityLimits limits = stability_limits(Scale::Reduced);
    const StabilityResult d = run_stability_case("nu_0.45", Scale::Reduced, limits);
    const StabilityResult f = run_stability_case("nu_0.45/float", Scale::Reduced, limits);
    EXPECT_EQ(f.name, "nu_0.45/float");
    EXPECT_EQ(d.outcome, Outcome::Completed) << d.message;
    EXPECT_EQ(f.outcome, Outcome::Completed) << f.message;
    EXPECT_NE(f.energy_drift, d.energy_drift) << "the same drift to the bit: not a float run";
    EXPECT_THROW(run_stability_case("no_such_case/float", Scale::Reduced, limits), InputError);
}

// a float state rounds a nearly singular Fe: at full scale the 200 m/s corner impact left 305
// particles with det Fe <= 0 and no error (J, kept in double, stayed > 0) before the step checked
// the stored Fe; now such a step is retried like any inverted one
TEST(StabilityRecovery, AFloatStateRetriesAnInvertedFeInsteadOfKeepingIt) {
    const StabilityResult r =
        run_stability_case("wall_impact_200/float", Scale::Full, stability_limits(Scale::Full));
    EXPECT_EQ(r.outcome, Outcome::Completed) << r.message;
    EXPECT_GT(r.retries, 0);
    EXPECT_TRUE(std::isfinite(r.energy_growth));
}

TEST(StabilityRefusals, FixedDtPastTheElasticBoundIsRefusedByTheShotLoader) {
    const StabilityResult r =
        run_stability_case("dt_past_bound_shot", Scale::Reduced, stability_limits(Scale::Reduced));
    EXPECT_EQ(r.outcome, Outcome::Refused) << r.message;
    EXPECT_NE(r.message.find("exceeds the elastic bound"), std::string::npos) << r.message;
}

TEST(StabilityRefusals, FlatTetWithZeroRestVolumeIsRefused) {
    const StabilityResult r =
        run_stability_case("tet_flat", Scale::Reduced, stability_limits(Scale::Reduced));
    EXPECT_EQ(r.outcome, Outcome::Refused) << r.message;
    EXPECT_NE(r.message.find("volume0 0"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace mudcrack::report
