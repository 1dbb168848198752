#pragma once
/// The paper's elastic model, Tu et al. 2023 Eq. (4)-(5), ziran's "NeoHookeanBorden" with g = 1
/// (docs/physics.md §1.6), on the elastic deformation gradient F = Fe, J = det Fe, b = F F^T:
///   psi = mu/2 (J^(-2/3) tr b - 3) + kappa/2 ((J^2 - 1)/2 - log J)
///   tau = mu J^(-2/3) dev(b) + kappa/2 (J^2 - 1) I
/// Pure functions, defined inline for the MPM particle loop.
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "sim/core/types.h"
#include "sim/material/material_math.h"
#include "sim/material/svd3.h"
#include "sim/model.h"

namespace mudcrack {

/// Shear and 3D bulk modulus [Pa] (docs/physics.md §1.6: kappa = lambda + 2/3 mu, also used by
/// NACC).
struct LameParams {
    Real mu, kappa;
};

/// mu and kappa of an ElasticParams.
inline LameParams lame_params(const ElasticParams& e) { return {e.mu(), e.kappa()}; }

/// Strain energy density psi [J/m^3]. +infinity for det Fe <= 0 (the log J barrier).
inline Real neo_hookean_energy(const Mat3& Fe, const LameParams& p) {
    const Real J = Fe.determinant();
    if (!(J > 0)) return std::numeric_limits<Real>::infinity();
    const Real tr_b = Fe.squaredNorm();
    return p.mu / 2 * (tr_b * inv_cube_root_squared(J) - 3) +
           p.kappa / 2 * ((J * J - 1) / 2 - std::log(J));
}

/// Principal Kirchhoff stresses [Pa] from the singular values of Fe (the eigenvalues of tau;
/// its eigenvectors are U's columns). Defined for any det != 0 (an inverted Fe included).
inline Vec3 neo_hookean_kirchhoff_principal(const Vec3& sigma, const LameParams& p) {
    const Real J = sigma(0) * sigma(1) * sigma(2);
    const Vec3 b = sigma.cwiseProduct(sigma);
    const Real mean_b = (b(0) + b(1) + b(2)) / 3;
    const Real shear = p.mu * inv_cube_root_squared(J);
    const Real volumetric = p.kappa / 2 * (J * J - 1);
    return (shear * (b.array() - mean_b) + volumetric).matrix();
}

/// The invariants of Fe that tau is made of, and that the NACC inside test reads too (so a
/// particle's step computes them once): J = det Fe, b = Fe Fe^T (symmetric), tr b / 3 and
/// mu J^(-2/3).
struct NeoHookeanTerms {
    Real J;
    SymMat3 b;
    Real mean_b;
    Real shear;
};

/// NeoHookeanTerms of four matrices side by side (G2P's lanes); b as xx, yy, zz, xy, xz, yz.
struct NeoHookeanLaneTerms {
    Lanes J;
    Lanes b[6];
    Lanes mean_b;
    Lanes shear;
};

/// The terms of F (Mat3 with T = Real, LaneMat3 with T = Lanes): J, b's six entries (xx, yy, zz,
/// xy, xz, yz), tr b / 3 and mu J^(-2/3). Defined for any F; shear is +infinity at J = 0. Every
/// product-sum is an explicit fused_madd, so the terms (and tau) round alike wherever they are
/// inlined: the stress G2P caches for the next P2G and the stress P2G computes itself are the
/// same bits, and so are a lane's and the scalar's. Always inlined: the inline cube root made it
/// large enough that g++ 12 called it from the G2P, and the call's stores and loads of the terms
/// cost more than the cube root saved.
template <class T, class M>
[[gnu::always_inline]] inline void neo_hookean_terms_of(const M& F, const LameParams& p, T& J,
                                                        T (&b)[6], T& mean_b, T& shear) {
    const auto dot3 = [](T a0, T a1, T a2, T b0, T b1, T b2) {
        return fused_madd(a2, b2, fused_madd(a1, b1, a0 * b0));
    };
    const auto row_dot = [&](int i, int j) {
        return dot3(F(i, 0), F(i, 1), F(i, 2), F(j, 0), F(j, 1), F(j, 2));
    };
    const T c0 = fused_madd(F(1, 1), F(2, 2), -(F(1, 2) * F(2, 1)));
    const T c1 = fused_madd(F(1, 0), F(2, 2), -(F(1, 2) * F(2, 0)));
    const T c2 = fused_madd(F(1, 0), F(2, 1), -(F(1, 1) * F(2, 0)));
    J = fused_madd(F(0, 2), c2, fused_madd(-F(0, 1), c1, F(0, 0) * c0));
    b[0] = row_dot(0, 0);
    b[1] = row_dot(1, 1);
    b[2] = row_dot(2, 2);
    b[3] = row_dot(0, 1);
    b[4] = row_dot(0, 2);
    b[5] = row_dot(1, 2);
    mean_b = (b[0] + b[1] + b[2]) / 3;
    shear = p.mu * inv_cube_root_squared(J);
}

/// The terms of Fe.
[[gnu::always_inline]] inline NeoHookeanTerms neo_hookean_terms(const Mat3& F,
                                                                const LameParams& p) {
    NeoHookeanTerms t;
    Real b[6];
    neo_hookean_terms_of(F, p, t.J, b, t.mean_b, t.shear);
    t.b = {b[0], b[1], b[2], b[3], b[4], b[5]};
    return t;
}

/// The terms of four matrices side by side.
[[gnu::always_inline]] inline NeoHookeanLaneTerms neo_hookean_terms(const LaneMat3& F,
                                                                    const LameParams& p) {
    NeoHookeanLaneTerms t;
    neo_hookean_terms_of(F, p, t.J, t.b, t.mean_b, t.shear);
    return t;
}

/// Kirchhoff stress's six entries (xx, yy, zz, xy, xz, yz) from the terms J, b, tr b / 3 and
/// mu J^(-2/3); T is Real or Lanes.
template <class T>
inline void neo_hookean_kirchhoff_of(T J, const T (&b)[6], T mean_b, T shear, const LameParams& p,
                                     T (&tau)[6]) {
    const T volumetric = p.kappa / 2 * fused_madd(J, J, splat<T>(-1));
    const T diagonal = fused_madd(-shear, mean_b, volumetric);
    for (int k = 0; k < 3; ++k) tau[k] = fused_madd(shear, b[k], diagonal);
    for (int k = 3; k < 6; ++k) tau[k] = shear * b[k];
}

/// Kirchhoff stress tau = dpsi/dFe Fe^T [Pa] from Fe's terms. Requires det Fe != 0.
inline SymMat3 neo_hookean_kirchhoff(const NeoHookeanTerms& t, const LameParams& p) {
    const Real b[6] = {t.b.xx, t.b.yy, t.b.zz, t.b.xy, t.b.xz, t.b.yz};
    Real tau[6];
    neo_hookean_kirchhoff_of(t.J, b, t.mean_b, t.shear, p, tau);
    return {tau[0], tau[1], tau[2], tau[3], tau[4], tau[5]};
}

/// Kirchhoff stress tau = dpsi/dFe Fe^T [Pa]. Requires det Fe != 0.
inline Mat3 neo_hookean_kirchhoff(const Mat3& Fe, const LameParams& p) {
    return neo_hookean_kirchhoff(neo_hookean_terms(Fe, p), p).matrix();
}

/// Kirchhoff stress from a precomputed SVD of Fe: U diag(tau_hat) U^T, no second SVD.
inline Mat3 neo_hookean_kirchhoff(const Svd3& svd, const LameParams& p) {
    const Vec3 tau_hat = neo_hookean_kirchhoff_principal(svd.sigma, p);
    return svd.U * tau_hat.asDiagonal() * svd.U.transpose();
}

/// First Piola-Kirchhoff stress P = dpsi/dFe = tau Fe^-T [Pa] (for derivative tests and
/// diagnostics; the MPM step uses tau). Requires det Fe != 0.
inline Mat3 neo_hookean_first_piola(const Mat3& Fe, const LameParams& p) {
    const Real J = Fe.determinant();
    const Mat3 Finv_T = Fe.inverse().transpose();
    const Real shear = p.mu * inv_cube_root_squared(J);
    return shear * (Fe - Fe.squaredNorm() / 3 * Finv_T) + p.kappa / 2 * (J * J - 1) * Finv_T;
}

}  // namespace mudcrack
