#pragma once
/// Small scalar helpers shared by the constitutive kernels.
#include <cmath>

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

/// J^(-2/3), also for J < 0 (= |J|^(-2/3)); +infinity at J = 0.
inline Real cbrt_inv_sq(Real J) {
    const Real c = std::cbrt(J);
    return 1 / (c * c);
}

}  // namespace mudcrack
