#pragma once
/// Eigenvalues of a symmetric 3x3 matrix in closed form, without trigonometry: the roots of its
/// characteristic cubic, the best-separated one refined by Halley's method. Shared by svd3's
/// eigenbasis (which adds eigenvectors) and the SVD-free NACC return map (which needs only the
/// eigenvalues to evaluate a function of b = Fe Fe^T). Pure functions, defined inline for the MPM
/// particle loop.
#include <algorithm>
#include <cmath>

#include "sim/core/types.h"

namespace mudcrack {

/// The characteristic roots of a symmetric S: its eigenvalues are m + p x for the roots x of
/// x^3 - 3x - 2r = 0. `isolated` is the best-separated eigenvalue (the largest when r >= 0, else
/// the smallest), accurate to round-off; `other` the opposite extreme one, accurate unless it is
/// nearly double with the middle one (then its error is about sqrt(eps) ||S||, and the sum of the
/// two stays exact). When S is m I to round-off, `scalar` is set and all three are m.
struct CharacteristicRoots {
    Real m = 0;         // tr S / 3
    Real isolated = 0;  // best-separated eigenvalue
    Real other = 0;     // the other extreme eigenvalue
    bool isolated_is_largest = true;
    bool scalar = false;  // S = m I to round-off: every vector is an eigenvector

    /// The middle eigenvalue, from the trace.
    Real middle() const { return 3 * m - isolated - other; }
};

/// The characteristic roots of the symmetric matrix with entries s00, s11, s22 on the diagonal
/// and s01, s02, s12 off it. Accurate to ~eps ||S|| for the isolated eigenvalue.
inline CharacteristicRoots characteristic_roots(Real s00, Real s11, Real s22, Real s01, Real s02,
                                                Real s12) {
    CharacteristicRoots out;
    const Real m = (s00 + s11 + s22) / 3;
    out.m = out.isolated = out.other = m;
    const Real k00 = s00 - m, k11 = s11 - m, k22 = s22 - m;
    const Real p2 =
        (k00 * k00 + k11 * k11 + k22 * k22 + 2 * (s01 * s01 + s02 * s02 + s12 * s12)) / 6;
    // S = m I to round-off
    if (!(p2 > Real(1e-34) * m * m)) {
        out.scalar = true;
        return out;
    }
    const Real p = std::sqrt(p2);
    const Real det_k = k00 * (k11 * k22 - s12 * s12) - s01 * (s01 * k22 - s12 * s02) +
                       s02 * (s01 * s12 - k11 * s02);
    // x = 2 cos(acos(r)/3 + 2 pi k/3) with r = det(K/p)/2 in [-1, 1]. The root at the end of
    // [-2, 2] on r's side is the best-separated eigenvalue (r >= 0: the largest); by symmetry it
    // is sign(r) times the largest root of x^3 - 3x - 2|r|, which lies in [sqrt 3, 2] where the
    // cubic's slope is >= 6. Two Halley steps from a quadratic fit (error < 1.1e-3) reach
    // round-off (checked over |r| in [0, 1]); no acos/cos calls.
    const Real r = std::min(std::max(det_k / (2 * p2 * p), Real(-1)), Real(1));
    const Real r_abs = std::abs(r);
    Real x = Real(1.7320508075688772) + r_abs * (Real(0.3213884) - Real(0.0534392) * r_abs);
    for (int it = 0; it < 2; ++it) {
        const Real f = x * x * x - 3 * x - 2 * r_abs;
        const Real df = 3 * x * x - 3;
        x -= 2 * f * df / (2 * df * df - f * 6 * x);
    }
    out.isolated_is_largest = r >= 0;
    const Real x_isolated = out.isolated_is_largest ? x : -x;
    // the other extreme root, from the deflated quadratic x'^2 + x x' + x^2 - 3 = 0
    const Real x_other =
        -x_isolated / 2 -
        std::copysign(std::sqrt(std::max(12 - 3 * x * x, Real(0))), x_isolated) / 2;
    out.isolated = m + p * x_isolated;
    out.other = m + p * x_other;
    return out;
}

/// characteristic_roots of a full matrix (its upper triangle is read).
inline CharacteristicRoots characteristic_roots(const Mat3& S) {
    return characteristic_roots(S(0, 0), S(1, 1), S(2, 2), S(0, 1), S(0, 2), S(1, 2));
}

/// characteristic_roots of a SymMat3.
inline CharacteristicRoots characteristic_roots(const SymMat3& S) {
    return characteristic_roots(S.xx, S.yy, S.zz, S.xy, S.xz, S.yz);
}

}  // namespace mudcrack
