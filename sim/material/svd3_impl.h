#pragma once
/// Inline definition of svd3 (sim/material/svd3.h). Included from svd3.h only.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Geometry>

#include "sim/core/types.h"
#include "sim/material/symmetric_eigenvalues.h"

namespace mudcrack {
namespace svd3_detail {

/// M <- M J with the plane rotation J of cosine c and sine s in columns (p, q):
/// column p <- c p - s q, column q <- s p + c q.
inline void rotate_columns(Mat3& M, int p, int q, Real c, Real s) {
    for (int i = 0; i < 3; ++i) {
        const Real mp = M(i, p), mq = M(i, q);
        M(i, p) = c * mp - s * mq;
        M(i, q) = s * mp + c * mq;
    }
}

/// Cosine and sine of the Jacobi rotation that diagonalises the symmetric 2x2 [[a, g], [g, b]]
/// (smaller angle, |tan| <= 1), in the convention of rotate_columns. Identity when g = 0.
inline void jacobi_angle(Real a, Real b, Real g, Real& c, Real& s) {
    const Real d = b - a;
    const Real denominator = std::abs(d) + std::sqrt(d * d + 4 * g * g);
    const Real t = denominator > 0 ? 2 * g * std::copysign(Real(1), d) / denominator : Real(0);
    c = 1 / std::sqrt(1 + t * t);
    s = t * c;
}

/// A unit vector orthogonal to the unit vector v (built from v's two largest components).
inline Vec3 any_orthogonal_unit(const Vec3& v) {
    const Vec3 w = std::abs(v(0)) > std::abs(v(1)) ? Vec3(-v(2), 0, v(0)) : Vec3(0, v(2), -v(1));
    return w.normalized();
}

/// Unit eigenvector of the symmetric S for the simple eigenvalue lambda: the longest cross
/// product of two rows of S - lambda I (they span the orthogonal complement of the eigenvector).
inline Vec3 eigenvector_of_simple_eigenvalue(const Mat3& S, Real lambda) {
    const Vec3 r0(S(0, 0) - lambda, S(0, 1), S(0, 2));
    const Vec3 r1(S(1, 0), S(1, 1) - lambda, S(1, 2));
    const Vec3 r2(S(2, 0), S(2, 1), S(2, 2) - lambda);
    const Vec3 c01 = r0.cross(r1), c02 = r0.cross(r2), c12 = r1.cross(r2);
    const Real n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
    // selects rather than branches: which product wins is data-dependent and unpredictable
    const bool use02 = n02 > n01;
    Real n = use02 ? n02 : n01;
    const bool use12 = n12 > n;
    n = use12 ? n12 : n;
    Vec3 v;
    for (int k = 0; k < 3; ++k) v(k) = use12 ? c12(k) : (use02 ? c02(k) : c01(k));
    if (!(n > 0)) return Vec3::UnitX();  // lambda not simple at this precision: any vector works
    return v / std::sqrt(n);
}

/// An orthonormal eigenbasis of S = A^T A (det +1), accurate to ~eps ||S|| / gap in the common
/// case: closed-form eigenvalues (a Halley-refined root of the characteristic cubic), the
/// eigenvector of the best-separated one from cross products (always well conditioned), and the
/// eigenvector of the other extreme eigenvalue made orthogonal to it. When that second eigenvalue
/// is nearly repeated the basis may be mixed within the near-degenerate plane; svd3's one-sided
/// polish repairs exactly that.
inline Mat3 eigenbasis(const Mat3& S) {
    const CharacteristicRoots roots = characteristic_roots(S);
    // S = m I to round-off: every basis is an eigenbasis
    if (roots.scalar) return Mat3::Identity();
    const bool isolated_is_largest = roots.isolated_is_largest;
    const Real isolated = roots.isolated, other = roots.other;
    const Vec3 v = eigenvector_of_simple_eigenvalue(S, isolated);

    // second vector: eigenvector of the other extreme eigenvalue, made orthogonal to v (any
    // vector of v's complement when that eigenvalue is not resolvable); the polish in svd3
    // repairs the rare cases where this basis is not accurate enough
    Vec3 w = eigenvector_of_simple_eigenvalue(S, other);
    w -= v.dot(w) * v;
    w -= v.dot(w) * v;  // Gram-Schmidt twice: orthogonal to round-off even if w was nearly parallel
    const Real w_norm2 = w.squaredNorm();
    w = w_norm2 > Real(1e-8) ? Vec3(w / std::sqrt(w_norm2)) : any_orthogonal_unit(v);
    // columns in decreasing eigenvalue order (so svd3's sort rarely swaps), right-handed:
    // for orthonormal (a, b, c) with det +1, b = c x a
    const Vec3 largest = isolated_is_largest ? v : w;
    const Vec3 smallest = isolated_is_largest ? w : v;
    Mat3 V;
    V.col(0) = largest;
    V.col(1) = smallest.cross(largest);
    V.col(2) = smallest;
    return V;
}

/// Swaps columns i and j of B and V and negates the new column j of both, so det V stays +1
/// and B = A V still holds.
inline void swap_columns(Mat3& B, Mat3& V, int i, int j) {
    B.col(i).swap(B.col(j));
    V.col(i).swap(V.col(j));
    B.col(j) = -B.col(j);
    V.col(j) = -V.col(j);
}

/// Swaps singular triplets i < j (columns of U and V, entries of sigma) and negates column j of
/// U and V, which keeps U diag(sigma) V^T and both determinants. A negative value that moved to
/// i < 2 is handed back to sigma_2 by negating U's columns i and 2 with sigma_i and sigma_2.
inline void swap_singular(Mat3& U, Vec3& sigma, Mat3& V, int i, int j) {
    U.col(i).swap(U.col(j));
    V.col(i).swap(V.col(j));
    std::swap(sigma(i), sigma(j));
    U.col(j) = -U.col(j);
    V.col(j) = -V.col(j);
    if (sigma(i) < 0) {
        sigma(i) = -sigma(i);
        sigma(2) = -sigma(2);
        U.col(i) = -U.col(i);
        U.col(2) = -U.col(2);
    }
}

}  // namespace svd3_detail

inline Svd3 svd3(const Mat3& F) {
    using namespace svd3_detail;
    Svd3 out;
    // Scale by a power of two (exact) when the entries are far from 1, so that A^T A can neither
    // overflow nor underflow.
    const Real max_entry = F.cwiseAbs().maxCoeff();
    if (max_entry == 0) {
        out.U.setIdentity();
        out.V.setIdentity();
        out.sigma.setZero();
        return out;
    }
    int exponent = 0;
    Mat3 A = F;
    const bool finite = max_entry <= std::numeric_limits<Real>::max();  // false for inf, NaN
    if (finite && !(max_entry > Real(0x1p-100) && max_entry < Real(0x1p100))) {
        exponent = std::ilogb(max_entry);
        // entry-wise scalbn: 2^-exponent itself overflows for subnormal inputs
        A = F.unaryExpr([exponent](Real x) { return std::scalbn(x, -exponent); });
    }

    // Eigenbasis V of S = A^T A in closed form; B = A V then has (nearly) orthogonal columns.
    const Mat3 S = A.transpose() * A;
    Mat3 V = eigenbasis(S);
    Mat3 B = A * V;

    // Polish with one-sided Jacobi rotations of B's columns, computed from their Gram matrix
    // (which, unlike S, keeps the small singular values' relative accuracy). A^T A resolves
    // the eigenvectors only to eps ||S|| / gap, so for ill-conditioned or nearly repeated cases
    // R's off-diagonal would be larger than eps sigma_0. A pair is rotated only when its R
    // entry would exceed 1e-15 sigma_0; for well-conditioned F nothing is rotated.
    Real n0 = B.col(0).squaredNorm(), n1 = B.col(1).squaredNorm(), n2 = B.col(2).squaredNorm();
    constexpr int kMaxPolishSweeps = 4;  // quadratic convergence; bounded for NaN input
    for (int sweep = 0; sweep < kMaxPolishSweeps; ++sweep) {
        const Real n_max = std::max(n0, std::max(n1, n2));
        bool rotated = false;
        const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (const auto& pair : pairs) {
            const int i = pair[0], j = pair[1];
            const Real ni = B.col(i).squaredNorm(), nj = B.col(j).squaredNorm();
            const Real g = B.col(i).dot(B.col(j));
            if (!(g * g > Real(1e-30) * n_max * std::max(ni, nj))) continue;
            Real c, s;
            jacobi_angle(ni, nj, g, c, s);
            rotate_columns(B, i, j, c, s);
            rotate_columns(V, i, j, c, s);
            rotated = true;
        }
        if (!rotated) break;
        n0 = B.col(0).squaredNorm();
        n1 = B.col(1).squaredNorm();
        n2 = B.col(2).squaredNorm();
    }

    // sort B's columns by decreasing norm (the singular values' order)
    if (n0 < n1) {
        swap_columns(B, V, 0, 1);
        std::swap(n0, n1);
    }
    if (n0 < n2) {
        swap_columns(B, V, 0, 2);
        std::swap(n0, n2);
    }
    if (n1 < n2) {
        swap_columns(B, V, 1, 2);
        std::swap(n1, n2);
    }

    // QR of B by Gram-Schmidt: B = U R with U = [u0, u1, u0 x u1] (det +1 by construction) and
    // R upper triangular; R's off-diagonal is below 1e-15 sigma_0 after the polish and is
    // dropped, its diagonal holds the singular values (R22 < 0 iff det F < 0).
    Mat3 U;
    const Real sigma0 = std::sqrt(n0);
    U.col(0) = B.col(0) / sigma0;
    Vec3 u1 = B.col(1) - U.col(0).dot(B.col(1)) * U.col(0);
    u1 -= U.col(0).dot(u1) * U.col(0);  // twice, for rank-deficient B
    Real sigma1 = u1.norm();
    if (sigma1 > 0) {
        u1 /= sigma1;
    } else {  // rank 1: any unit vector orthogonal to u0
        u1 = any_orthogonal_unit(U.col(0));
    }
    U.col(1) = u1;
    U.col(2) = U.col(0).cross(u1);
    Vec3 sigma(sigma0, sigma1, U.col(2).dot(B.col(2)));

    // Round-off can break the order by an ulp when singular values (nearly) coincide.
    if (sigma(0) < sigma(1)) swap_singular(U, sigma, V, 0, 1);
    if (sigma(1) < std::abs(sigma(2))) {
        swap_singular(U, sigma, V, 1, 2);
        if (sigma(0) < std::abs(sigma(1))) swap_singular(U, sigma, V, 0, 1);
    }
    if (exponent != 0)
        sigma = sigma.unaryExpr([exponent](Real x) { return std::scalbn(x, exponent); });
    out.U = U;
    out.sigma = sigma;
    out.V = V;
    return out;
}

}  // namespace mudcrack
