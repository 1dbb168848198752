// Neo-Hookean (Tu et al. Eq. 4-5): zero stress for rotations, SVD path == direct path, and the
// analytic stress against central differences of the energy (with the error order), and the
// terms and stress of four matrices side by side (G2P's lanes) bit for bit as one at a time.
#include "sim/material/neo_hookean.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cstring>
#include <random>

#include "material/material_samples.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

const LameParams kLame{740.74, 2222.2};  // E = 2000, nu = 0.35 (Table 1)

/// Central-difference gradient of the energy, P_ij = (psi(F + h E_ij) - psi(F - h E_ij)) / 2h.
Mat3 finite_difference_piola(const Mat3& F, Real h) {
    Mat3 P;
    for (int i = 0; i < 9; ++i) {
        Mat3 plus = F, minus = F;
        plus(i) += h;
        minus(i) -= h;
        P(i) = (neo_hookean_energy(plus, kLame) - neo_hookean_energy(minus, kLame)) / (2 * h);
    }
    return P;
}

Real smallest_singular_value(const Mat3& F) {
    return Eigen::JacobiSVD<Mat3>(F).singularValues()(2);
}

struct NamedCase {
    std::string name;
    Mat3 F;
};

/// Random states plus named degenerate regimes: J -> 0+, large stretch, near identity.
std::vector<NamedCase> derivative_cases() {
    std::mt19937_64 rng(11);
    std::vector<NamedCase> cases;
    for (int i = 0; i < 40; ++i)
        cases.push_back({"random #" + std::to_string(i), test::random_deformation(rng, 0.3)});
    cases.push_back({"J=1e-3 isotropic", test::with_singular_values(rng, Vec3(0.1, 0.1, 0.1))});
    cases.push_back({"J=1e-3 anisotropic", test::with_singular_values(rng, Vec3(1, 0.1, 0.01))});
    cases.push_back({"J=1e-6", test::with_singular_values(rng, Vec3(0.02, 0.01, 0.005))});
    cases.push_back({"stretch 5", test::with_singular_values(rng, Vec3(5, 5, 5))});
    cases.push_back({"stretch 5 sheared", test::with_singular_values(rng, Vec3(5, 1, 0.5))});
    cases.push_back({"near identity", Mat3::Identity() + 1e-3 * test::random_matrix(rng)});
    return cases;
}

TEST(NeoHookean, RotationGivesZeroStressAndEnergy) {
    std::mt19937_64 rng(5);
    for (int i = 0; i < 1000; ++i) {
        const Mat3 R = test::random_rotation(rng);
        const Real scale = kLame.mu + kLame.kappa;
        EXPECT_LE(neo_hookean_kirchhoff(R, kLame).norm(), tol::kRoundoff * scale) << "R =\n" << R;
        EXPECT_LE(neo_hookean_kirchhoff(svd3(R), kLame).norm(), tol::kRoundoff * scale) << "R =\n"
                                                                                        << R;
        EXPECT_LE(neo_hookean_first_piola(R, kLame).norm(), tol::kRoundoff * scale) << "R =\n" << R;
        EXPECT_NEAR(neo_hookean_energy(R, kLame), 0, tol::kRoundoff * scale);
    }
}

TEST(NeoHookean, SvdPathMatchesDirectPath) {
    std::mt19937_64 rng(6);
    for (int i = 0; i < 5000; ++i) {
        Mat3 F = test::random_deformation(rng, i % 2 ? 0.05 : 0.7);
        if (i % 10 == 0) F.col(0) = -F.col(0);  // inverted: tau is still defined
        const Mat3 direct = neo_hookean_kirchhoff(F, kLame);
        const Mat3 from_svd = neo_hookean_kirchhoff(svd3(F), kLame);
        const Real scale =
            (kLame.mu + kLame.kappa) * (1 + F.squaredNorm() + std::pow(F.determinant(), 2));
        EXPECT_LE((direct - from_svd).norm(), tol::kRoundoff * scale) << "F =\n" << F;
        EXPECT_LE((direct - direct.transpose()).norm(), tol::kRoundoff * scale);
    }
}

TEST(NeoHookean, KirchhoffEqualsPiolaTimesFTransposed) {
    for (const NamedCase& c : derivative_cases()) {
        const Mat3 tau = neo_hookean_kirchhoff(c.F, kLame);
        const Mat3 from_piola = neo_hookean_first_piola(c.F, kLame) * c.F.transpose();
        EXPECT_LE((tau - from_piola).norm(), tol::kRoundoffLoose * (tau.norm() + kLame.kappa))
            << c.name;
    }
}

TEST(NeoHookean, StressMatchesFiniteDifferenceOfEnergy) {
    for (const NamedCase& c : derivative_cases()) {
        const Real h = 1e-6 * smallest_singular_value(c.F);
        const Mat3 P_fd = finite_difference_piola(c.F, h);
        const Mat3 P = neo_hookean_first_piola(c.F, kLame);
        const Real scale = std::max(P.norm(), kLame.mu);
        EXPECT_LE((P_fd - P).norm(), tol::kFiniteDiff * scale) << c.name << "\nF =\n" << c.F;
        // tau = P F^T: the Kirchhoff stress the MPM step uses, against the differenced energy
        const Mat3 tau = neo_hookean_kirchhoff(c.F, kLame);
        const Mat3 tau_fd = P_fd * c.F.transpose();
        EXPECT_LE((tau_fd - tau).norm(), tol::kFiniteDiff * std::max(tau.norm(), kLame.mu))
            << c.name;
    }
}

TEST(NeoHookean, FiniteDifferenceErrorIsSecondOrder) {
    for (const NamedCase& c : derivative_cases()) {
        const Mat3 P = neo_hookean_first_piola(c.F, kLame);
        // steps where truncation (~h^2) dominates round-off (~eps psi / h) by many digits
        const Real h = 1e-3 * smallest_singular_value(c.F);
        const Real coarse = (finite_difference_piola(c.F, h) - P).norm();
        const Real fine = (finite_difference_piola(c.F, h / 2) - P).norm();
        const Real ratio = coarse / fine;
        EXPECT_GT(ratio, 3.5) << c.name << " errors " << coarse << " -> " << fine;
        EXPECT_LT(ratio, 4.5) << c.name << " errors " << coarse << " -> " << fine;
    }
}

TEST(NeoHookean, EnergyIsInfiniteForNonPositiveJ) {
    EXPECT_TRUE(std::isinf(neo_hookean_energy(Vec3(1, 1, -1).asDiagonal(), kLame)));
    EXPECT_TRUE(std::isinf(neo_hookean_energy(Mat3::Zero(), kLame)));
}

TEST(NeoHookean, PrincipalStressesOfAStretch) {
    // uniaxial stretch diag(2, 1, 1): J = 2, b = (4, 1, 1), mean 2, J^(-2/3) = 2^(-2/3)
    const Vec3 tau = neo_hookean_kirchhoff_principal(Vec3(2, 1, 1), kLame);
    const Real shear = kLame.mu * std::pow(2.0, -2.0 / 3);
    const Real volumetric = kLame.kappa / 2 * 3;
    EXPECT_NEAR(tau(0), 2 * shear + volumetric, tol::kRoundoff * kLame.kappa);
    EXPECT_NEAR(tau(1), -shear + volumetric, tol::kRoundoff * kLame.kappa);
    EXPECT_NEAR(tau(2), -shear + volumetric, tol::kRoundoff * kLame.kappa);
}

TEST(NeoHookean, FourLanesGiveTheScalarTermsAndStressBitForBit) {
    std::mt19937_64 rng(23);
    std::normal_distribution<Real> g(0, 0.3);
    const auto same_bits = [](Real a, Real b) { return std::memcmp(&a, &b, sizeof a) == 0; };
    for (int i = 0; i < 5000; ++i) {
        Mat3 F[kLaneCount];
        LaneMat3 lanes;
        for (int l = 0; l < kLaneCount; ++l) {
            F[l] = Mat3::Identity() + (i % 7 == 0 && l == 1
                                           ? Mat3::Zero()
                                           : Mat3(Mat3::NullaryExpr([&] { return g(rng); })));
            if (i % 11 == 0 && l == 2) F[l].col(2) = F[l].col(0);  // J = 0: shear is infinite
            for (int k = 0; k < 9; ++k) lanes.m[k][l] = F[l](k);
        }
        const NeoHookeanLaneTerms t = neo_hookean_terms(lanes, kLame);
        Lanes tau[6];
        neo_hookean_kirchhoff_of(t.J, t.b, t.mean_b, t.shear, kLame, tau);
        for (int l = 0; l < kLaneCount; ++l) {
            const NeoHookeanTerms want = neo_hookean_terms(F[l], kLame);
            const SymMat3 want_tau = neo_hookean_kirchhoff(want, kLame);
            const Real want_b[6] = {want.b.xx, want.b.yy, want.b.zz,
                                    want.b.xy, want.b.xz, want.b.yz};
            const Real want_t[6] = {want_tau.xx, want_tau.yy, want_tau.zz,
                                    want_tau.xy, want_tau.xz, want_tau.yz};
            ASSERT_TRUE(same_bits(t.J[l], want.J)) << i;
            ASSERT_TRUE(same_bits(t.mean_b[l], want.mean_b)) << i;
            ASSERT_TRUE(same_bits(t.shear[l], want.shear)) << i;
            for (int k = 0; k < 6; ++k) {
                ASSERT_TRUE(same_bits(t.b[k][l], want_b[k])) << i << " b " << k;
                ASSERT_TRUE(same_bits(tau[k][l], want_t[k])) << i << " tau " << k;
            }
        }
    }
}

}  // namespace
}  // namespace mudcrack
