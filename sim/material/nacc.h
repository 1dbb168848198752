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
#include "sim/material/symmetric_eigenvalues.h"
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

/// A return mapping as it acts on the trial's left Cauchy-Green tensor b = Fe Fe^T: the returned
/// b is c0 I + s b, on the same principal axes (docs/physics.md §2.2). Every case is of that
/// form: inside c0 = 0, s = 1; at a tip c0 = J_new^(2/3), s = 0 (all deviatoric strain removed);
/// projected (3b) c0 = (1 - s) tr(b) / 3 with s = ||s_new|| / ||s_trial|| in [0, 1) (the
/// deviator scaled radially at fixed tr b). So the map needs only the trial's rotation
/// invariants, and the returned Fe follows from either the trial's SVD (nacc_return_principal)
/// or a matrix function of b (nacc_project), without one.
struct NaccBMap {
    Real c0 = 0;                   // isotropic part of the returned b
    Real s = 1;                    // factor on the trial b
    Real alpha = 0;                // updated hardening state (ziran's logJp)
    int yield_case = kNaccInside;  // NaccYieldCase
};

/// The return mapping's NaccBMap from the trial's J = det Fe (|J| is used: an inverted trial
/// returns as its mirror image), mean_b = tr(b) / 3 and dev_b_norm = ||b - mean_b I||.
/// beta = beta0 (1 - s) + beta1 s comes from the caller; nacc.beta0/beta1 are not read here.
/// `strength` multiplies p0: the particle's share of a heterogeneous soil
/// (sim/material/strength_field.h), 1 for uniform.
inline NaccBMap nacc_b_map(Real J_trial, Real mean_b, Real dev_b_norm, Real alpha, Real beta,
                           const NaccParams& nacc, const LameParams& lame, Real strength = 1) {
    constexpr Real kMax = std::numeric_limits<Real>::max();
    const Real kappa = lame.kappa, mu = lame.mu, M = nacc.M;
    const Real p0 = strength * nacc_p0(alpha, nacc.xi, kappa);
    const Real J = nacc_safe_J(J_trial);
    const Real p = -kappa / 2 * (J * J - 1);  // -inf for J^2 overflow: the tension tip
    // trial deviatoric Kirchhoff stress s_hat = mu J^(-2/3) dev(b_hat)
    const Real s_norm = mu * inv_cube_root_squared(J) * dev_b_norm;

    NaccBMap out;
    out.alpha = alpha;
    out.yield_case = nacc_yield_case(p, s_norm, p0, beta, M, kappa);
    if (out.yield_case == kNaccInside) return out;  // case 3a
    // Cases 1 and 2: project to a tip of the ellipse, all deviatoric strain removed.
    if (out.yield_case != kNaccProjected) {
        const bool compression = out.yield_case == kNaccCompressionTip;
        // p <= kappa/2 always, so p > p0 implies p0 < kappa/2 and the root is real
        const Real J_new = std::sqrt(compression ? 1 - 2 * p0 / kappa : 1 + 2 * beta * p0 / kappa);
        const Real J_new_third = cube_root(J_new);
        out.c0 = J_new_third * J_new_third;
        out.s = 0;
        if (nacc.hardening) out.alpha += std::log(J / J_new);
        return out;
    }
    const Real a = Real(1.5) * (1 + 2 * beta);
    const Real y_p = M * M * (p + beta * p0) * (p - p0);  // <= 0 between the tips

    // Case 3b: scale s radially onto the ellipse at fixed p and tr(b_hat).
    const Real s_norm_new = std::sqrt(std::max(-y_p / a, Real(0)));
    const Real J_two_thirds = cube_root(J) * cube_root(J);
    out.s = dev_b_norm > 0 ? J_two_thirds / mu * s_norm_new / dev_b_norm : Real(0);
    out.c0 = (1 - out.s) * mean_b;

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

/// Result of a return mapping in principal space.
struct NaccPrincipalReturn {
    Vec3 sigma;      // singular values of the returned Fe (same U, V as the trial)
    Real alpha;      // updated hardening state (ziran's logJp)
    int yield_case;  // NaccYieldCase
};

/// Return mapping on the trial singular values (docs/physics.md §2.2): nacc_b_map on them, then
/// sigma_new = sqrt(c0 + s sigma^2). With preserve_volume the case-3b result keeps det Fe_new =
/// |J_trial| exactly, so it satisfies y = 0 exactly (see volume_preserving_sigma; off by
/// default, as in the reference code). See nacc_b_map for beta and strength.
inline NaccPrincipalReturn nacc_return_principal(const Vec3& sigma, Real alpha, Real beta,
                                                 const NaccParams& nacc, const LameParams& lame,
                                                 bool preserve_volume = false, Real strength = 1) {
    const Vec3 b = sigma.cwiseProduct(sigma);
    const Real mean_b = (b(0) + b(1) + b(2)) / 3;
    const Vec3 dev_b = b.array() - mean_b;
    const NaccBMap map = nacc_b_map(sigma(0) * sigma(1) * sigma(2), mean_b, dev_b.norm(), alpha,
                                    beta, nacc, lame, strength);
    NaccPrincipalReturn out{sigma, map.alpha, map.yield_case};
    if (map.yield_case == kNaccInside) return out;  // case 3a: sigma unchanged, bit for bit
    if (preserve_volume && map.yield_case == kNaccProjected) {
        const Real J = nacc_safe_J(sigma(0) * sigma(1) * sigma(2));
        out.sigma = volume_preserving_sigma(dev_b * (map.s * inv_cube_root_squared(J)),
                                            mean_b * inv_cube_root_squared(J), J);
    } else {
        for (int k = 0; k < 3; ++k)
            out.sigma(k) = std::sqrt(std::max(fused_madd(map.s, b(k), map.c0), Real(0)));
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

/// nacc_project falls back to the SVD when b's smallest eigenvalue is below this fraction of its
/// largest (singular values 1e3 apart): g(b) divides by the eigenvalues, and so loses accuracy
/// as cond(b) grows. No soil state comes near it; the stability matrix's extreme cases do.
constexpr Real kBMapMinEigenvalueRatio = 1e-6;
/// ... or when its eigenvalues leave [this, 1 / this], where the products of up to six of them
/// and the h's that g(b) is made of could overflow or underflow (J of 1e-30 or 1e30).
constexpr Real kBMapMinEigenvalue = 1e-20;

/// The Fe with the NaccBMap's b (c0 I + s b) and Fe's rotation: Fe_new = g(b) Fe with the matrix
/// function g(lambda) = sqrt(c0 / lambda + s) of b = Fe Fe^T (docs/physics.md §2.2: b's principal
/// axes are Fe's left singular vectors, and g(b) b^(1/2) = (c0 I + s b)^(1/2)). g(b) is the
/// quadratic in b that interpolates g at b's eigenvalues (Newton form), with divided differences
/// taken in closed form, so (nearly) repeated eigenvalues lose nothing to cancellation:
///   g[l1, l2] = -c0 / (l1 l2 (h1 + h2)),
///   g[l1, l2, l3] = c0 (h2 + (c0 + s (l1 + l3)) / (k1 + k3)) / (l1 l2 l3 (h1 + h2)(h2 + h3)),
/// h_i = g(l_i), k_i = l_i h_i. An eigenvalue off by d (a nearly double one, from the cubic)
/// moves g(b) by O(d^2). False, and Fe_new untouched, when b is singular, ill-conditioned or
/// extreme (kBMapMinEigenvalueRatio, kBMapMinEigenvalue) or not finite: the caller then takes
/// the SVD.
inline bool apply_nacc_b_map(const NaccBMap& map, const SymMat3& b, const Mat3& Fe, Mat3& Fe_new) {
    const CharacteristicRoots roots = characteristic_roots(b);
    const Real l1 = roots.isolated, l2 = roots.middle(), l3 = roots.other;
    const Real l_min = std::min(l1, std::min(l2, l3)), l_max = std::max(l1, std::max(l2, l3));
    if (!(l_min > kBMapMinEigenvalueRatio * l_max) || !(l_min > kBMapMinEigenvalue) ||
        !(l_max < 1 / kBMapMinEigenvalue))
        return false;
    const Real c0 = map.c0, s = map.s;
    // two divisions, not eight: they sit on the particle's dependency chain
    const Real l12 = l1 * l2, l123 = l12 * l3;
    const Real c0_over_l123 = c0 / l123;
    const Real h1 = std::sqrt(fused_madd(c0_over_l123, l2 * l3, s)),
               h2 = std::sqrt(fused_madd(c0_over_l123, l1 * l3, s)),
               h3 = std::sqrt(fused_madd(c0_over_l123, l12, s));
    if (roots.scalar) {
        Fe_new = h1 * Fe;
        return true;
    }
    // d12 = -c0 / (l1 l2 h12), d123 = c0 (h2 k13 + c0 + s (l1 + l3)) / (l1 l2 l3 h12 h23 k13)
    const Real h12 = h1 + h2, h23 = h2 + h3, k13 = l1 * h1 + l3 * h3;
    const Real c0_over_denominator = c0 / (l123 * h12 * h23 * k13);
    const Real d12 = -c0_over_denominator * (l3 * h23 * k13);
    const Real d123 = c0_over_denominator * (fused_madd(h2, k13, c0) + s * (l1 + l3));
    // g(b) = h1 I + d12 (b - l1 I) + d123 (b - l1 I)(b - l2 I)
    Mat3 b1 = b.matrix(), b2 = b1;
    b1.diagonal().array() -= l1;
    b2.diagonal().array() -= l2;
    Mat3 g = d123 * (b1 * b2) + d12 * b1;
    g.diagonal().array() += h1;
    Fe_new = g * Fe;
    return true;
}

/// The return mapping of nacc_return_map for callers that take the stress from Fe directly
/// (neo_hookean_kirchhoff(Fe, ...)), from Fe's Neo-Hookean terms (J and b, which the caller
/// usually has for the stress or an inside test already) and without an SVD: the case and the
/// hardening from nacc_b_map on the rotation invariants, the returned Fe from apply_nacc_b_map.
/// Inside states come back bitwise unchanged. The result equals nacc_return_map's to round-off
/// (a few 1e-16 of ||Fe||). An inverted or ill-conditioned trial (det Fe <= 0, or see
/// kBMapMinEigenvalueRatio) takes nacc_return_map's SVD, so extreme states return as they did.
inline NaccProjection nacc_project(const Mat3& Fe_trial, const NeoHookeanTerms& trial, Real alpha,
                                   Real beta, const NaccParams& nacc, const LameParams& lame,
                                   Real strength = 1) {
    const SymMat3& b = trial.b;
    const Real dxx = b.xx - trial.mean_b, dyy = b.yy - trial.mean_b, dzz = b.zz - trial.mean_b;
    const Real dev_b_norm = std::sqrt(dxx * dxx + dyy * dyy + dzz * dzz +
                                      2 * (b.xy * b.xy + b.xz * b.xz + b.yz * b.yz));
    const NaccBMap map =
        nacc_b_map(trial.J, trial.mean_b, dev_b_norm, alpha, beta, nacc, lame, strength);
    NaccProjection out{Fe_trial, map.alpha, map.yield_case};
    if (map.yield_case == kNaccInside) return out;
    if (trial.J > 0 && apply_nacc_b_map(map, b, Fe_trial, out.Fe)) return out;
    const NaccReturn r = nacc_return_map(Fe_trial, alpha, beta, nacc, lame, false, strength);
    return {r.Fe, r.alpha, r.yield_case};
}

/// nacc_project of Fe_trial alone (its terms computed here).
inline NaccProjection nacc_project(const Mat3& Fe_trial, Real alpha, Real beta,
                                   const NaccParams& nacc, const LameParams& lame,
                                   Real strength = 1) {
    return nacc_project(Fe_trial, neo_hookean_terms(Fe_trial, lame), alpha, beta, nacc, lame,
                        strength);
}

}  // namespace mudcrack
