#pragma once
/// Small scalar helpers shared by the constitutive kernels.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "sim/core/types.h"

namespace mudcrack {

/// a b + c rounded once where the CPU has FMA (the hardware instruction, never libm's
/// emulation), else a b + c with two roundings (the compiler cannot fuse without FMA). Written
/// where the same sum must round alike in every function it is inlined into.
inline Real fused_madd(Real a, Real b, Real c) {
#if defined(__FMA__)
    return std::fma(a, b, c);
#else
    return a * b + c;
#endif
}

/// Cube roots without a libm call. The kernels take J^(1/3) and J^(-2/3) of every particle every
/// step, and libm's cbrt (a call, a frexp, a polynomial and a division) was 12 % of the G2P
/// (docs/measurements.md). The inverse cube root starts from the exponent divided by three in
/// the bits of the double (as the fast inverse square root does; within 3.4 %) and takes three
/// division-free iterations. The result is within a few ulp of the true root, not correctly
/// rounded, and the same bits on every run of one build.
namespace cube_root_detail {

/// x^(-1/3) for a positive normal double x.
inline Real positive_inv_cube_root(double x) {
    // the exponent's third, with the mantissa offset that minimises the largest relative error
    // over an octave (3.42 %)
    constexpr uint64_t kMagic = 0x553ef0ff25e5c700ull;
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    bits = kMagic - bits / 3;
    double r;
    std::memcpy(&r, &bits, sizeof r);
    // the root is r (1 - e)^(-1/3), e = 1 - x r^3: the series to e^2 triples the digits
    // (3.4e-2 -> 2e-4 -> 4e-11 relative), then the series to e (Newton) doubles them
    for (int k = 0; k < 2; ++k) {
        const double e = fused_madd(-x * r, r * r, 1);
        r = fused_madd(r * e, fused_madd(e, 2.0 / 9, 1.0 / 3), r);
    }
    const double e = fused_madd(-x * r, r * r, 1);
    return fused_madd(r * e, 1.0 / 3, r);
}

/// Whether |x| is in the bit trick's domain: the normal doubles.
inline bool normal_magnitude(double x) {
    const double a = std::abs(x);
    return a >= std::numeric_limits<double>::min() && a <= std::numeric_limits<double>::max();
}

}  // namespace cube_root_detail

/// x^(-1/3), odd in x (libm's 1 / cbrt(x) outside the normal doubles: +-infinity at +-0, 0 at
/// infinity, NaN for NaN).
inline Real inv_cube_root(Real x) {
    if (!cube_root_detail::normal_magnitude(x)) return 1 / std::cbrt(x);
    return std::copysign(cube_root_detail::positive_inv_cube_root(std::abs(x)), x);
}

/// x^(1/3), odd in x (libm's cbrt outside the normal doubles).
inline Real cube_root(Real x) {
    if (!cube_root_detail::normal_magnitude(x)) return std::cbrt(x);
    const Real r = cube_root_detail::positive_inv_cube_root(std::abs(x));
    return x * (r * r);
}

/// |x|^(-2/3), also for x < 0; +infinity at 0.
inline Real inv_cube_root_squared(Real x) {
    const Real r = inv_cube_root(x);
    return r * r;
}

}  // namespace mudcrack
