#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace mudcrack {

namespace {
constexpr float kPi = 3.14159265358979f;
float radians(float deg) { return deg * kPi / 180.0f; }
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

Camera auto_frame(const Bounds& bounds, float fov_deg, float aspect, float fill) {
    Camera cam;
    cam.fov_deg = fov_deg;
    if (bounds.is_empty()) return cam;
    const Vec3f c = bounds.center();
    const float az = radians(kAutoAzimuthDeg), el = radians(kAutoElevationDeg);
    const Vec3f back(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
    // camera basis for the direction (independent of distance)
    const Vec3f f = -back;
    const Vec3f s = f.cross(Vec3f(0, 1, 0)).normalized();
    const Vec3f u = s.cross(f);
    const float tan_v = std::tan(0.5f * radians(fov_deg)) * fill;
    const float tan_h = tan_v * aspect;
    // each corner at depth (d - z) must satisfy |x| <= tan_h (d - z) and |y| <= tan_v (d - z)
    float d = 0;
    for (int i = 0; i < 8; ++i) {
        const Vec3f p((i & 1) ? bounds.max.x() : bounds.min.x(),
                      (i & 2) ? bounds.max.y() : bounds.min.y(),
                      (i & 4) ? bounds.max.z() : bounds.min.z());
        const Vec3f q = p - c;
        const float x = q.dot(s), y = q.dot(u), z = -q.dot(f);  // z > 0: towards the camera
        d = std::max({d, z + std::abs(x) / tan_h, z + std::abs(y) / tan_v});
    }
    d = std::max(d, 1e-3f);
    cam.target = c;
    cam.position = c + back * d;
    return cam;
}

Camera resolve_camera(const CameraParams& params, const Bounds& bounds, float aspect) {
    if (params.is_auto) return auto_frame(bounds, float(params.fov_deg), aspect);
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
    return orbit(base, 2.0f * kPi * float(view) / float(std::max(views, 1)));
}

}  // namespace mudcrack
