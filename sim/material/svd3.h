#pragma once
/// Fast, robust singular value decomposition of a 3x3 matrix for the per-particle constitutive
/// kernels (docs/physics.md §2.1 item 1). Not Eigen's JacobiSVD (about 700 ns a call here, ~4x
/// slower). Structure of McAdams et al. 2011 ("V first, then a QR of A V for U and sigma"), with
/// the iterative Jacobi eigen-solve replaced by a closed form:
///   1. eigenbasis V of S = A^T A: eigenvalues from the characteristic cubic (Halley-refined, no
///      trigonometry), eigenvectors of the two extreme eigenvalues from cross products of the rows
///      of S - lambda I, orthonormalised;
///   2. one-sided Jacobi polish of B = A V, run only where S lost accuracy (nearly repeated or
///      ill-conditioned singular values; ~2-3 % of random inputs);
///   3. Gram-Schmidt QR B = U R, sigma = diag R (sign of det F on sigma_2), ordering fix-up.
/// Sign and ordering follow ziran's sign-corrected SVD. Defined inline: the MPM particle loop
/// calls it once per particle and step.
#include <cmath>

#include "sim/core/types.h"

namespace mudcrack {

/// F = U diag(sigma) V^T with det U = det V = +1 and |sigma_0| >= |sigma_1| >= |sigma_2|;
/// sigma_0, sigma_1 >= 0 and only sigma_2 may be negative (an inverted F, det F < 0).
struct Svd3 {
    Mat3 U;
    Vec3 sigma;
    Mat3 V;
};

/// SVD of any finite 3x3 matrix: identity, rotations, repeated or zero singular values, inverted
/// and near-singular matrices, entries from 1e-300 to 1e300. Accuracy: ||U diag(sigma) V^T - F||
/// and the orthogonality errors are a few 1e-16 relative to ||F||. A non-finite F gives a
/// non-finite result after a bounded amount of work (no loop waits on a NaN). No allocation.
inline Svd3 svd3(const Mat3& F);

}  // namespace mudcrack

#include "sim/material/svd3_impl.h"
