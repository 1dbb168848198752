#pragma once
/// Non-associated Cam-Clay (NACC) return mapping of CD-MPM (Wolper et al. 2019), as used by
/// Tu et al. 2023 Eq. (7)-(9): docs/physics.md §2.1-2.2, in exactly that order, with the semantics
/// of ziran2020's NonAssociativeCamClay::projectStrain (hardening mode 0, "fake p", qHard off).
/// Differences from the reference code, all documented at their constants below:
///   - the "inside" and hardening-guard tolerances are relative to kappa (docs/physics.md §2.2 asks
/// for     this when stresses are scaled away from E ~ 1e3); they equal ziran's absolute 1e-4 at
/// the     paper's kappa = 2222 Pa;
///   - the sinh argument of p0 is capped, so p0 never overflows;
///   - J is floored at the smallest normal double in the logs and powers, so the map stays finite
///     for J -> 0+ and for huge stretch; an inverted trial (det < 0) uses |J|.
/// Pure functions, defined inline for the MPM particle loop.
#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/core/types.h"
#include "sim/material/material_math.h"
#include "sim/material/neo_hookean.h"
#include "sim/material/svd3.h"
#include "sim/model.h"

namespace mudcrack {

/// Which branch of docs/physics.md §2.2 a return mapping took.
enum NaccYieldCase : int {
    kNaccInside = 0,          // case 3a: y below tolerance, Fe unchanged
    kNaccCompressionTip = 1,  // case 1: p > p0
    kNaccTensionTip = 2,      // case 2: p < -beta p0
    kNaccProjected = 3,       // case 3b: deviatoric (volume-preserving) projection
};

/// Cap on xi max(-alpha, 0) inside sinh. sinh(20) = 2.4e8, so p0 <= 2.4e8 kappa: far past any
/// physical state (the compression tip is unreachable once p0 >= kappa/2, and the tension tip
/// then sits at J = sqrt(1 + 2 beta p0/kappa) ~ 2e4 sqrt(beta)), yet small enough that M^2 beta
/// p0^2 stays finite for any kappa below 1e140. sinh itself would overflow past 710.
constexpr Real kNaccMaxSinhArgument = 20;
/// Case 3a: y < kNaccInsideTolerance kappa^2 counts as inside (ziran: y < 1e-4 Pa^2 absolute,
/// = 2.03e-11 kappa^2 at kappa = 2222.2 Pa).
constexpr Real kNaccInsideTolerance = 2e-11;
/// Case 3b hardening guard: p0 > tol and -beta p0 + tol < p < p0 - tol with tol =
/// kNaccPressureTolerance kappa (ziran: 1e-4 Pa absolute = 4.5e-8 kappa at kappa = 2222.2 Pa).
constexpr Real kNaccPressureTolerance = 4.5e-8;
/// Case 3b hardening is skipped when the "fake" elastic J is below this (ziran's 1e-4).
constexpr Real kNaccMinFakeJ = 1e-4;

/// p0 = kappa (1e-5 + sinh(xi max(-alpha, 0))) [Pa], the ellipse's compression tip, with the sinh
/// argument capped at kNaccMaxSinhArgument (never inf for finite inputs).
inline Real nacc_p0(Real alpha, Real xi, Real kappa) {
    const Real x = std::min(xi * std::max(-alpha, Real(0)), kNaccMaxSinhArgument);
    return kappa * (Real(1e-5) + std::sinh(x));
}

/// nacc_p0 from below, to within 2e-10 and up to a few ulps of rounding, without the sinh call
/// (glibc's costs about as much as the rest of a clearly elastic particle's return-map test):
/// sinh's Taylor series has only positive terms, so every truncation lies below it, and to x^13
/// it is within 2e-10 of it up to x = 1.5; beyond, 0.5 (e^x - e^-x) is within a few ulps. For
/// tests that only need p0 from below, with a relative margin far above an ulp: a smaller p0 is
/// a smaller ellipse, inside the true one.
inline Real nacc_p0_lower_bound(Real alpha, Real xi, Real kappa) {
    constexpr Real kSeriesLimit = 1.5;
    const Real x = std::min(xi * std::max(-alpha, Real(0)), kNaccMaxSinhArgument);
    Real sinh_x;
    if (x <= kSeriesLimit) {
        const Real x2 = x * x;
        // multiplications by the reciprocals (rounded: the few ulps above), not divisions
        constexpr Real c3 = Real(1) / 6, c5 = Real(1) / 20, c7 = Real(1) / 42, c9 = Real(1) / 72,
                       c11 = Real(1) / 110, c13 = Real(1) / 156;
        sinh_x =
            x * (1 + x2 * c3 *
                         (1 + x2 * c5 *
                                  (1 + x2 * c7 * (1 + x2 * c9 * (1 + x2 * c11 * (1 + x2 * c13))))));
    } else {
        const Real e = std::exp(x);
        sinh_x = Real(0.5) * (e - 1 / e);
    }
    return kappa * (Real(1e-5) + sinh_x);
}

/// Yield function of Eq. (8) in the a ||s||^2 form (docs/physics.md §2.1 item 7) [Pa^2]:
/// y = 3/2 (1 + 2 beta) ||s||^2 + M^2 (p + beta p0)(p - p0); y <= 0 is admissible.
inline Real nacc_yield(Real p, Real s_norm, Real p0, Real beta, Real M) {
    const Real a = Real(1.5) * (1 + 2 * beta);
    return a * s_norm * s_norm + M * M * (p + beta * p0) * (p - p0);
}

/// Singular values with det = J whose isochoric left Cauchy-Green eigenvalues b_bar = J^(-2/3)
/// sigma^2 have the deviator d (sum d = 0): b_bar = d + m with m the root of
/// prod(m + d_k) = 1. The reference code instead keeps tr b_hat, which changes J slightly
/// (docs/physics.md §2.2 "fine point"; a uniform rescale afterwards would restore J but not s,
/// since s is measured with the state's own J). f(m) = prod(m + d_k) - 1 is convex and increasing
/// where every factor is positive, and m_start (the trial's isochoric mean, whose deviator is
/// larger) has f >= 0, so Newton from there converges monotonically; 8 steps bound the work.
inline Vec3 volume_preserving_sigma(const Vec3& d, Real m_start, Real J) {
    Real m = m_start;
    for (int it = 0; it < 8; ++it) {
        const Real a0 = m + d(0), a1 = m + d(1), a2 = m + d(2);
        const Real f = a0 * a1 * a2 - 1;
        const Real df = a1 * a2 + a0 * a2 + a0 * a1;
        if (!(std::abs(f) > Real(4e-16)) || !(df > 0)) break;
        m -= f / df;
    }
    const Real J_third = cube_root(J);
    Vec3 sigma;
    for (int k = 0; k < 3; ++k) sigma(k) = J_third * std::sqrt(std::max(m + d(k), Real(0)));
    return sigma;
}

/// Which case of docs/physics.md §2.2 a trial state with pressure p and deviatoric norm ||s_hat||
/// falls in, in the reference order: the tips first, then inside (y below the relative tolerance)
/// or projected.
inline int nacc_yield_case(Real p, Real s_norm, Real p0, Real beta, Real M, Real kappa) {
    if (p > p0) return kNaccCompressionTip;
    if (p < -beta * p0) return kNaccTensionTip;
    return nacc_yield(p, s_norm, p0, beta, M) < kNaccInsideTolerance * kappa * kappa
               ? kNaccInside
               : kNaccProjected;
}

/// |J| clamped to the normal doubles: keeps logs and powers finite for J -> 0 and huge stretch.
inline Real nacc_safe_J(Real J) {
    return std::min(std::max(std::abs(J), std::numeric_limits<Real>::min()),
                    std::numeric_limits<Real>::max());
}

/// Result of a return mapping in principal space.
struct NaccPrincipalReturn {
    Vec3 sigma;      // singular values of the returned Fe (same U, V as the trial)
    Real alpha;      // updated hardening state (ziran's logJp)
    int yield_case;  // NaccYieldCase
};

/// Return mapping on the trial singular values (docs/physics.md §2.2). beta = beta0 (1-s) + beta1 s
/// comes from the caller; nacc.beta0/beta1 are not read here. With preserve_volume the case-3b
/// result keeps det Fe_new = |J_trial| exactly, so it satisfies y = 0 exactly (see
/// volume_preserving_sigma; off by default, as in the reference code). `strength` multiplies p0:
/// the particle's share of a heterogeneous soil (sim/material/strength_field.h), 1 for uniform.
inline NaccPrincipalReturn nacc_return_principal(const Vec3& sigma, Real alpha, Real beta,
                                                 const NaccParams& nacc, const LameParams& lame,
                                                 bool preserve_volume = false, Real strength = 1) {
    constexpr Real kMax = std::numeric_limits<Real>::max();
    const Real kappa = lame.kappa, mu = lame.mu, M = nacc.M;
    const Real p0 = strength * nacc_p0(alpha, nacc.xi, kappa);
    const Real J = nacc_safe_J(sigma(0) * sigma(1) * sigma(2));
    const Real p = -kappa / 2 * (J * J - 1);  // -inf for J^2 overflow: the tension tip
    // trial deviatoric Kirchhoff stress s_hat = mu J^(-2/3) dev(b_hat), b_hat = sigma^2
    const Vec3 b = sigma.cwiseProduct(sigma);
    const Real mean_b = (b(0) + b(1) + b(2)) / 3;
    const Vec3 dev_b = b.array() - mean_b;
    const Real dev_b_norm = dev_b.norm();
    const Real s_norm = mu * inv_cube_root_squared(J) * dev_b_norm;

    NaccPrincipalReturn out{sigma, alpha, nacc_yield_case(p, s_norm, p0, beta, M, kappa)};
    if (out.yield_case == kNaccInside) return out;  // case 3a
    // Cases 1 and 2: project to a tip of the ellipse, all deviatoric strain removed.
    if (out.yield_case != kNaccProjected) {
        const bool compression = out.yield_case == kNaccCompressionTip;
        // p <= kappa/2 always, so p > p0 implies p0 < kappa/2 and the root is real
        const Real J_new = std::sqrt(compression ? 1 - 2 * p0 / kappa : 1 + 2 * beta * p0 / kappa);
        out.sigma.setConstant(cube_root(J_new));
        if (nacc.hardening) out.alpha += std::log(J / J_new);
        return out;
    }
    const Real a = Real(1.5) * (1 + 2 * beta);
    const Real y_p = M * M * (p + beta * p0) * (p - p0);  // <= 0 between the tips

    // Case 3b: scale s radially onto the ellipse at fixed p and tr(b_hat).
    const Real s_norm_new = std::sqrt(std::max(-y_p / a, Real(0)));
    const Real J_two_thirds = cube_root(J) * cube_root(J);
    const Real scale = dev_b_norm > 0 ? J_two_thirds / mu * s_norm_new / dev_b_norm : Real(0);
    if (preserve_volume) {
        out.sigma = volume_preserving_sigma(dev_b * (scale * inv_cube_root_squared(J)),
                                            mean_b * inv_cube_root_squared(J), J);
    } else {
        for (int k = 0; k < 3; ++k)
            out.sigma(k) = std::sqrt(std::max(mean_b + scale * dev_b(k), Real(0)));
    }

    // "Fake p" hardening: intersect the ray from the ellipse centre through the trial point
    // with y = 0 and harden by the elastic J that root's pressure would need.
    const Real p_tol = kNaccPressureTolerance * kappa;
    if (nacc.hardening && p0 > p_tol && p < p0 - p_tol && p > -beta * p0 + p_tol) {
        const Real p_c = (1 - beta) * p0 / 2;
        const Real q = std::sqrt(Real(1.5)) * s_norm;
        Real dir_p = 0, dir_q = -1;  // the limit of the direction for an overflowed q
        if (q < kMax) {
            const Real n = std::hypot(p_c - p, q);
            dir_p = (p_c - p) / n;
            dir_q = -q / n;
        }
        const Real M2 = M * M;
        const Real qa = M2 * dir_p * dir_p + (1 + 2 * beta) * dir_q * dir_q;
        const Real qb = M2 * dir_p * (2 * p_c - p0 + beta * p0);  // 0 up to round-off
        const Real qc = M2 * (p_c + beta * p0) * (p_c - p0);      // <= 0: two real roots
        const Real root = std::sqrt(std::max(qb * qb - 4 * qa * qc, Real(0)));
        const Real p1 = p_c + (-qb + root) / (2 * qa) * dir_p;
        const Real p2 = p_c + (-qb - root) / (2 * qa) * dir_p;
        const Real p_fake = (p - p_c) * (p1 - p_c) > 0 ? p1 : p2;
        const Real J_fake = std::sqrt(std::abs(1 - 2 * p_fake / kappa));
        if (J_fake > kNaccMinFakeJ) out.alpha += std::log(J / J_fake);
    }
    return out;
}

/// Return mapping of one particle (docs/physics.md §2.2). NaccReturn::svd is the SVD of the
/// returned Fe, so the stress (neo_hookean_kirchhoff(svd, ...)) needs no second SVD.
struct NaccReturn {
    Mat3 Fe;         // returned elastic deformation gradient
    Real alpha;      // updated hardening state
    Svd3 svd;        // SVD of Fe
    int yield_case;  // NaccYieldCase: 0 inside, 1 compression tip, 2 tension tip, 3 projected
};

/// Return mapping from a precomputed SVD of Fe_trial. Inside (case 3a) Fe is Fe_trial bitwise.
inline NaccReturn nacc_return_map(const Svd3& trial, const Mat3& Fe_trial, Real alpha, Real beta,
                                  const NaccParams& nacc, const LameParams& lame,
                                  bool preserve_volume = false, Real strength = 1) {
    const NaccPrincipalReturn r =
        nacc_return_principal(trial.sigma, alpha, beta, nacc, lame, preserve_volume, strength);
    NaccReturn out{Fe_trial, r.alpha, trial, r.yield_case};
    if (r.yield_case != kNaccInside) {
        out.svd.sigma = r.sigma;
        out.Fe = trial.U * r.sigma.asDiagonal() * trial.V.transpose();
    }
    return out;
}

/// Return mapping of Fe_trial with hardening state alpha and cohesion beta (the caller computes
/// beta = beta0 (1 - s) + beta1 s). See nacc_return_principal for preserve_volume and strength.
inline NaccReturn nacc_return_map(const Mat3& Fe_trial, Real alpha, Real beta,
                                  const NaccParams& nacc, const LameParams& lame,
                                  bool preserve_volume = false, Real strength = 1) {
    return nacc_return_map(svd3(Fe_trial), Fe_trial, alpha, beta, nacc, lame, preserve_volume,
                           strength);
}

/// Result of nacc_project: a NaccReturn without the SVD.
struct NaccProjection {
    Mat3 Fe;         // returned elastic deformation gradient
    Real alpha;      // updated hardening state
    int yield_case;  // NaccYieldCase
};

/// The same return mapping as nacc_return_map, for callers that take the stress from Fe
/// directly (neo_hookean_kirchhoff(Fe, ...)) and so need no SVD of the result: the case is first
/// decided from the rotation invariants det Fe and ||dev(Fe Fe^T)|| (equal to prod sigma and
/// ||dev(sigma^2)||), and the SVD is computed only for states that leave the yield surface.
/// Inside states (the common case) cost no SVD and come back bitwise unchanged. Up to round-off
/// in states within ~1e-15 of the yield surface, the result equals nacc_return_map's.
inline NaccProjection nacc_project(const Mat3& Fe_trial, Real alpha, Real beta,
                                   const NaccParams& nacc, const LameParams& lame,
                                   bool preserve_volume = false) {
    const Real J = nacc_safe_J(Fe_trial.determinant());
    Mat3 dev_b = Fe_trial * Fe_trial.transpose();
    dev_b.diagonal().array() -= dev_b.trace() / 3;
    const Real s_norm = lame.mu * inv_cube_root_squared(J) * dev_b.norm();
    const Real p = -lame.kappa / 2 * (J * J - 1);
    const Real p0 = nacc_p0(alpha, nacc.xi, lame.kappa);
    if (nacc_yield_case(p, s_norm, p0, beta, nacc.M, lame.kappa) == kNaccInside) {
        return {Fe_trial, alpha, kNaccInside};
    }
    const NaccReturn r = nacc_return_map(Fe_trial, alpha, beta, nacc, lame, preserve_volume);
    return {r.Fe, r.alpha, r.yield_case};
}

}  // namespace mudcrack
