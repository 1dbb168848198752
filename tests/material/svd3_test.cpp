// svd3: reconstruction, orthogonality, det +1, ordering and sign convention on seeded random and
// named degenerate matrices; singular values against Eigen's JacobiSVD.
#include "sim/material/svd3.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <limits>
#include <random>

#include "material/material_samples.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

/// Frobenius norm without overflow or underflow (Eigen 3.4's Matrix3d::stableNorm asserts in
/// debug builds, so go through the 9-vector).
Real stable_norm(const Mat3& M) {
    return Eigen::Map<const Eigen::Matrix<Real, 9, 1>>(M.data()).stableNorm();
}

/// Checks every property of the contract in svd3.h; `what` names the matrix in failures.
void expect_valid_svd(const Mat3& F, const std::string& what) {
    const Svd3 s = svd3(F);
    const Real scale = stable_norm(F);
    const Mat3 I = Mat3::Identity();
    SCOPED_TRACE(what);
    ASSERT_TRUE(s.U.allFinite() && s.V.allFinite() && s.sigma.allFinite()) << "F =\n" << F;
    const Mat3 reconstructed = s.U * s.sigma.asDiagonal() * s.V.transpose();
    // subnormal inputs carry fewer digits: allow a few of their ulps too
    EXPECT_LE(stable_norm(reconstructed - F),
              tol::kRoundoffKernel * scale + 64 * std::numeric_limits<Real>::denorm_min())
        << "F =\n"
        << F << "\nsigma = " << s.sigma.transpose();
    EXPECT_LE((s.U.transpose() * s.U - I).norm(), tol::kRoundoffKernel) << "U =\n" << s.U;
    EXPECT_LE((s.V.transpose() * s.V - I).norm(), tol::kRoundoffKernel) << "V =\n" << s.V;
    EXPECT_NEAR(s.U.determinant(), 1, tol::kRoundoffKernel);
    EXPECT_NEAR(s.V.determinant(), 1, tol::kRoundoffKernel);
    EXPECT_GE(s.sigma(0), s.sigma(1)) << "sigma = " << s.sigma.transpose();
    EXPECT_GE(s.sigma(1), std::abs(s.sigma(2))) << "sigma = " << s.sigma.transpose();
    EXPECT_GE(s.sigma(1), 0);
    // the sign of sigma_2 is the sign of det F whenever det F is resolvable at this precision
    const Real det = F.determinant();
    if (std::abs(det) > 1e-10 * scale * scale * scale) {
        EXPECT_EQ(s.sigma(2) < 0, det < 0)
            << "det F = " << det << " sigma = " << s.sigma.transpose();
    }
    // singular values against Eigen's JacobiSVD (|sigma| sorted, absolute accuracy ~ eps ||F||)
    const Eigen::JacobiSVD<Mat3> reference(F);
    const Vec3 ref_sigma = reference.singularValues();
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(std::abs(s.sigma(k)), ref_sigma(k),
                    tol::kRoundoff * scale + 64 * std::numeric_limits<Real>::denorm_min())
            << "k = " << k;
    }
}

TEST(Svd3, NamedDegenerateMatrices) {
    for (const test::NamedMatrix& m : test::degenerate_matrices()) expect_valid_svd(m.F, m.name);
}

TEST(Svd3, RandomEntries) {
    std::mt19937_64 rng(20230101);
    for (int i = 0; i < 20000; ++i)
        expect_valid_svd(test::random_matrix(rng), "random #" + std::to_string(i));
}

TEST(Svd3, RandomDeformationsWideSpread) {
    std::mt19937_64 rng(42);
    for (int i = 0; i < 20000; ++i) {
        expect_valid_svd(test::random_deformation(rng, i % 2 ? 0.01 : 2.0),
                         "deformation #" + std::to_string(i));
    }
}

TEST(Svd3, RandomWithRepeatedAndZeroSingularValues) {
    std::mt19937_64 rng(3);
    const Real values[] = {0, 1e-12, 1e-6, 0.5, 1, 1, 1 + 1e-14, 1 + 1e-7, 2, -1};
    std::uniform_int_distribution<int> pick(0, 9);
    for (int i = 0; i < 20000; ++i) {
        const Vec3 sigma(values[pick(rng)], values[pick(rng)], values[pick(rng)]);
        expect_valid_svd(test::with_singular_values(rng, sigma),
                         "sigma = " + std::to_string(sigma(0)) + "," + std::to_string(sigma(1)) +
                             "," + std::to_string(sigma(2)));
    }
}

TEST(Svd3, ExactForDiagonalAndIdentity) {
    const Svd3 s = svd3(Mat3::Identity());
    EXPECT_EQ(s.sigma, Vec3::Ones());
    const Svd3 d = svd3(Vec3(0.5, 4, -2).asDiagonal());
    EXPECT_EQ(d.sigma, Vec3(4, 2, -0.5));
}

TEST(Svd3, NonFiniteInputTerminatesWithNonFiniteOutput) {
    Mat3 F = Mat3::Identity();
    F(1, 2) = std::numeric_limits<Real>::quiet_NaN();
    const Svd3 s = svd3(F);
    EXPECT_FALSE(s.sigma.allFinite() && s.U.allFinite() && s.V.allFinite());
    F(1, 2) = std::numeric_limits<Real>::infinity();
    const Svd3 t = svd3(F);
    EXPECT_FALSE(t.sigma.allFinite() && t.U.allFinite() && t.V.allFinite());
}

}  // namespace
}  // namespace mudcrack
