#include "sim/material/strength_field.h"

#include <cmath>
#include <random>

#include "sim/core/check.h"
#include "sim/core/parallel.h"

namespace mudcrack {

namespace {

// uniform in (0, 1) from 53 random bits of the generator: mt19937_64's output is specified
// bit for bit by the standard, std::uniform_real_distribution's and std::normal_distribution's
// algorithms are not, so the field is the same with any standard library
Real open_unit(std::mt19937_64& rng) {
    return (static_cast<Real>(rng() >> 11) + Real(0.5)) * 0x1.0p-53;
}

// one standard normal by Box-Muller (the cosine branch)
Real standard_normal(std::mt19937_64& rng) {
    const Real u = open_unit(rng), v = open_unit(rng);
    return std::sqrt(-2 * std::log(u)) * std::cos(2 * kPi * v);
}

}  // namespace

StrengthField make_strength_field(const StrengthFieldParams& params, uint64_t seed) {
    MC_CHECK(params.correlation_length > 0 && params.weibull_modulus > 0);
    // a stream of its own: the lattice jitter and the mesher draw from the same shot seed
    std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
    // the strata's offsets on a stream of their own, so that an even field is the random one's
    // modes turned about the vertical, mode for mode
    std::mt19937_64 azimuth_rng(seed ^ 0xbf58476d1ce4e5b9ull);
    StrengthField f;
    f.frequency.resize(kStrengthFieldModes);
    f.phase.resize(kStrengthFieldModes);
    const Real inv_l = 1 / params.correlation_length;
    for (int k = 0; k < kStrengthFieldModes; ++k) {
        for (int d = 0; d < 3; ++d) f.frequency[k][d] = standard_normal(rng) * inv_l;
        f.phase[k] = 2 * kPi * open_unit(rng);
        if (params.azimuths == ModeAzimuths::Even) {
            // the same length and vertical part, turned about the vertical into stratum k
            const Real azimuth = 2 * kPi * (k + open_unit(azimuth_rng)) / kStrengthFieldModes;
            const Real across = std::hypot(f.frequency[k].x(), f.frequency[k].z());
            f.frequency[k].x() = across * std::cos(azimuth);
            f.frequency[k].z() = across * std::sin(azimuth);
        }
    }
    f.weibull_modulus = params.weibull_modulus;
    f.weibull_scale = 1 / std::tgamma(1 + 1 / params.weibull_modulus);
    return f;
}

Real strength_field_gaussian(const StrengthField& field, const Vec3& x) {
    Real sum = 0;
    for (size_t k = 0; k < field.phase.size(); ++k)
        sum += std::cos(field.frequency[k].dot(x) + field.phase[k]);
    return std::sqrt(Real(2) / static_cast<Real>(field.phase.size())) * sum;
}

Real weibull_of_gaussian(Real g, Real modulus, Real scale) {
    // 1 - Phi(g) = erfc(g / sqrt 2) / 2 directly, so the upper tail keeps its digits
    const Real survival = Real(0.5) * std::erfc(g / std::sqrt(Real(2)));
    return scale * std::pow(-std::log(survival), 1 / modulus);
}

std::vector<Real> strength_multipliers(const StrengthField& field, const std::vector<Vec3>& rest) {
    std::vector<Real> m(rest.size());
    parallel_for(static_cast<int64_t>(rest.size()), [&](int64_t p) {
        m[p] = weibull_of_gaussian(strength_field_gaussian(field, rest[p]), field.weibull_modulus,
                                   field.weibull_scale);
    });
    return m;
}

Real weibull_cv(Real modulus) {
    const Real g1 = std::tgamma(1 + 1 / modulus), g2 = std::tgamma(1 + 2 / modulus);
    return std::sqrt(g2 / (g1 * g1) - 1);
}

}  // namespace mudcrack
