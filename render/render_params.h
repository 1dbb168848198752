#pragma once
/// Settings of the headless preview renderer.
#include <optional>
#include <string>

#include "sim/core/types.h"

namespace mudcrack {

enum class ColorMode {
    Moisture,  // wetter is darker (the paper's convention), from per-vertex saturation
    Hardening, // alpha through a diverging colormap (the paper's Fig. 9)
    Plain,     // albedo only
};

/// The image sides /render/resolution accepts (the shot spec's bounds) and the renderer's
/// precondition [px].
constexpr int kMinResolution = 16;
constexpr int kMaxResolution = 16384;

struct CameraParams {
    bool is_auto = true;           // frame the bounds automatically
    Vec3 position = Vec3(3, 2, 3); // [m]
    Vec3 target = Vec3(0, 0, 0);   // [m]
    Real fov_deg = 35;             // vertical field of view [deg]
};

struct RenderParams {
    int width = 960;
    int height = 540;
    ColorMode color_mode = ColorMode::Moisture;
    CameraParams camera;
    int samples = 4;                // anti-aliasing samples per pixel (MSAA)
    bool turntable = false;         // render a turntable orbit (on when the shot has /render/turntable)
    int turntable_views = 36;       // views in the orbit
    int turntable_frame = -1;       // frame to orbit; -1 = the last frame
    Vec3 albedo = Vec3(0.55, 0.42, 0.30); // dry soil color (linear RGB)
    Real alpha_range = 0.5;         // hardening colormap spans alpha0 -/+ this
    Real fps = 24;                  // movie frame rate
};

}  // namespace mudcrack

namespace mudcrack {
/// "moisture" | "hardening" | "plain".
const char* color_mode_name(ColorMode mode);
}  // namespace mudcrack
