// NACC return mapping (docs/physics.md §2.2): inside states unchanged, outside states on the yield
// surface, both tips, hardening on/off, wet side hardens and dry side softens, agreement with an
// independent plain-Eigen evaluation of 2.2 on a random sweep, and finiteness at the extremes.
#include "sim/material/nacc.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <array>
#include <random>

#include "material/material_samples.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

const LameParams kLame{740.74, 2222.2};  // E = 2000, nu = 0.35 (Table 1)

NaccParams params(Real M = 1.87, Real xi = 1, bool hardening = true) {
    NaccParams n;
    n.M = M;
    n.xi = xi;
    n.hardening = hardening;
    return n;
}

/// p and ||s_hat|| of a state with singular values sigma, using the elastic J `J_for_s` in
/// s_hat = mu J^(-2/3) dev(sigma^2) (pass prod sigma for the state's own J).
std::pair<Real, Real> pressure_and_shear(const Vec3& sigma, Real J_for_s, const LameParams& lame) {
    const Real J = sigma.prod();
    const Vec3 b = sigma.cwiseProduct(sigma);
    const Vec3 s = lame.mu * std::pow(J_for_s, -2.0 / 3) * (b.array() - b.sum() / 3).matrix();
    return {-lame.kappa / 2 * (J * J - 1), s.norm()};
}

/// Size of y on the ellipse: its value at the centre p_c with s = 0, M^2 ((1+beta) p0 / 2)^2.
Real yield_scale(Real p0, Real beta, Real M) { return M * M * std::pow((1 + beta) * p0 / 2, 2); }

/// Singular values with elastic J and a volume-preserving deviatoric stretch exp(+-dev).
Vec3 sigma_with(Real J, Real dev) { return std::cbrt(J) * Vec3(std::exp(dev), 1, std::exp(-dev)); }

// ---------------------------------------------------------------------------------------------
// Independent evaluation of docs/physics.md §2.2, written from the text with plain Eigen: JacobiSVD
// with its own sign fix, std::pow for the powers, the case-3b hardening as the PhysBAM-form
// quadratic in p (ziran2019), not the ray intersection the kernel uses.
struct Reference {
    Mat3 Fe;
    Real alpha;
    int yield_case;
};

Reference reference_return_map(const Mat3& Fe_trial, Real alpha, Real beta, const NaccParams& n,
                               const LameParams& lame) {
    const int d = 3;
    const Real mu = lame.mu, kappa = lame.kappa, M = n.M;
    Eigen::JacobiSVD<Mat3> svd(Fe_trial, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 U = svd.matrixU(), V = svd.matrixV();
    Vec3 sigma = svd.singularValues();
    if (U.determinant() < 0) {
        U.col(2) *= -1;
        sigma(2) *= -1;
    }
    if (V.determinant() < 0) {
        V.col(2) *= -1;
        sigma(2) *= -1;
    }

    const Real p0 =
        kappa * (1e-5 + std::sinh(std::min(n.xi * std::max(-alpha, 0.0), kNaccMaxSinhArgument)));
    const Real J = sigma.prod();
    const Vec3 b_hat = sigma.cwiseProduct(sigma);
    const Vec3 s_hat = mu * std::pow(J, -2.0 / d) * (b_hat.array() - b_hat.sum() / d).matrix();
    const Real p = -(kappa / 2) * (J * J - 1);
    const Real q = std::sqrt((6.0 - d) / 2) * s_hat.norm();
    const Real a = (6.0 - d) / 2 * (1 + 2 * beta);

    Reference r{Fe_trial, alpha, 0};
    if (p > p0 || p < -beta * p0) {
        const Real J_new =
            p > p0 ? std::sqrt(1 - 2 * p0 / kappa) : std::sqrt(1 + 2 * beta * p0 / kappa);
        r.Fe = U * Vec3::Constant(std::pow(J_new, 1.0 / d)).asDiagonal() * V.transpose();
        if (n.hardening) r.alpha += std::log(J / J_new);
        r.yield_case = p > p0 ? 1 : 2;
        return r;
    }
    const Real y = (1 + 2 * beta) * q * q + M * M * (p + beta * p0) * (p - p0);
    if (y < kNaccInsideTolerance * kappa * kappa) return r;

    const Real q_target_sq = -M * M * (p + beta * p0) * (p - p0) / (1 + 2 * beta);
    const Real s_new_norm = std::sqrt(q_target_sq / ((6.0 - d) / 2));
    const Vec3 b_hat_new =
        (std::pow(J, 2.0 / d) / mu * s_new_norm * s_hat / s_hat.norm()).array() + b_hat.sum() / d;
    r.Fe = U * b_hat_new.cwiseSqrt().asDiagonal() * V.transpose();
    r.yield_case = 3;

    const Real tol = kNaccPressureTolerance * kappa;
    if (n.hardening && p0 > tol && p < p0 - tol && p > -beta * p0 + tol) {
        const Real p_c = (1 - beta) * p0 / 2;
        const Real aa = M * M * (p - p_c) * (p - p_c) / (a * s_hat.squaredNorm());
        const Real qa = 1 + aa, qb = aa * beta * p0 - aa * p0 - 2 * p_c,
                   qc = p_c * p_c - aa * beta * p0 * p0;
        const Real root = std::sqrt(std::abs(qb * qb - 4 * qa * qc));
        const Real p1 = (-qb + root) / (2 * qa), p2 = (-qb - root) / (2 * qa);
        const Real p_fake = (p - p_c) * (p1 - p_c) > 0 ? p1 : p2;
        const Real J_fake = std::sqrt(std::abs(1 - 2 * p_fake / kappa));
        if (J_fake > kNaccMinFakeJ) r.alpha += std::log(J / J_fake);
    }
    return r;
}

TEST(NaccReference, SweepOfRandomStatesMatchesIndependentEvaluation) {
    std::mt19937_64 rng(2019);
    std::uniform_real_distribution<Real> u(0, 1);
    std::array<int, 4> case_count{};
    const int n_states = 4000;
    for (int i = 0; i < n_states; ++i) {
        const NaccParams n =
            params(1 + 1.5 * u(rng), std::array<Real, 3>{0.5, 1, 3}[i % 3], i % 5 != 0);
        const Real beta = 2.5 * u(rng);
        const Real alpha = -0.6 + 0.7 * u(rng);
        const Real log_J = 0.5 * (u(rng) - 0.5);
        const Real dev = 0.3 * u(rng);
        std::normal_distribution<Real> g(0, 1);
        const Vec3 sigma =
            std::exp(log_J / 3) *
            Vec3(std::exp(dev * g(rng)), std::exp(dev * g(rng)), std::exp(dev * g(rng)));
        const Mat3 Fe = test::with_singular_values(rng, sigma);

        const NaccReturn got = nacc_return_map(Fe, alpha, beta, n, kLame);
        const Reference want = reference_return_map(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(got.yield_case, want.yield_case) << "state #" << i << " Fe =\n"
                                                   << Fe << "\nalpha " << alpha;
        ++case_count[got.yield_case];
        EXPECT_LE((got.Fe - want.Fe).norm(), tol::kRoundoffLoose * Fe.norm())
            << "state #" << i << " case " << got.yield_case;
        EXPECT_NEAR(got.alpha, want.alpha, tol::kRoundoffLoose * (1 + std::abs(alpha)))
            << "state #" << i << " case " << got.yield_case;
        // the returned SVD is the SVD of the returned Fe
        EXPECT_LE((got.svd.U * got.svd.sigma.asDiagonal() * got.svd.V.transpose() - got.Fe).norm(),
                  tol::kRoundoff * got.Fe.norm());
    }
    for (int c = 0; c < 4; ++c)
        EXPECT_GE(case_count[c], n_states / 20) << "too few states in case " << c;
}

TEST(NaccProject, MatchesReturnMapWithoutItsSvd) {
    std::mt19937_64 rng(2020);
    std::uniform_real_distribution<Real> u(0, 1);
    std::array<int, 4> case_count{};
    for (int i = 0; i < 4000; ++i) {
        const NaccParams n =
            params(1 + 1.5 * u(rng), std::array<Real, 3>{0.5, 1, 3}[i % 3], i % 5 != 0);
        const Real beta = 2.5 * u(rng), alpha = -0.6 + 0.7 * u(rng);
        const Real J = std::exp(0.5 * (u(rng) - 0.5));
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(J, 0.3 * u(rng)));
        const NaccReturn full = nacc_return_map(Fe, alpha, beta, n, kLame);
        const NaccProjection fast = nacc_project(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(fast.yield_case, full.yield_case) << "state #" << i << " Fe =\n" << Fe;
        ++case_count[fast.yield_case];
        // J = det Fe against prod sigma: the same to a few ulps, so alpha to a few 1e-16
        EXPECT_LE((fast.Fe - full.Fe).norm(), tol::kRoundoffKernel * Fe.norm()) << "state #" << i;
        EXPECT_NEAR(fast.alpha, full.alpha, tol::kRoundoffKernel) << "state #" << i;
        if (fast.yield_case == kNaccInside) {
            EXPECT_TRUE(fast.Fe == Fe) << "inside: bitwise unchanged";
        }
    }
    for (int c = 0; c < 4; ++c) EXPECT_GE(case_count[c], 200) << "too few states in case " << c;
}

// g(b) is interpolated at b's eigenvalues, which the cubic gives only to sqrt(eps) when two
// coincide: repeated, nearly repeated (1e-12 to 1e-4 apart) and all-equal stretches, each
// pushed out of the yield surface (both tips and the projection), return as the SVD path does.
TEST(NaccProject, RepeatedAndNearlyRepeatedStretchesReturnAsWithTheSvd) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<Real> u(0, 1);
    const NaccParams n = params(1.87, 1);
    std::array<int, 4> case_count{};
    for (int i = 0; i < 3000; ++i) {
        const Real J = std::exp(0.5 * (u(rng) - 0.5)), dev = 0.3 * u(rng);
        const Real gap = std::pow(10.0, -12 + 8 * u(rng));  // the near pair's relative distance
        Vec3 stretch;
        switch (i % 4) {
            case 0: stretch = Vec3(std::exp(dev), std::exp(dev), std::exp(-2 * dev)); break;
            case 1:
                stretch = Vec3(std::exp(dev), std::exp(dev) * (1 + gap), std::exp(-2 * dev));
                break;
            case 2:
                stretch = Vec3(std::exp(2 * dev), std::exp(-dev) * (1 + gap), std::exp(-dev));
                break;
            default: stretch = Vec3(1 + gap, 1, 1 - gap); break;
        }
        const Vec3 sigma = std::cbrt(J / stretch.prod()) * stretch;
        const Mat3 Fe = test::with_singular_values(rng, sigma);
        const Real beta = 2.5 * u(rng), alpha = -0.6 + 0.7 * u(rng);
        const NaccReturn full = nacc_return_map(Fe, alpha, beta, n, kLame);
        const NaccProjection fast = nacc_project(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(fast.yield_case, full.yield_case) << "state #" << i << " Fe =\n" << Fe;
        ++case_count[fast.yield_case];
        // the SVD's own U and V are ill-determined within a nearly repeated pair: 1e-13 there
        EXPECT_LE((fast.Fe - full.Fe).norm(), tol::kRoundoff * Fe.norm())
            << "state #" << i << " sigma = " << sigma.transpose();
    }
    for (int c = 1; c < 4; ++c) EXPECT_GE(case_count[c], 100) << "too few states in case " << c;
}

// Fe_new = g(b) Fe keeps Fe's rotation and has b_new = c0 I + s b: checked on the map alone,
// for c0 and s that no return produces too, against g(b) from a long-double eigendecomposition
// of b (distinct, repeated and nearly repeated stretches), to a few ulps of ||Fe_new||.
TEST(NaccProject, BMapIsTheMatrixFunctionOfBWithFesRotation) {
    using Mat3L = Eigen::Matrix<long double, 3, 3>;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<Real> u(0, 1);
    for (int i = 0; i < 2000; ++i) {
        Vec3 sigma(std::exp(u(rng) - 0.5), std::exp(u(rng) - 0.5), std::exp(u(rng) - 0.5));
        if (i % 2) sigma(1) = sigma(0) * (1 + std::pow(10.0, -14 + 12 * u(rng)));
        if (i % 10 == 9) sigma(2) = sigma(0);
        const Mat3 Fe = test::with_singular_values(rng, sigma);
        NaccBMap map;
        map.c0 = 2 * u(rng);
        map.s = u(rng);
        Mat3 got;
        ASSERT_TRUE(apply_nacc_b_map(map, neo_hookean_terms(Fe, kLame).b, Fe, got));
        const Mat3L FeL = Fe.cast<long double>();
        const Eigen::SelfAdjointEigenSolver<Mat3L> eig(FeL * FeL.transpose());
        const auto g = (map.c0 / eig.eigenvalues().array() + map.s).sqrt().matrix();
        const Mat3L want =
            eig.eigenvectors() * g.asDiagonal() * eig.eigenvectors().transpose() * FeL;
        EXPECT_LE((got.cast<long double>() - want).norm(), tol::kRoundoffKernel * want.norm())
            << "state #" << i << " sigma = " << sigma.transpose();
    }
    // singular and badly conditioned b are refused (the caller takes the SVD)
    NaccBMap map;
    map.c0 = 1;
    map.s = 0.5;
    Mat3 untouched = Mat3::Identity();
    const Mat3 flat = Vec3(1, 1, 1e-4).asDiagonal();
    EXPECT_FALSE(apply_nacc_b_map(map, neo_hookean_terms(flat, kLame).b, flat, untouched));
    EXPECT_TRUE(untouched == Mat3::Identity());
}

TEST(NaccReturnMap, InsideStateIsReturnedUnchanged) {
    std::mt19937_64 rng(1);
    const NaccParams n = params(1.87, 1);
    for (int i = 0; i < 200; ++i) {
        const Mat3 Fe = test::with_singular_values(
            rng, sigma_with(0.98 + 0.04 * (i % 10) / 10, 0.001 * (i % 7)));
        const NaccReturn r = nacc_return_map(Fe, -0.3, 0.5, n, kLame);
        ASSERT_EQ(r.yield_case, kNaccInside) << "Fe =\n" << Fe;
        EXPECT_TRUE(r.Fe == Fe) << "Fe must come back bitwise unchanged";
        EXPECT_EQ(r.alpha, -0.3);
    }
}

TEST(NaccReturnMap, ProjectedStatesLandOnTheYieldSurface) {
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<Real> u(0, 1);
    int projected = 0;
    for (int i = 0; i < 2000; ++i) {
        const NaccParams n = params(1 + u(rng), 1 + 2 * u(rng), true);
        const Real beta = 2 * u(rng), alpha = -0.5 * u(rng);
        const Real p0 = nacc_p0(alpha, n.xi, kLame.kappa);
        // p strictly between the tips, deviatoric strain large enough to be outside
        const Real p_max = std::min(p0, 0.45 * kLame.kappa);  // J real and not tiny
        const Real p = -beta * p0 + (0.05 + 0.9 * u(rng)) * (p_max + beta * p0);
        const Real J = std::sqrt(1 - 2 * p / kLame.kappa);
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(J, 0.05 + 0.5 * u(rng)));
        const Real scale = yield_scale(p0, beta, n.M);
        for (bool preserve_volume : {false, true}) {
            const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame, preserve_volume);
            if (r.yield_case != kNaccProjected) continue;
            ++projected;
            const Real J_trial = svd3(Fe).sigma.prod();
            if (preserve_volume) {
                // exact J: the returned state itself satisfies y = 0
                const auto [p_new, s_new] =
                    pressure_and_shear(r.svd.sigma, r.svd.sigma.prod(), kLame);
                EXPECT_NEAR(r.svd.sigma.prod(), J_trial, tol::kRoundoff);
                EXPECT_NEAR(nacc_yield(p_new, s_new, p0, beta, n.M), 0, tol::kRoundoffLoose * scale)
                    << "Fe =\n"
                    << Fe;
            } else {
                // reference semantics: tr(b_hat) is kept and s is scaled radially at the trial
                // J and p, so y(p_trial, s_new(J_trial)) = 0
                const auto [p_unused, s_new] = pressure_and_shear(r.svd.sigma, J_trial, kLame);
                (void)p_unused;
                const Vec3 sigma_trial = svd3(Fe).sigma;
                EXPECT_NEAR(r.svd.sigma.squaredNorm(), sigma_trial.squaredNorm(),
                            tol::kRoundoff * sigma_trial.squaredNorm());
                EXPECT_NEAR(nacc_yield(p, s_new, p0, beta, n.M), 0, tol::kRoundoffLoose * scale)
                    << "Fe =\n"
                    << Fe;
                // shrinking the deviator at fixed trace can only raise det: the reference code's
                // J drift is always an expansion
                EXPECT_GE(r.svd.sigma.prod(), J_trial * (1 - tol::kRoundoff));
            }
        }
    }
    EXPECT_GT(projected, 2000);
}

TEST(NaccReturnMap, CompressionTip) {
    std::mt19937_64 rng(3);
    const Real alpha = -0.05, beta = 1;
    for (bool hardening : {true, false}) {
        const NaccParams n = params(1.87, 1, hardening);
        const Real p0 = nacc_p0(alpha, n.xi, kLame.kappa);
        // p = 0.255 kappa > p0
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(0.7, 0.2));
        const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(r.yield_case, kNaccCompressionTip);
        const Real J_new = std::sqrt(1 - 2 * p0 / kLame.kappa);
        EXPECT_NEAR(r.Fe.determinant(), J_new, tol::kRoundoff);
        // deviatoric part removed: Fe = J_new^(1/3) R
        EXPECT_LE((r.Fe * r.Fe.transpose() - std::pow(J_new, 2.0 / 3) * Mat3::Identity()).norm(),
                  tol::kRoundoff);
        if (hardening) {
            EXPECT_NEAR(r.alpha, alpha + std::log(0.7 / J_new), tol::kRoundoff);
            EXPECT_LT(r.alpha, alpha);  // compaction hardens
        } else {
            EXPECT_EQ(r.alpha, alpha);
        }
    }
}

TEST(NaccReturnMap, TensionTip) {
    std::mt19937_64 rng(4);
    const Real alpha = -0.05, beta = 0.8;
    for (bool hardening : {true, false}) {
        const NaccParams n = params(1.87, 1, hardening);
        const Real p0 = nacc_p0(alpha, n.xi, kLame.kappa);
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(1.3, 0.1));  // p = -0.345 kappa
        const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(r.yield_case, kNaccTensionTip);
        const Real J_new = std::sqrt(1 + 2 * beta * p0 / kLame.kappa);
        EXPECT_NEAR(r.Fe.determinant(), J_new, tol::kRoundoff);
        EXPECT_LE((r.Fe * r.Fe.transpose() - std::pow(J_new, 2.0 / 3) * Mat3::Identity()).norm(),
                  tol::kRoundoff);
        if (hardening) {
            EXPECT_NEAR(r.alpha, alpha + std::log(1.3 / J_new), tol::kRoundoff);
            EXPECT_GT(r.alpha, alpha);  // tension softens
        } else {
            EXPECT_EQ(r.alpha, alpha);
        }
    }
}

TEST(NaccReturnMap, StrengthScalesTheYieldPressure) {
    // a heterogeneous soil's multiplier s moves both tips: p0 -> s p0
    std::mt19937_64 rng(11);
    const Real alpha = -0.3, beta = 0.8;
    const NaccParams n = params(1.87, 1, true);
    const Real p0 = nacc_p0(alpha, n.xi, kLame.kappa);
    for (Real strength : {0.25, 0.5, 2.0}) {
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(1.6, 0.05));  // far in tension
        const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame, false, strength);
        ASSERT_EQ(r.yield_case, kNaccTensionTip) << strength;
        EXPECT_NEAR(r.Fe.determinant(), std::sqrt(1 + 2 * beta * strength * p0 / kLame.kappa),
                    tol::kRoundoff)
            << strength;
        // and a state inside the stronger ellipse is outside the weaker one
        const Real J_between = std::sqrt(1 + 2 * beta * 0.75 * strength * p0 / kLame.kappa) * 1.0;
        const Mat3 F_mid = test::with_singular_values(rng, sigma_with(J_between, 0));
        EXPECT_EQ(nacc_return_map(F_mid, alpha, beta, n, kLame, false, strength).yield_case,
                  kNaccInside)
            << strength;
        EXPECT_EQ(nacc_return_map(F_mid, alpha, beta, n, kLame, false, strength / 2).yield_case,
                  kNaccTensionTip)
            << strength;
    }
}

TEST(NaccReturnMap, WetSideHardensDrySideSoftens) {
    std::mt19937_64 rng(5);
    const Real alpha = -0.3, beta = 0.5;
    const NaccParams n = params(1.87, 1, true);
    const Real p0 = nacc_p0(alpha, n.xi, kLame.kappa);
    const Real p_c = (1 - beta) * p0 / 2;
    for (Real fraction : {0.1, 0.3, 0.45, 0.55, 0.7, 0.9}) {
        // p from just above the tension tip (dry) to just below the compression tip (wet)
        const Real p = -beta * p0 + fraction * (1 + beta) * p0;
        const Real J = std::sqrt(1 - 2 * p / kLame.kappa);
        const Mat3 Fe = test::with_singular_values(rng, sigma_with(J, 0.4));
        const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame);
        ASSERT_EQ(r.yield_case, kNaccProjected) << "fraction " << fraction;
        if (p > p_c) {
            EXPECT_LT(r.alpha, alpha) << "wet side (p > p_c) must harden, fraction " << fraction;
        } else {
            EXPECT_GT(r.alpha, alpha) << "dry side (p < p_c) must soften, fraction " << fraction;
        }
        const NaccReturn off = nacc_return_map(Fe, alpha, beta, params(1.87, 1, false), kLame);
        EXPECT_EQ(off.alpha, alpha);
        EXPECT_TRUE(off.Fe == r.Fe) << "hardening changes alpha only";
    }
}

TEST(NaccP0, FloorAndOverflowCap) {
    EXPECT_DOUBLE_EQ(nacc_p0(0.5, 3, 2000), 2000 * 1e-5);  // alpha >= 0: the floor only
    EXPECT_NEAR(nacc_p0(-0.1, 2, 2000), 2000 * (1e-5 + std::sinh(0.2)), tol::kRoundoff * 2000);
    const Real capped = nacc_p0(-1e6, 3, 2000);
    EXPECT_TRUE(std::isfinite(capped));
    EXPECT_DOUBLE_EQ(capped, 2000 * (1e-5 + std::sinh(kNaccMaxSinhArgument)));
    EXPECT_DOUBLE_EQ(nacc_p0(-std::numeric_limits<Real>::infinity(), 3, 2000), capped);
}

TEST(NaccP0, LowerBoundIsBelowAndWithin2e10) {
    constexpr Real kappa = 2000, xi = 1;
    for (Real x = 0; x <= kNaccMaxSinhArgument + 1; x += 1.0 / 64) {
        const Real exact = nacc_p0(-x, xi, kappa), lower = nacc_p0_lower_bound(-x, xi, kappa);
        // below up to a few ulps of rounding (both sides of x = 1.5)
        EXPECT_LE(lower, exact * (1 + 8 * std::numeric_limits<Real>::epsilon())) << "x = " << x;
        EXPECT_GE(lower, exact * (1 - 2e-10)) << "x = " << x;
    }
    EXPECT_EQ(nacc_p0_lower_bound(0.5, 3, kappa), kappa * 1e-5);  // alpha >= 0: the floor only
}

TEST(NaccReturnMap, ExtremeStatesStayFinite) {
    std::mt19937_64 rng(6);
    const Mat3 R = test::random_rotation(rng), Q = test::random_rotation(rng);
    const std::vector<std::pair<std::string, Mat3>> states = {
        {"J=1e-9", R * Vec3(1e-3, 1e-3, 1e-3).asDiagonal() * Q.transpose()},
        {"J=1e-30 sheared", R * Vec3(1e-5, 1e-10, 1e-15).asDiagonal() * Q.transpose()},
        {"J=1e-300", R * Vec3(1e-100, 1e-100, 1e-100).asDiagonal() * Q.transpose()},
        {"rank 2 (J=0)", R * Vec3(1, 0.5, 0).asDiagonal() * Q.transpose()},
        {"zero", Mat3::Zero()},
        {"stretch 1e3", R * Vec3(1e3, 1e3, 1e3).asDiagonal() * Q.transpose()},
        {"stretch 1e100 (J overflows)", R * Vec3(1e100, 1e100, 1e100).asDiagonal() * Q.transpose()},
        {"stretch 1e150 sheared", R * Vec3(1e150, 1, 1e-3).asDiagonal() * Q.transpose()},
        {"inverted", R * Vec3(1.2, 1, -0.8).asDiagonal() * Q.transpose()},
        {"inverted near zero", R * Vec3(1, 1, -1e-12).asDiagonal() * Q.transpose()},
    };
    for (Real alpha : {0.0, -0.05, -1.0, -1e3, -1e300}) {  // -1e3 and below: sinh would overflow
        for (Real beta : {0.0, 1.0, 2.5}) {
            for (const auto& [name, Fe] : states) {
                const NaccParams n = params(1.87, 3, true);
                const NaccReturn r = nacc_return_map(Fe, alpha, beta, n, kLame);
                SCOPED_TRACE(name + " alpha " + std::to_string(alpha) + " beta " +
                             std::to_string(beta));
                EXPECT_TRUE(r.Fe.allFinite()) << r.Fe;
                EXPECT_TRUE(std::isfinite(r.alpha)) << r.alpha;
                EXPECT_TRUE(r.svd.sigma.allFinite() && r.svd.U.allFinite() && r.svd.V.allFinite());
                const NaccProjection projected = nacc_project(Fe, alpha, beta, n, kLame);
                EXPECT_TRUE(projected.Fe.allFinite() && std::isfinite(projected.alpha));
                EXPECT_TRUE(neo_hookean_kirchhoff(r.svd, kLame).allFinite() ||
                            r.svd.sigma.prod() == 0)
                    << "stress of the returned state, sigma = " << r.svd.sigma.transpose();
                // p0 >= kappa/2 (alpha <= -1 at xi = 3): the compression tip is unreachable
                if (nacc_p0(alpha, n.xi, kLame.kappa) >= kLame.kappa / 2) {
                    EXPECT_NE(r.yield_case, kNaccCompressionTip);
                }
            }
        }
    }
}

TEST(NaccYield, MatchesEquation8) {
    // y = (1 + 2 beta) q^2 + M^2 (p + beta p0)(p - p0) with q = sqrt(3/2) ||s||
    const Real p = 10, s = 4, p0 = 30, beta = 0.5, M = 1.5;
    const Real q = std::sqrt(1.5) * s;
    EXPECT_NEAR(nacc_yield(p, s, p0, beta, M),
                (1 + 2 * beta) * q * q + M * M * (p + beta * p0) * (p - p0), tol::kRoundoff);
    EXPECT_LT(nacc_yield(p, 0, p0, beta, M), 0);  // on the p axis between the tips: inside
    EXPECT_NEAR(nacc_yield(p0, 0, p0, beta, M), 0, tol::kRoundoff);          // compression tip
    EXPECT_NEAR(nacc_yield(-beta * p0, 0, p0, beta, M), 0, tol::kRoundoff);  // tension tip
}

}  // namespace
}  // namespace mudcrack
