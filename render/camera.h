#pragma once
/// A pinhole camera, automatic framing of bounds, and the turntable orbit. y is up.
#include <Eigen/Core>

#include "render/render_params.h"
#include "render/scene.h"

namespace mudcrack {

struct Camera {
    Vec3f position = Vec3f(3, 2, 3);  // [m]
    Vec3f target = Vec3f(0, 0, 0);    // [m]
    float fov_deg = 35;               // vertical field of view [deg]
};

/// Default viewing direction of automatic framing: from the front right, above.
constexpr float kAutoAzimuthDeg = 35;    // from +z towards +x
constexpr float kAutoElevationDeg = 26;  // above the horizon

/// A camera looking at the center of `bounds` from the default direction, at the smallest
/// distance at which all 8 corners of the box fit in the frame with `fill` of the half-extent
/// (0.9 leaves a 10% margin). @param aspect width / height
Camera auto_frame(const Bounds& bounds, float fov_deg, float aspect, float fill = 0.88f);

/// The first view of a turntable around `bounds` (turntable_camera orbits it): the default
/// direction at the smallest distance at which the box stays in the frame, with `fill` of the
/// half-extent, in every view of the orbit. It frames the cylinder the box sweeps about the
/// vertical axis through its center.
Camera auto_frame_orbit(const Bounds& bounds, float fov_deg, float aspect, float fill = 0.88f);

/// The shot's camera: `params` as given, or auto-framed from `bounds` when params.is_auto (for a
/// turntable's orbit when `orbit`).
Camera resolve_camera(const CameraParams& params, const Bounds& bounds, float aspect,
                      bool orbit = false);

/// `camera` rotated by angle_rad about the vertical axis through its target (turntable view;
/// right-hand rule about +y).
Camera orbit(const Camera& camera, float angle_rad);

/// View `view` (0-based) of a turntable of `views` evenly spaced views orbiting `base` once.
Camera turntable_camera(const Camera& base, int view, int views);

/// World-to-view transform (right-handed, the camera looks down -z).
Eigen::Matrix4f view_matrix(const Camera& camera);
/// OpenGL perspective projection. @param aspect width / height @param near, far > 0 [m]
Eigen::Matrix4f perspective_matrix(float fov_deg, float aspect, float near, float far);
/// OpenGL orthographic projection of the box [l,r]x[b,t]x[-n,-f] in view space.
Eigen::Matrix4f ortho_matrix(float l, float r, float b, float t, float n, float f);
/// A view matrix looking from eye towards target with the given up hint.
Eigen::Matrix4f look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up_hint);

}  // namespace mudcrack
