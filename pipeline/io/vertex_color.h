#pragma once
/// The vertex colour every mesh file carries: r = saturation, g = the NACC hardening state alpha
/// (unbounded, either sign) through the logistic function, b = 0, a = 1. g is in (0, 1), 0.5 at
/// alpha = 0, and alpha = log(g / (1 - g)) inverts it.
#include <algorithm>
#include <cmath>

namespace mudcrack {

inline float alpha_to_color(float alpha) { return float(1.0 / (1.0 + std::exp(-double(alpha)))); }

inline float color_to_alpha(float g) {
    const double clamped = std::clamp(double(g), 1e-7, 1.0 - 1e-7);
    return float(std::log(clamped / (1.0 - clamped)));
}

}  // namespace mudcrack
