#pragma once
/// Small scalar helpers shared by the constitutive kernels.
#include <cmath>

#include "sim/core/types.h"

namespace mudcrack {

/// J^(-2/3), also for J < 0 (= |J|^(-2/3)); +infinity at J = 0.
inline Real cbrt_inv_sq(Real J) {
    const Real c = std::cbrt(J);
    return 1 / (c * c);
}

}  // namespace mudcrack
