#include "render/camera.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

namespace mudcrack {

namespace {
constexpr float kPiF = float(kPi);  // the renderer works in float
float radians(float deg) { return deg * kPiF / 180.0f; }
}  // namespace

Eigen::Matrix4f look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up_hint) {
    const Vec3f f = (target - eye).normalized();
    Vec3f up = up_hint;
    // looking straight up or down: any perpendicular up will do
    if (std::abs(f.dot(up.normalized())) > 0.999f) up = Vec3f(0, 0, -1);
    const Vec3f s = f.cross(up).normalized();
    const Vec3f u = s.cross(f);
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.block<1, 3>(0, 0) = s.transpose();
    m.block<1, 3>(1, 0) = u.transpose();
    m.block<1, 3>(2, 0) = -f.transpose();
    m(0, 3) = -s.dot(eye);
    m(1, 3) = -u.dot(eye);
    m(2, 3) = f.dot(eye);
    return m;
}

Eigen::Matrix4f view_matrix(const Camera& camera) {
    return look_at(camera.position, camera.target, Vec3f(0, 1, 0));
}

Eigen::Matrix4f perspective_matrix(float fov_deg, float aspect, float near, float far) {
    const float f = 1.0f / std::tan(0.5f * radians(fov_deg));
    Eigen::Matrix4f m = Eigen::Matrix4f::Zero();
    m(0, 0) = f / aspect;
    m(1, 1) = f;
    m(2, 2) = (far + near) / (near - far);
    m(2, 3) = 2 * far * near / (near - far);
    m(3, 2) = -1;
    return m;
}

Eigen::Matrix4f ortho_matrix(float l, float r, float b, float t, float n, float f) {
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m(0, 0) = 2 / (r - l);
    m(1, 1) = 2 / (t - b);
    m(2, 2) = -2 / (f - n);
    m(0, 3) = -(r + l) / (r - l);
    m(1, 3) = -(t + b) / (t - b);
    m(2, 3) = -(f + n) / (f - n);
    return m;
}

namespace {
Camera default_camera(float fov_deg) {
    Camera cam;
    cam.fov_deg = fov_deg;
    return cam;
}

/// A camera looking at `target` from the default direction, at the smallest distance at which
/// every point of `points` fits in the frame with `fill` of the half-extent.
Camera frame_points(const std::vector<Vec3f>& points, const Vec3f& target, float fov_deg,
                    float aspect, float fill) {
    Camera cam;
    cam.fov_deg = fov_deg;
    const float az = radians(kAutoAzimuthDeg), el = radians(kAutoElevationDeg);
    const Vec3f back(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
    // camera basis for the direction (independent of distance)
    const Vec3f f = -back;
    const Vec3f s = f.cross(Vec3f(0, 1, 0)).normalized();
    const Vec3f u = s.cross(f);
    const float tan_v = std::tan(0.5f * radians(fov_deg)) * fill;
    const float tan_h = tan_v * aspect;
    // each point at depth (d - z) must satisfy |x| <= tan_h (d - z) and |y| <= tan_v (d - z)
    float d = 0;
    for (const Vec3f& p : points) {
        const Vec3f q = p - target;
        const float x = q.dot(s), y = q.dot(u), z = -q.dot(f);  // z > 0: towards the camera
        d = std::max({d, z + std::abs(x) / tan_h, z + std::abs(y) / tan_v});
    }
    d = std::max(d, 1e-3f);
    cam.target = target;
    cam.position = target + back * d;
    return cam;
}
}  // namespace

Camera auto_frame(const Bounds& bounds, float fov_deg, float aspect, float fill) {
    if (bounds.is_empty()) return default_camera(fov_deg);
    std::vector<Vec3f> corners;
    for (int i = 0; i < 8; ++i) corners.push_back(bounds.corner(i));
    return frame_points(corners, bounds.center(), fov_deg, aspect, fill);
}

Camera auto_frame_orbit(const Bounds& bounds, float fov_deg, float aspect, float fill) {
    if (bounds.is_empty()) return default_camera(fov_deg);
    // The box swept about the vertical axis through its center fills a cylinder of the radius of
    // its horizontal half-diagonal. The orbit turns the camera about that same axis, so every
    // view sees the cylinder alike: framing it in one view frames the box in all of them. A
    // polygon of kSides sides drawn around the circle stands for it (it holds the circle).
    constexpr int kSides = 96;
    const Vec3f c = bounds.center();
    const float r = 0.5f *
                    std::hypot(bounds.max.x() - bounds.min.x(), bounds.max.z() - bounds.min.z()) /
                    std::cos(kPiF / kSides);
    std::vector<Vec3f> rims;
    for (int k = 0; k < kSides; ++k) {
        const float a = 2 * kPiF * k / kSides;
        for (const float y : {bounds.min.y(), bounds.max.y()})
            rims.emplace_back(c.x() + r * std::cos(a), y, c.z() + r * std::sin(a));
    }
    return frame_points(rims, c, fov_deg, aspect, fill);
}

Camera resolve_camera(const CameraParams& params, const Bounds& bounds, float aspect, bool orbit) {
    if (params.is_auto)
        return orbit ? auto_frame_orbit(bounds, float(params.fov_deg), aspect)
                     : auto_frame(bounds, float(params.fov_deg), aspect);
    Camera cam;
    cam.position = params.position.cast<float>();
    cam.target = params.target.cast<float>();
    cam.fov_deg = float(params.fov_deg);
    return cam;
}

Camera orbit(const Camera& camera, float angle_rad) {
    Camera out = camera;
    const Vec3f r = camera.position - camera.target;
    const float c = std::cos(angle_rad), s = std::sin(angle_rad);
    // rotation about +y
    out.position = camera.target + Vec3f(c * r.x() + s * r.z(), r.y(), -s * r.x() + c * r.z());
    return out;
}

Camera turntable_camera(const Camera& base, int view, int views) {
    return orbit(base, 2.0f * kPiF * float(view) / float(std::max(views, 1)));
}

}  // namespace mudcrack
