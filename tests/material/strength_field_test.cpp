// The heterogeneous strength field: its multipliers have the requested mean and spread, its
// Gaussian field the requested variance and correlation length (measured on samples), a seed
// gives one field bit for bit and another seed another one; the Weibull map is the quantile; even
// azimuths leave the modes no preferred pair of horizontal directions, where random ones have one.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "sim/material/strength_field.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
constexpr double kSampleVariance = 0.1;      // a sampled field's variance vs 1 (finite domain)
constexpr double kSampleCorrelation = 0.08;  // a sampled correlation vs the kernel's
constexpr double kSampleMean = 0.05;         // a sampled field's mean vs 1
constexpr double kTabulated = 1e-3;          // a value against its 4-digit table entry
// the 2- and 4-theta moments of N = 256 azimuths: about N^-1.5 stratified (0.001-0.003 on seeds
// 1-8), about N^-0.5 independent (0.02-0.09)
constexpr double kEvenMoment = 0.01;
constexpr double kRandomMomentMean = 0.03;

// a lattice of n^3 points at `spacing`
std::vector<Vec3> lattice(int n, Real spacing) {
    std::vector<Vec3> x;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) x.emplace_back(i * spacing, j * spacing, k * spacing);
    return x;
}

Real mean_of(const std::vector<Real>& v) {
    Real s = 0;
    for (Real a : v) s += a;
    return s / v.size();
}

Real variance_of(const std::vector<Real>& v) {
    const Real m = mean_of(v);
    Real s = 0;
    for (Real a : v) s += (a - m) * (a - m);
    return s / v.size();
}

TEST(StrengthField, GaussianFieldHasUnitVarianceAndTheRequestedCorrelationLength) {
    // averaged over 8 seeds: one realisation's sample covariance scatters by ~(l / L)^(3/2)
    const Real l = 0.1;
    StrengthFieldParams params;
    params.correlation_length = l;
    const std::vector<Vec3> x = lattice(24, l / 2);  // 12 correlation lengths a side
    Real variance = 0, corr_l = 0, corr_2l = 0;
    const int seeds = 8;
    for (int seed = 1; seed <= seeds; ++seed) {
        const StrengthField f = make_strength_field(params, static_cast<uint64_t>(seed));
        std::vector<Real> g(x.size());
        for (size_t i = 0; i < x.size(); ++i) g[i] = strength_field_gaussian(f, x[i]);
        const Real m = mean_of(g), v = variance_of(g);
        variance += v / seeds;
        // correlation at lags l and 2l along each axis: target exp(-1/2) and exp(-2)
        auto correlation = [&](int lag) {
            Real c = 0;
            int n = 0;
            auto at = [](int i, int j, int k) { return (i * 24 + j) * 24 + k; };
            for (int i = 0; i < 24; ++i)
                for (int j = 0; j < 24; ++j)
                    for (int k = 0; k < 24; ++k) {
                        const Real ga = g[at(i, j, k)] - m;
                        if (i + lag < 24) c += ga * (g[at(i + lag, j, k)] - m), ++n;
                        if (j + lag < 24) c += ga * (g[at(i, j + lag, k)] - m), ++n;
                        if (k + lag < 24) c += ga * (g[at(i, j, k + lag)] - m), ++n;
                    }
            return c / n / v;
        };
        corr_l += correlation(2) / seeds;
        corr_2l += correlation(4) / seeds;
    }
    EXPECT_NEAR(variance, 1.0, kSampleVariance);
    EXPECT_NEAR(corr_l, std::exp(-0.5), kSampleCorrelation)
        << "correlation at one correlation length";
    EXPECT_NEAR(corr_2l, std::exp(-2.0), kSampleCorrelation)
        << "correlation at two correlation lengths";
    // the correlation length a fit of exp(-r^2 / (2 l^2)) to the lag-l value gives
    EXPECT_NEAR(l / std::sqrt(-2 * std::log(corr_l)), l, 0.15 * l);
}

TEST(StrengthField, MultipliersHaveMeanOneAndTheWeibullSpread) {
    for (Real modulus : {2.0, 4.0, 8.0}) {
        StrengthFieldParams params;
        params.correlation_length = 0.02;
        params.weibull_modulus = modulus;
        // many correlation lengths, so the sample is close to the distribution
        const std::vector<Real> m =
            strength_multipliers(make_strength_field(params, 7), lattice(40, 0.02));
        EXPECT_NEAR(mean_of(m), 1.0, kSampleMean) << "modulus " << modulus;
        EXPECT_NEAR(std::sqrt(variance_of(m)), weibull_cv(modulus), 0.2 * weibull_cv(modulus))
            << "modulus " << modulus;
        for (Real v : m) ASSERT_GT(v, 0);
    }
    EXPECT_NEAR(weibull_cv(4), 0.2805, kTabulated);  // the tabulated value
}

TEST(StrengthField, WeibullQuantileOfTheNormalCdf) {
    // g = 0 is the median: scale (log 2)^(1/m)
    EXPECT_NEAR(weibull_of_gaussian(0, 4, 1), std::pow(std::log(2.0), 0.25), tol::kRoundoffKernel);
    // monotone, and the upper tail keeps its digits
    Real last = 0;
    for (Real g = -6; g <= 8; g += 0.5) {
        const Real v = weibull_of_gaussian(g, 3, 1);
        EXPECT_GT(v, last) << g;
        EXPECT_TRUE(std::isfinite(v)) << g;
        last = v;
    }
}

// |mean of exp(i n phi_k)| over the modes, phi_k the azimuth of w_k about the vertical
Real azimuth_moment(const StrengthField& f, int n) {
    std::complex<Real> sum = 0;
    for (const Vec3& w : f.frequency) sum += std::polar(Real(1), n * std::atan2(w.z(), w.x()));
    return std::abs(sum) / static_cast<Real>(f.frequency.size());
}

TEST(StrengthField, EvenAzimuthsPreferNoPairOfDirectionsWhereRandomOnesDo) {
    // a pair of perpendicular directions is the 4-theta moment (a large slab's cracks follow
    // it: docs/physics.md §6.1), one direction the 2-theta moment
    StrengthFieldParams even, random;
    random.azimuths = ModeAzimuths::Random;
    constexpr int kSeeds = 20;
    Real random_mean = 0;
    for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
        const StrengthField e = make_strength_field(even, seed);
        EXPECT_LT(azimuth_moment(e, 4), kEvenMoment) << "seed " << seed;
        EXPECT_LT(azimuth_moment(e, 2), kEvenMoment) << "seed " << seed;
        random_mean += azimuth_moment(make_strength_field(random, seed), 4) / kSeeds;
    }
    EXPECT_GT(random_mean, kRandomMomentMean);
}

TEST(StrengthField, EvenAzimuthsTurnEachRandomModeAboutTheVerticalOnly) {
    // the same stream up to the turn: each mode keeps its phase, its vertical part and its
    // length across, so its distribution is the isotropic Gaussian's and a random field (the
    // shots measured on it) keeps its bits
    StrengthFieldParams even, random;
    random.azimuths = ModeAzimuths::Random;
    const StrengthField e = make_strength_field(even, 5), r = make_strength_field(random, 5);
    ASSERT_EQ(e.frequency.size(), r.frequency.size());
    int turned = 0;
    for (size_t k = 0; k < e.frequency.size(); ++k) {
        EXPECT_EQ(e.phase[k], r.phase[k]);
        EXPECT_EQ(e.frequency[k].y(), r.frequency[k].y());
        EXPECT_NEAR(std::hypot(e.frequency[k].x(), e.frequency[k].z()),
                    std::hypot(r.frequency[k].x(), r.frequency[k].z()),
                    tol::kRoundoffKernel * r.frequency[k].norm());
        turned += e.frequency[k].x() != r.frequency[k].x();
    }
    EXPECT_GT(turned, 0);
}

TEST(StrengthField, SameSeedSameBitsOtherSeedOtherField) {
    StrengthFieldParams params;
    const std::vector<Vec3> x = lattice(10, 0.03);
    const std::vector<Real> a = strength_multipliers(make_strength_field(params, 3), x);
    const std::vector<Real> b = strength_multipliers(make_strength_field(params, 3), x);
    const std::vector<Real> c = strength_multipliers(make_strength_field(params, 4), x);
    ASSERT_EQ(a.size(), b.size());
    int same_as_other = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i], b[i]);
        same_as_other += a[i] == c[i];
    }
    EXPECT_EQ(same_as_other, 0);
}

}  // namespace
}  // namespace mudcrack
