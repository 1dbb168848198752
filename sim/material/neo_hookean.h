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
    return p.mu / 2 * (tr_b * cbrt_inv_sq(J) - 3) + p.kappa / 2 * ((J * J - 1) / 2 - std::log(J));
}

/// Principal Kirchhoff stresses [Pa] from the singular values of Fe (the eigenvalues of tau;
/// its eigenvectors are U's columns). Defined for any det != 0 (an inverted Fe included).
inline Vec3 neo_hookean_kirchhoff_principal(const Vec3& sigma, const LameParams& p) {
    const Real J = sigma(0) * sigma(1) * sigma(2);
    const Vec3 b = sigma.cwiseProduct(sigma);
    const Real mean_b = (b(0) + b(1) + b(2)) / 3;
    const Real shear = p.mu * cbrt_inv_sq(J);
    const Real volumetric = p.kappa / 2 * (J * J - 1);
    return (shear * (b.array() - mean_b) + volumetric).matrix();
}

/// Kirchhoff stress tau = dpsi/dFe Fe^T [Pa]. Requires det Fe != 0.
inline Mat3 neo_hookean_kirchhoff(const Mat3& Fe, const LameParams& p) {
    const Real J = Fe.determinant();
    const Mat3 b = Fe * Fe.transpose();
    const Real mean_b = b.trace() / 3;
    const Real shear = p.mu * cbrt_inv_sq(J);
    const Real diagonal = p.kappa / 2 * (J * J - 1) - shear * mean_b;
    Mat3 tau = shear * b;
    tau.diagonal().array() += diagonal;
    return tau;
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
    const Real shear = p.mu * cbrt_inv_sq(J);
    return shear * (Fe - Fe.squaredNorm() / 3 * Finv_T) + p.kappa / 2 * (J * J - 1) * Finv_T;
}

}  // namespace mudcrack
