// Tensile damage (sim/material/damage.h): it only grows, only from softening returns, saturates
// at 1, and a fully damaged particle carries no tension whatever p0 drying has built; with the
// NACC return map, a stretched particle's damage rises and its next tension return is weaker.
#include "sim/material/damage.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sim/material/nacc.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

const LameParams kLame{740.74, 2222.2};  // E = 2000, nu = 0.35 (Table 1)

TEST(Damage, NeverDecreasesAndSaturatesAtOne) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> alpha(-1, 1), strain(0.001, 0.1);
    Real d = 0;
    for (int i = 0; i < 10000; ++i) {
        const Real before = alpha(rng), after = alpha(rng);
        const Real next = damage_after_return(d, before, after, strain(rng));
        ASSERT_GE(next, d) << "step " << i;
        ASSERT_LE(next, 1) << "step " << i;
        if (after <= before) {
            ASSERT_EQ(next, d) << "a hardening return must leave the damage";
        }
        d = next;
    }
    EXPECT_EQ(d, 1);
}

TEST(Damage, GrowsBySofteningOverTheDamageStrain) {
    EXPECT_NEAR(damage_after_return(0.1, -0.3, -0.28, 0.05), 0.1 + 0.02 / 0.05,
                tol::kRoundoffKernel);
    EXPECT_EQ(damage_after_return(0.2, -0.3, -0.35, 0.05), 0.2);
    EXPECT_EQ(damage_after_return(0.9, 0.0, 1.0, 0.05), 1.0);
    EXPECT_DOUBLE_EQ(damaged_cohesion(0.8, 0.25), 0.6);
    EXPECT_EQ(damaged_cohesion(0.8, 1.0), 0.0);
}

TEST(Damage, FullyDamagedSoilCarriesNoTensionWhateverItsHardening) {
    NaccParams nacc;
    nacc.M = 1.87;
    nacc.xi = 1;
    for (Real alpha : {-0.04, -0.5, -2.0}) {  // wet, dry, very hard
        const Vec3 stretched = Vec3::Constant(std::cbrt(1.2));
        const Real beta = damaged_cohesion(1.0, 1.0);
        const NaccPrincipalReturn r = nacc_return_principal(stretched, alpha, beta, nacc, kLame);
        EXPECT_EQ(r.yield_case, kNaccTensionTip) << alpha;
        EXPECT_NEAR(r.sigma.prod(), 1.0, tol::kRoundoffKernel)
            << "the tension tip of beta = 0 is p = 0, J = 1";
    }
}

TEST(Damage, TensionReturnsDamageAndWeakenTheNext) {
    // a particle held at 5 % volumetric stretch, returned again and again (a crack held open)
    NaccParams nacc;
    nacc.M = 1.87;
    nacc.xi = 1;
    const Real damage_strain = 0.2, beta0 = 1;
    Real alpha = -0.02, d = 0, last_J = 2;
    for (int i = 0; i < 20; ++i) {
        const Vec3 trial = Vec3::Constant(std::cbrt(1.05));
        const NaccPrincipalReturn r =
            nacc_return_principal(trial, alpha, damaged_cohesion(beta0, d), nacc, kLame);
        const Real next_d = damage_after_return(d, alpha, r.alpha, damage_strain);
        EXPECT_GE(next_d, d);
        const Real J = r.sigma.prod();
        EXPECT_LE(J, last_J + 1e-15) << "the admissible stretch shrinks as damage grows";
        last_J = J;
        alpha = r.alpha;
        d = next_d;
    }
    EXPECT_EQ(d, 1);
    EXPECT_NEAR(last_J, 1.0, tol::kRoundoffKernel);
}

}  // namespace
}  // namespace mudcrack
