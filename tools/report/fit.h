#pragma once
/// Convergence orders: least-squares slopes on log-log data.
#include <vector>

#include "sim/core/types.h"

namespace mudcrack::report {

/// Least-squares slope of log(y) against log(x) over the pairs with x > 0 and finite y > 0
/// (error ~ C knob^slope). NaN when fewer than two such pairs exist.
Real log_log_slope(const std::vector<Real>& x, const std::vector<Real>& y);

}  // namespace mudcrack::report
