#pragma once
/// Settings of the headless preview renderer.
#include <optional>
#include <string>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

/// The colour modes. Their names (/render/color_mode, manifests) and the shader's constants
/// (MC_COLOR_MODE_<NAME>, the enum's values) both come from one table, kColorModes
/// (render_params.cpp).
enum class ColorMode {
    Moisture = 0,   // wetter is darker (the paper's convention), from per-vertex saturation
    Hardening = 1,  // alpha through a diverging colormap (the paper's Fig. 9)
    Plain = 2,      // albedo only
};

/// The image sides /render/resolution accepts (the shot spec's bounds) and the renderer's
/// precondition [px].
constexpr int kMinResolution = 16;
constexpr int kMaxResolution = 16384;

struct CameraParams {
    bool is_auto = true;            // frame the bounds automatically
    Vec3 position = Vec3(3, 2, 3);  // [m]
    Vec3 target = Vec3(0, 0, 0);    // [m]
    Real fov_deg = 35;              // vertical field of view [deg]
};

struct RenderParams {
    int width = 960;
    int height = 540;
    ColorMode color_mode = ColorMode::Moisture;
    CameraParams camera;
    int samples = 4;  // anti-aliasing samples per pixel (MSAA)
    // render a turntable orbit (on when the shot has /render/turntable)
    bool turntable = false;
    int turntable_views = 36;              // views in the orbit
    int turntable_frame = -1;              // frame to orbit; -1 = the last frame
    Vec3 albedo = Vec3(0.55, 0.42, 0.30);  // dry soil color (linear RGB)
    Real alpha_range = 0.5;                // hardening colormap spans alpha0 -/+ this
    Real fps = 24;                         // movie frame rate
};

}  // namespace mudcrack

namespace mudcrack {
/// "moisture" | "hardening" | "plain".
const char* color_mode_name(ColorMode mode);
/// The mode of a name, or nullopt for another string.
std::optional<ColorMode> parse_color_mode(const std::string& name);
/// Every mode's name, in the enum's order (the shot spec's choices).
std::vector<std::string> color_mode_names();
/// GLSL lines "#define MC_COLOR_MODE_MOISTURE 0" ..., one per mode: what the shaders compare
/// their u_mode uniform (the enum's value) with.
std::string color_mode_glsl_defines();
}  // namespace mudcrack
