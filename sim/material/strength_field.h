#pragma once
/// Heterogeneous soil strength: a seeded, spatially correlated random field of multipliers on the
/// NACC yield pressure p0 (docs/physics.md §6.1).
///
/// Why: a uniform slab has no place to start a crack but its corners and the grid's own axes, so
/// the cracks it grows draw the grid; real soil has weak spots a few grains to a few centimetres
/// across, where cracks start and from which they wander. The multiplier scales p0, so it survives
/// the drying hardening (alpha only moves p0's sinh argument) where noise added to alpha0 does not.
///
/// The field is g(x) = sqrt(2/N) sum_k cos(w_k . x + phi_k) over N random Fourier modes, with
/// w_k ~ Normal(0, I / l^2) (its azimuth stratified, ModeAzimuths) and phi_k ~ Uniform(0, 2 pi): a
/// stationary field of mean 0, variance 1 and covariance exp(-|r|^2 / (2 l^2)) (Rahimi and Recht
/// 2007), Gaussian in the limit of many modes. Each value is mapped through the normal CDF onto a
/// Weibull distribution of modulus m scaled to mean 1, the distribution fracture mechanics uses for
/// the strength of brittle material (a smaller m: more spread, weaker weakest spots). A function of
/// position and seed only, so it does not depend on the particle order or count.
#include <cstdint>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

/// How the field's modes share out the horizontal directions of their wave vectors.
///
/// Why: a sum of N plane waves whose azimuths are drawn independently prefers one pair of
/// perpendicular directions by chance: the mean of exp(4 i phi_k) over the modes is about
/// 1 / sqrt(N) (0.03-0.09 on seeds 1-8 at N = 256), and every wave runs across the whole body,
/// so a large slab's weak valleys can keep that pair, and its cracks with them (docs/physics.md
/// §6.1, §6.5: on fig6_eps_0.5 the even field did not take the cracks off the world's axes).
/// Drawn one per stratum of the circle, the azimuths' low moments vanish to about N^-1.5
/// (0.001-0.003), and each mode still has the isotropic Gaussian's distribution (its azimuth is
/// uniform and independent of its length and vertical part).
enum class ModeAzimuths {
    Even,    // mode k's azimuth uniform in [2 pi k / N, 2 pi (k + 1) / N)
    Random,  // each independent: the only way until 2026-11-30, which shots measured on it keep
};

struct StrengthFieldParams {
    Real correlation_length = 0.05;  // l in the covariance exp(-r^2 / (2 l^2)) [m]
    Real weibull_modulus = 4;        // m of the multipliers' Weibull distribution (mean 1) [-]
    ModeAzimuths azimuths = ModeAzimuths::Even;
};

/// Random Fourier modes that define one realisation of the field.
struct StrengthField {
    std::vector<Vec3> frequency;  // w_k [1/m]
    std::vector<Real> phase;      // phi_k [rad]
    Real weibull_modulus = 4;
    Real weibull_scale = 1;  // 1 / Gamma(1 + 1/m): the multipliers' mean is 1
};

/// Modes of the field used by every shot (enough that the values are Gaussian to the eye and the
/// measured covariance follows the target within a few % at one correlation length).
constexpr int kStrengthFieldModes = 256;

/// The realisation of `params` for `seed` (a pure function of both: identical for equal inputs).
StrengthField make_strength_field(const StrengthFieldParams& params, uint64_t seed);

/// The Gaussian field value g(x) (mean 0, variance 1).
Real strength_field_gaussian(const StrengthField& field, const Vec3& x);

/// Weibull quantile of the normal value g, scaled to mean 1: scale (-log(1 - Phi(g)))^(1/m).
Real weibull_of_gaussian(Real g, Real modulus, Real scale);

/// The p0 multiplier at each rest position (in parallel; the result does not depend on the
/// thread count).
std::vector<Real> strength_multipliers(const StrengthField& field, const std::vector<Vec3>& rest);

/// The Weibull distribution's coefficient of variation for modulus m: the spread a shot asks for.
Real weibull_cv(Real modulus);

}  // namespace mudcrack
