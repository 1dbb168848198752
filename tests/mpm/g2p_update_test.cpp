// The G2P's per-particle update (docs/physics.md §7 steps 4-8) against the paper's equations, one
// step on a handful of particles: the pore update (Eq. 6 Jw, Eq. 10 Fe compensation, Eq. 11 mass,
// Eq. 12 saturation hardening) and the SVD-free "clearly inside" test in front of the NACC return
// map (Eq. 8). Each check is written from the equation, not from the kernels the G2P calls, so a
// changed sign, factor or exponent in the G2P or in sim/moisture/pore.h fails here in
// milliseconds instead of in the figure-claim integration tests.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>

#include "material/material_samples.h"
#include "mpm_test_util.h"
#include "sim/core/parallel.h"
#include "sim/material/nacc.h"
#include "sim/material/neo_hookean.h"
#include "sim/mpm/g2p_impl.h"
#include "sim/mpm/simulation.h"
#include "sim/mpm/workspace.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// alpha after a return map against its closed form
constexpr double kReturnMapAlpha = 1e-10;

using test::make_lattice;
using test::plain_model;

// a soil with pores and NACC whose particles start at rest, unstressed (Fe = I) and hardened far
// inside the yield surface (alpha0 = -2: p0 = 3.6 kappa), so the return map leaves them alone and
// only the pore update moves Fe and alpha. No diffusion and no evaporation: theta stays put.
SimModel pore_model() {
    SimModel m = plain_model(0.1);
    m.nacc = NaccParams{};
    m.nacc->alpha0 = -2;
    m.nacc->beta0 = 0.3;
    m.nacc->beta1 = 0.1;
    m.moisture = MoistureParams{};
    m.moisture->eta = 0.4;
    m.moisture->k_r = 1.5;
    m.moisture->eps = 0.7;
    m.moisture->D = 0;
    m.moisture->lambda = 0;
    m.moisture->max_log_jw_step = 0;  // uncapped: Jw reaches its target in one step
    return m;
}

// Jw of Eq. 6 from its two-phase form: solid (1 - eta) keeps its volume, pores keep s of theirs
Real eq6_jw(Real s, Real eta) { return (1 - eta) * (1 - s) + s; }

TEST(G2pPoreUpdate, OneStepFollowsEquations6To12) {
    const SimModel model = pore_model();
    const MoistureParams& mp = *model.moisture;
    const Real dt = 1e-3;
    const test::Lattice l = make_lattice(Vec3::Zero(), Vec3i(2, 2, 2), 0.05);
    SimState s = make_initial_state(model, l.X, l.V0);
    // per particle (by id): a saturation, and Jw off its target by a factor exp(offset): drying
    // (Jw above the target) and wetting (below), by large steps (log1p path) and small ones (the
    // series path of pore_step, |ratio - 1| < 1e-3)
    const Real sat[8] = {0.2, 0.2, 0.9, 0.9, 0.5, 0.5, 0.05, 1.0};
    const Real offset[8] = {0.06, -0.06, 0.1, -0.1, 4e-4, -4e-4, 0.03, -0.08};
    std::vector<Real> Jw_old(8), alpha_old(8);
    for (size_t p = 0; p < s.size(); ++p) {
        const int id = s.id[p];
        s.theta[p] = sat[id] * mp.eta;
        s.Jw[p] = eq6_jw(sat[id], mp.eta) * std::exp(offset[id]);
        Jw_old[id] = s.Jw[p];
        alpha_old[id] = s.alpha[p];
    }
    std::vector<Mat3> Fe_old(8);
    for (size_t p = 0; p < s.size(); ++p) Fe_old[s.id[p]] = s.Fe[p];
    step(model, s, dt);

    for (size_t p = 0; p < s.size(); ++p) {
        const int id = s.id[p];
        SCOPED_TRACE(testing::Message() << "particle " << id << ": s = " << sat[id]
                                        << ", log(Jw / target) = " << offset[id]);
        ASSERT_NEAR(s.theta[p], sat[id] * mp.eta, tol::kRoundoff)
            << "theta must not move (D = lambda = 0)";
        // Eq. 6: Jw = (1 - eta)(1 - s) + s
        const Real Jw_new = eq6_jw(sat[id], mp.eta);
        EXPECT_NEAR(s.Jw[p], Jw_new, tol::kRoundoff);
        // Eq. 12: alpha += eps log(Jw^{n+1} / Jw^n): drying (Jw falls) softens, wetting hardens
        const Real log_ratio = std::log(Jw_new / Jw_old[id]);
        EXPECT_NEAR(s.alpha[p] - alpha_old[id], mp.eps * log_ratio, tol::kRoundoff)
            << "alpha " << alpha_old[id] << " -> " << s.alpha[p];
        EXPECT_EQ(s.alpha[p] > alpha_old[id], Jw_new > Jw_old[id]) << "the sign of the hardening";
        // Eq. 10: Fe^{n+1} = (Jw^n / Jw^{n+1})^(1/3) (I + dt C) Fe^n, so Fe Fw keeps det F
        Mat3 dF = dt * s.C[p];
        dF.diagonal().array() += 1;
        const Mat3 Fe_expected = std::pow(Jw_old[id] / Jw_new, 1.0 / 3) * dF * Fe_old[id];
        EXPECT_LT((s.Fe[p] - Fe_expected).norm(), tol::kRoundoff) << "Fe =\n"
                                                                  << s.Fe[p] << "\nexpected\n"
                                                                  << Fe_expected;
        EXPECT_NEAR(s.Fe[p].determinant() * s.Jw[p],
                    dF.determinant() * Fe_old[id].determinant() * Jw_old[id], tol::kRoundoff);
        // Eq. 11: m = V0 (rho_s (1 - eta) + rho_w eta s), rho_w = rho_s / k_r
        const Real rho_s = model.elastic.density, rho_w = rho_s / mp.k_r;
        const Real mass = s.V0[p] * (rho_s * (1 - mp.eta) + rho_w * mp.eta * sat[id]);
        EXPECT_NEAR(s.mass[p], mass, tol::kRoundoff * mass);
    }
}

// the per-step cap on |log Jw ratio| (docs/physics.md §3.2): Jw moves by exactly the cap towards
// its target, and alpha by eps times it, with the sign of the change
TEST(G2pPoreUpdate, CappedStepHardensByEpsTimesTheCap) {
    SimModel model = pore_model();
    model.moisture->max_log_jw_step = 2e-3;
    const MoistureParams& mp = *model.moisture;
    const test::Lattice l = make_lattice(Vec3::Zero(), Vec3i(2, 1, 1), 0.05);
    SimState s = make_initial_state(model, l.X, l.V0);
    for (size_t p = 0; p < s.size(); ++p) {
        s.theta[p] = (s.id[p] == 0 ? 0.1 : 0.9) * mp.eta;
        s.Jw[p] = eq6_jw(0.5, mp.eta);  // id 0 dries, id 1 wets
    }
    const Real Jw0 = eq6_jw(0.5, mp.eta), alpha0 = s.alpha[0];
    step(model, s, 1e-3);
    for (size_t p = 0; p < s.size(); ++p) {
        const Real sign = s.id[p] == 0 ? -1 : 1;
        EXPECT_NEAR(std::log(s.Jw[p] / Jw0), sign * 2e-3, tol::kRoundoff) << "particle " << s.id[p];
        EXPECT_NEAR(s.alpha[p] - alpha0, sign * mp.eps * 2e-3, tol::kRoundoff)
            << "particle " << s.id[p];
    }
}

// the G2P skips the return map for states its SVD-free test finds clearly inside Eq. 8's yield
// surface; over states inside, projected and past both tips, its result is the return map's
TEST(G2pYield, FastInsideTestAgreesWithTheReturnMap) {
    SimModel model = plain_model(0.1);
    model.nacc = NaccParams{};
    model.nacc->beta0 = model.nacc->beta1 = 0.4;
    model.nacc->alpha0 = -0.2;
    const LameParams lame = lame_params(model.elastic);
    const Real dt = 1e-4;
    const test::Lattice l = make_lattice(Vec3::Zero(), Vec3i(4, 4, 4), 0.05);
    std::mt19937_64 rng(18);
    std::uniform_real_distribution<Real> u(0, 1);
    std::normal_distribution<Real> g(0, 1);
    SimState s = make_initial_state(model, l.X, l.V0);
    std::vector<Mat3> Fe_old(s.size());
    std::vector<Real> alpha_old(s.size());
    for (size_t p = 0; p < s.size(); ++p) {
        // volume and shear spread so that about half the states leave the surface
        const Real log_J = 0.12 * (u(rng) - 0.5), dev = 0.08 * u(rng);
        const Vec3 sigma =
            std::exp(log_J / 3) *
            Vec3(std::exp(dev * g(rng)), std::exp(dev * g(rng)), std::exp(dev * g(rng)));
        s.Fe[p] = test::with_singular_values(rng, sigma);
        s.alpha[p] = -0.3 * u(rng);
        Fe_old[s.id[p]] = s.Fe[p];
        alpha_old[s.id[p]] = s.alpha[p];
    }
    step(model, s, dt);
    int inside = 0, outside = 0;
    for (size_t p = 0; p < s.size(); ++p) {
        const int id = s.id[p];
        Mat3 dF = dt * s.C[p];
        dF.diagonal().array() += 1;
        const Mat3 Fe_trial = dF * Fe_old[id];
        const NaccReturn want =
            nacc_return_map(Fe_trial, alpha_old[id], model.nacc->beta1, *model.nacc, lame);
        (want.yield_case == kNaccInside ? inside : outside) += 1;
        EXPECT_LT((s.Fe[p] - want.Fe).norm(), 1e-10)
            << "particle " << id << " case " << want.yield_case;
        EXPECT_NEAR(s.alpha[p], want.alpha, kReturnMapAlpha)
            << "particle " << id << " case " << want.yield_case;
    }
    EXPECT_GT(inside, 8);
    EXPECT_GT(outside, 8);
}

// a lattice whose particles start on both sides of Eq. 8's surface (the G2P's "clearly inside"
// shortcut and the full return map both run) and squeeze under gravity
SimState mixed_yield_state(const SimModel& model, uint64_t seed) {
    const test::Lattice l = make_lattice(Vec3::Zero(), Vec3i(4, 4, 4), 0.05);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<Real> u(0, 1);
    std::normal_distribution<Real> g(0, 1);
    SimState s = make_initial_state(model, l.X, l.V0);
    for (size_t p = 0; p < s.size(); ++p) {
        const Real log_J = 0.12 * (u(rng) - 0.5), dev = 0.08 * u(rng);
        const Vec3 sigma =
            std::exp(log_J / 3) *
            Vec3(std::exp(dev * g(rng)), std::exp(dev * g(rng)), std::exp(dev * g(rng)));
        s.Fe[p] = test::with_singular_values(rng, sigma);
        s.alpha[p] = -0.3 * u(rng);
    }
    s.workspace.reset();  // Fe was edited: the stress cache (none yet here) must not be trusted
    return s;
}

SimModel mixed_yield_model() {
    SimModel model = plain_model(0.1);
    model.nacc = NaccParams{};
    model.nacc->beta0 = model.nacc->beta1 = 0.4;
    model.nacc->alpha0 = -0.2;
    return model;
}

// the stress G2P leaves for the next P2G is the Kirchhoff stress of the new Fe, bit for bit, on
// the inside shortcut's particles and on the returned ones alike
TEST(G2pStressCache, IsTheKirchhoffStressOfTheNewFe) {
    const SimModel model = mixed_yield_model();
    const LameParams lame = lame_params(model.elastic);
    SimState s = mixed_yield_state(model, 19);
    for (int k = 0; k < 3; ++k) {
        step(model, s, 1e-4);
        const SimWorkspace& ws = *s.workspace;
        ASSERT_EQ(ws.tau_step, s.step_count);
        ASSERT_EQ(ws.tau.size(), s.size());
        for (size_t p = 0; p < s.size(); ++p) {
            const Mat3 want = neo_hookean_kirchhoff(s.Fe[p], lame);
            const Mat3 got = ws.tau[p].matrix();
            EXPECT_EQ(0, std::memcmp(want.data(), got.data(), sizeof(Mat3)))
                << "step " << k << " slot " << p;
            EXPECT_LT((want - neo_hookean_first_piola(s.Fe[p], lame) * s.Fe[p].transpose()).norm(),
                      1e-9 * (1 + want.norm()));
        }
    }
}

// a run that drops its workspace before every step (so P2G computes tau from Fe, as after a
// checkpoint load or a rollback) stays bit for bit with one that uses G2P's stress each step
TEST(G2pStressCache, RecomputingFromFeChangesNoBit) {
    const SimModel model = mixed_yield_model();
    SimState cached = mixed_yield_state(model, 20), fresh = mixed_yield_state(model, 20);
    for (int k = 0; k < 20; ++k) {
        step(model, cached, 1e-4);
        fresh.workspace.reset();
        step(model, fresh, 1e-4);
    }
    cached.for_each_array([&](const char* name, const auto& a, ArrayPresence) {
        fresh.for_each_array([&](const char* other, const auto& b, ArrayPresence) {
            if constexpr (std::is_same_v<decltype(a), decltype(b)>) {
                if (std::string(name) == other) {
                    ASSERT_EQ(a.size(), b.size()) << name;
                    // bit for bit; an empty array (physics the model lacks) has no data to compare
                    if (!a.empty()) {
                        EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])))
                            << name;
                    }
                }
            }
        });
    });
}

// the G2P's kinematics on four particles at once: dF Fe and det dF within a few ulps of the exact
// products (a long double reference)
TEST(G2pLanes, KinematicsAreTheProductAndDeterminantToAFewUlps) {
    std::mt19937_64 rng(31);
    std::normal_distribution<Real> g(0, 0.3);
    Real worst_product = 0, worst_det = 0;
    for (int i = 0; i < 2000; ++i) {
        Mat3 dF[kLaneCount], Fe[kLaneCount];
        LaneMat3 dF_lanes, Fe_lanes;
        for (int l = 0; l < kLaneCount; ++l) {
            dF[l] = Mat3::Identity() + 0.01 * Mat3(Mat3::NullaryExpr([&] { return g(rng); }));
            Fe[l] = Mat3::Identity() + Mat3(Mat3::NullaryExpr([&] { return g(rng); }));
            for (int k = 0; k < 9; ++k) {
                dF_lanes.m[k][l] = dF[l](k);
                Fe_lanes.m[k][l] = Fe[l](k);
            }
        }
        const LaneMat3 product = mpm::g2p_detail::lanes_product(dF_lanes, Fe_lanes);
        const Lanes det = mpm::g2p_detail::lanes_determinant(dF_lanes);
        for (int l = 0; l < kLaneCount; ++l) {
            const Eigen::Matrix<long double, 3, 3> a = dF[l].cast<long double>(),
                                                   b = Fe[l].cast<long double>();
            const Eigen::Matrix<long double, 3, 3> exact = a * b;
            for (int k = 0; k < 9; ++k)
                worst_product = std::max(worst_product, Real(std::abs(product.m[k][l] - exact(k)) /
                                                             b.cwiseAbs().maxCoeff()));
            worst_det = std::max(worst_det, Real(std::abs(det[l] - a.determinant())));
        }
    }
    const Real eps = std::numeric_limits<Real>::epsilon();
    EXPECT_LT(worst_product, 4 * eps);  // |dF| ~ 1: an ulp or two of the largest term
    EXPECT_LT(worst_det, 8 * eps);
}

// the inside test on four particles at once decides as it does on one
TEST(G2pLanes, InsideTestDecidesAsTheScalarOne) {
    const SimModel model = mixed_yield_model();
    const LameParams lame = lame_params(model.elastic);
    std::mt19937_64 rng(37);
    std::uniform_real_distribution<Real> u(0, 1);
    std::normal_distribution<Real> g(0, 1);
    int inside = 0, outside = 0;
    for (int i = 0; i < 4000; ++i) {
        LaneMat3 F;
        Real p0[kLaneCount], beta[kLaneCount];
        Mat3 Fs[kLaneCount];
        for (int l = 0; l < kLaneCount; ++l) {
            const Real log_J = 0.12 * (u(rng) - 0.5), dev = 0.08 * u(rng);
            Fs[l] = test::with_singular_values(
                rng, std::exp(log_J / 3) * Vec3(std::exp(dev * g(rng)), std::exp(dev * g(rng)),
                                                std::exp(dev * g(rng))));
            for (int k = 0; k < 9; ++k) F.m[k][l] = Fs[l](k);
            p0[l] = nacc_p0_lower_bound(-0.3 * u(rng), model.nacc->xi, lame.kappa);
            beta[l] = 0.4 * u(rng);
        }
        const NeoHookeanLaneTerms t = neo_hookean_terms(F, lame);
        const LaneMask got = mpm::g2p_detail::clearly_inside_yield_surface(
            t.J, t.b, t.mean_b, t.shear, Lanes{p0[0], p0[1], p0[2], p0[3]},
            Lanes{beta[0], beta[1], beta[2], beta[3]}, *model.nacc, lame);
        for (int l = 0; l < kLaneCount; ++l) {
            const NeoHookeanTerms s = neo_hookean_terms(Fs[l], lame);
            const Real b[6] = {s.b.xx, s.b.yy, s.b.zz, s.b.xy, s.b.xz, s.b.yz};
            const bool want = mpm::g2p_detail::clearly_inside_yield_surface(
                s.J, b, s.mean_b, s.shear, p0[l], beta[l], *model.nacc, lame);
            ASSERT_EQ(got[l] != 0, want) << i << " lane " << l;
            (want ? inside : outside) += 1;
        }
    }
    EXPECT_GT(inside, 1000);
    EXPECT_GT(outside, 1000);
}

}  // namespace
}  // namespace mudcrack
