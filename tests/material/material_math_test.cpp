// The kernels' cube roots (sim/material/material_math.h): within a few ulp of the root over the
// whole range of doubles, libm's own answers outside the positive normals, the same bits run to
// run, and the same bits in four lanes (G2P's) as one at a time.
#include "sim/material/material_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

namespace mudcrack {
namespace {

/// The relative error of `value` against `reference`, in units of the double's epsilon.
double relative_ulps(double value, long double reference) {
    return double(std::abs(value / reference - 1) / std::numeric_limits<double>::epsilon());
}

TEST(CubeRoot, IsWithinFourEpsilonsOfTheRootFromTheSmallestToTheLargestNormalDouble) {
    std::mt19937_64 rng(7);  // the engine's sequence is the same on every platform
    std::uniform_real_distribution<double> exponent(-1021.9, 1023.9), mantissa(1, 2);
    double worst_root = 0, worst_inverse = 0, worst_square = 0;
    for (int i = 0; i < 100000; ++i) {
        const double x = std::ldexp(mantissa(rng), int(std::floor(exponent(rng))));
        // the reference in long double: 11 more bits than the double under test
        const long double root = std::cbrt(static_cast<long double>(x));
        worst_root = std::max(worst_root, relative_ulps(cube_root(x), root));
        worst_inverse = std::max(worst_inverse, relative_ulps(inv_cube_root(x), 1 / root));
        worst_square =
            std::max(worst_square, relative_ulps(inv_cube_root_squared(x), 1 / (root * root)));
        ASSERT_EQ(cube_root(-x), -cube_root(x)) << x;
        ASSERT_EQ(inv_cube_root(-x), -inv_cube_root(x)) << x;
    }
    // a few ulp: the iterations' rounding, and the square's and product's
    std::printf("worst relative error in epsilons: root %.2f, inverse %.2f, squared %.2f\n",
                worst_root, worst_inverse, worst_square);
    EXPECT_LE(worst_root, 4);
    EXPECT_LE(worst_inverse, 4);
    EXPECT_LE(worst_square, 4);
}

TEST(CubeRoot, IsExactOnPerfectCubesNearOne) {
    // J near 1 is where the kernels live; the cubes of small integers' ratios come back whole
    for (double a : {1.0, 0.5, 0.75, 1.25, 2.0, 3.0}) {
        EXPECT_NEAR(cube_root(a * a * a), a, 2 * std::numeric_limits<double>::epsilon() * a) << a;
        EXPECT_NEAR(inv_cube_root(a * a * a), 1 / a, 2 * std::numeric_limits<double>::epsilon() / a)
            << a;
    }
    EXPECT_EQ(cube_root(1.0), 1.0);
    EXPECT_EQ(inv_cube_root_squared(1.0), 1.0);
}

TEST(CubeRoot, OutsideTheNormalDoublesGivesLibmsAnswers) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const double subnormal = std::numeric_limits<double>::denorm_min() * 12345;
    EXPECT_EQ(cube_root(0.0), 0.0);
    EXPECT_EQ(inv_cube_root(0.0), kInf);
    EXPECT_EQ(inv_cube_root(-0.0), -kInf);
    EXPECT_EQ(inv_cube_root_squared(0.0), kInf);
    EXPECT_EQ(cube_root(kInf), kInf);
    EXPECT_EQ(inv_cube_root(kInf), 0.0);
    EXPECT_TRUE(std::isnan(cube_root(std::nan(""))));
    EXPECT_TRUE(std::isnan(inv_cube_root_squared(std::nan(""))));
    EXPECT_EQ(cube_root(subnormal), std::cbrt(subnormal));
    // negative J (an inverted element): the kernels use |J|^(-2/3)
    EXPECT_LE(relative_ulps(inv_cube_root_squared(-8.0), 0.25), 4);
    EXPECT_LE(relative_ulps(cube_root(-27.0), -3.0), 4);
}

TEST(CubeRoot, GivesTheSameBitsEveryCall) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> J(0.2, 3);
    for (int i = 0; i < 1000; ++i) {
        const double x = J(rng);
        const double a = cube_root(x);
        volatile double y = x;  // a second evaluation the compiler cannot fold into the first
        EXPECT_EQ(a, cube_root(y));
    }
}

TEST(CubeRoot, FourLanesGiveTheBitsOfFourScalarCalls) {
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> exponent(-1021.9, 1023.9), mantissa(1, 2), sign(-1, 1);
    const auto same_bits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
    const auto check = [&](Lanes x) {
        const Lanes root = inv_cube_root(x), square = inv_cube_root_squared(x);
        for (int l = 0; l < kLaneCount; ++l) {
            ASSERT_TRUE(same_bits(root[l], inv_cube_root(x[l]))) << x[l];
            ASSERT_TRUE(same_bits(square[l], inv_cube_root_squared(x[l]))) << x[l];
        }
    };
    for (int i = 0; i < 20000; ++i) {
        Lanes x;
        for (int l = 0; l < kLaneCount; ++l)
            x[l] =
                std::copysign(std::ldexp(mantissa(rng), int(std::floor(exponent(rng)))), sign(rng));
        check(x);
    }
    // a lane outside the normal doubles sends all four down libm's path, each still its own
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const double subnormal = std::numeric_limits<double>::denorm_min() * 12345;
    for (double odd : {0.0, -0.0, kInf, -kInf, subnormal, std::nan("")})
        check(Lanes{0.7, odd, -3.2, 1e300});
}

}  // namespace
}  // namespace mudcrack
