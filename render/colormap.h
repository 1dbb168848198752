#pragma once
/// The renderer's color conventions, shared by the shaders (which receive the same tables as
/// uniforms) and by tests: how saturation darkens soil and how the hardening state alpha maps
/// to a diverging colormap. Colors are floats in [0, 1].
#include <array>

#include "sim/core/types.h"

namespace mudcrack {

/// Moisture shading darkens the albedo linearly with saturation: wet soil is darker (the
/// paper's convention, Tu et al. 2023 Fig. 1, 10): color = albedo * (1 - kMoistureDarkening s).
constexpr float kMoistureDarkening = 0.55f;

/// Number of control points of the hardening colormap.
constexpr int kColormapStops = 9;

/// Moreland's "cool to warm" diverging colormap (2009) sampled at 9 evenly spaced points, sRGB,
/// linearly interpolated between them (perceptually close to the smooth map, cheap in a shader).
const std::array<Vec3f, kColormapStops>& coolwarm_stops();

/// The diverging colormap at t in [0, 1] (clamped), sRGB: 0 blue, 0.5 neutral grey, 1 red.
Vec3f coolwarm(float t);

/// Position of alpha on the hardening colormap: 0.5 + 0.5 (alpha - alpha0) / alpha_range, clamped
/// to [0, 1]. @param alpha NACC hardening state (Tu et al. 2023 Eq. 9, ziran's logJp)
/// @param alpha0 the shot's initial hardening state (colormap center) @param alpha_range > 0
float hardening_coordinate(float alpha, float alpha0, float alpha_range);

/// Hardening color (Tu et al. 2023 Fig. 9), sRGB: blue for hardened/compressed material
/// (alpha < alpha0), neutral grey at alpha0, red for softened/stretched (alpha > alpha0);
/// saturates at alpha0 -/+ alpha_range.
Vec3f hardening_color(float alpha, float alpha0, float alpha_range);

/// Moisture color, linear RGB: albedo * (1 - kMoistureDarkening s), s clamped to [0, 1].
/// @param albedo dry soil color, linear RGB @param saturation s in [0, 1]
Vec3f moisture_color(const Vec3f& albedo, float saturation);

/// sRGB transfer function (IEC 61966-2-1), per channel, for values in [0, 1].
float srgb_to_linear(float c);
float linear_to_srgb(float c);

}  // namespace mudcrack
