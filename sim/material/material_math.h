#pragma once
/// Small scalar helpers shared by the constitutive kernels.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "sim/core/lanes.h"
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

/// fused_madd in every lane: the same bits per lane.
inline Lanes fused_madd(Lanes a, Lanes b, Lanes c) {
#if defined(__FMA__)
    return __builtin_ia32_vfmaddpd256(a, b, c);
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

// the exponent's third, with the mantissa offset that minimises the largest relative error over
// an octave (3.42 %)
constexpr uint64_t kMagic = 0x553ef0ff25e5c700ull;

/// x^(-1/3) from r, its first guess within 3.42 %: the root is r (1 - e)^(-1/3), e = 1 - x r^3;
/// the series to e^2 triples the digits (3.4e-2 -> 2e-4 -> 4e-11 relative), then the series to e
/// (Newton) doubles them. T is Real or Lanes.
template <class T>
inline T refine_inv_cube_root(T x, T r) {
    for (int k = 0; k < 2; ++k) {
        const T e = fused_madd(-x * r, r * r, splat<T>(1));
        r = fused_madd(r * e, fused_madd(e, splat<T>(2.0 / 9), splat<T>(1.0 / 3)), r);
    }
    const T e = fused_madd(-x * r, r * r, splat<T>(1));
    return fused_madd(r * e, splat<T>(1.0 / 3), r);
}

/// x^(-1/3) for a positive normal double x.
inline Real positive_inv_cube_root(double x) {
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    bits = kMagic - bits / 3;
    double r;
    std::memcpy(&r, &bits, sizeof r);
    return refine_inv_cube_root(x, r);
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

/// inv_cube_root in every lane: the same bits per lane.
inline Lanes inv_cube_root(Lanes x) {
    constexpr uint64_t kSign = uint64_t(1) << 63;
    const LaneBits sign = lanes_to_bits(x) & kSign;
    const LaneBits magnitude_bits = lanes_to_bits(x) & ~kSign;
    const Lanes magnitude = lanes_from_bits(magnitude_bits);
    const LaneMask normal = (magnitude >= std::numeric_limits<double>::min()) &
                            (magnitude <= std::numeric_limits<double>::max());
    if (!lanes_all(normal)) {  // rare: a zero, subnormal, infinite or NaN J
        Lanes r = x;
        for (int l = 0; l < kLaneCount; ++l) r[l] = inv_cube_root(x[l]);
        return r;
    }
    LaneBits guess_bits;
    for (int l = 0; l < kLaneCount; ++l)  // no 64-bit SIMD division: the scalar's bits / 3
        guess_bits[l] = cube_root_detail::kMagic - magnitude_bits[l] / 3;
    const Lanes root =
        cube_root_detail::refine_inv_cube_root(magnitude, lanes_from_bits(guess_bits));
    const LaneBits root_bits = lanes_to_bits(root) | sign;
    return lanes_from_bits(root_bits);
}

/// inv_cube_root_squared in every lane: the same bits per lane.
inline Lanes inv_cube_root_squared(Lanes x) {
    const Lanes r = inv_cube_root(x);
    return r * r;
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
