#include "render/colormap.h"

#include <algorithm>
#include <cmath>

namespace mudcrack {

const std::array<Vec3f, kColormapStops>& coolwarm_stops() {
    // Moreland 2009, Table 2 entries at s = 0, 1/8, ..., 1 (8-bit sRGB / 255)
    static const std::array<Vec3f, kColormapStops> stops = [] {
        const int rgb[kColormapStops][3] = {{59, 76, 192},   {98, 130, 234},  {141, 176, 254},
                                            {184, 208, 249}, {221, 221, 221}, {245, 196, 173},
                                            {244, 154, 123}, {222, 96, 77},   {180, 4, 38}};
        std::array<Vec3f, kColormapStops> s;
        for (int i = 0; i < kColormapStops; ++i)
            s[i] = Vec3f(rgb[i][0], rgb[i][1], rgb[i][2]) / 255.0f;
        return s;
    }();
    return stops;
}

Vec3f coolwarm(float t) {
    // the shaders evaluate the same piecewise-linear form from the same stops
    const auto& stops = coolwarm_stops();
    const float x = std::clamp(t, 0.0f, 1.0f) * float(kColormapStops - 1);
    const int i = std::min(int(std::floor(x)), kColormapStops - 2);
    const float f = x - float(i);
    return stops[i] * (1 - f) + stops[i + 1] * f;
}

float hardening_coordinate(float alpha, float alpha0, float alpha_range) {
    return std::clamp(0.5f + 0.5f * (alpha - alpha0) / alpha_range, 0.0f, 1.0f);
}

Vec3f hardening_color(float alpha, float alpha0, float alpha_range) {
    return coolwarm(hardening_coordinate(alpha, alpha0, alpha_range));
}

Vec3f moisture_color(const Vec3f& albedo, float saturation) {
    return albedo * (1.0f - kMoistureDarkening * std::clamp(saturation, 0.0f, 1.0f));
}

float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float c) {
    c = std::clamp(c, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace mudcrack
