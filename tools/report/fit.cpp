#include "tools/report/fit.h"

#include <cmath>
#include <limits>

namespace mudcrack::report {

Real log_log_slope(const std::vector<Real>& x, const std::vector<Real>& y) {
    Real sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
        if (!(x[i] > 0) || !(y[i] > 0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
        const Real lx = std::log(x[i]), ly = std::log(y[i]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
        ++n;
    }
    const Real denom = n * sxx - sx * sx;
    if (n < 2 || !(std::abs(denom) > 0)) return std::numeric_limits<Real>::quiet_NaN();
    return (n * sxy - sx * sy) / denom;
}

}  // namespace mudcrack::report
