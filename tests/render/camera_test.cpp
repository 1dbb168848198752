// Camera framing and the turntable orbit (no GL).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "render/camera.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound (the camera works in float)
constexpr double kOrbitAbs = 1e-4;  // positions and distances after trigonometry in float [m]
constexpr double kFloatAbs = 1e-5;  // one float operation on values of order 1-10 [m]
// auto_frame: the box's widest extent in NDC vs the asked fill
constexpr float kFrameFillAbs = 0.02f;

/// Normalized device coordinates of p seen through cam.
Eigen::Vector3f ndc(const Camera& cam, float aspect, const Vec3f& p) {
    const Eigen::Matrix4f m =
        perspective_matrix(cam.fov_deg, aspect, 0.01f, 100.0f) * view_matrix(cam);
    const Eigen::Vector4f q = m * Eigen::Vector4f(p.x(), p.y(), p.z(), 1.0f);
    return q.head<3>() / q.w();
}

TEST(Camera, AutoFrameFitsEveryCornerWithAMargin) {
    for (const float aspect : {16.0f / 9.0f, 1.0f, 0.5f}) {
        Bounds b;
        b.extend(Vec3f(-2, 0, -2));
        b.extend(Vec3f(2, 0.3f, 2));  // a flat slab: the sphere fit would be far too loose
        const Camera cam = auto_frame(b, 35, aspect, 0.88f);
        float widest = 0;
        for (int i = 0; i < 8; ++i) {
            const Vec3f p = b.corner(i);
            const Eigen::Vector3f q = ndc(cam, aspect, p);
            EXPECT_LE(std::abs(q.x()), 0.88f + 1e-4f) << "aspect " << aspect << " corner " << i;
            EXPECT_LE(std::abs(q.y()), 0.88f + 1e-4f) << "aspect " << aspect << " corner " << i;
            widest = std::max({widest, std::abs(q.x()), std::abs(q.y())});
        }
        // tight: some corner touches the margin
        EXPECT_NEAR(widest, 0.88f, kFrameFillAbs) << "aspect " << aspect;
    }
}

TEST(Camera, OrbitFrameKeepsTheBoxInEveryViewOfTheTurntable) {
    for (const float aspect : {16.0f / 9.0f, 1.0f}) {
        Bounds b;
        b.extend(Vec3f(-18, 0, -18));  // the riverbed: a wide flat patch, off the origin
        b.extend(Vec3f(20, 0.5f, 16));
        const Camera base = auto_frame_orbit(b, 35, aspect, 0.88f);
        const int views = 72;
        float widest = 0;
        for (int v = 0; v < views; ++v) {
            const Camera cam = turntable_camera(base, v, views);
            for (int i = 0; i < 8; ++i) {
                const Vec3f p = b.corner(i);
                const Eigen::Vector3f q = ndc(cam, aspect, p);
                EXPECT_LE(std::abs(q.x()), 0.88f + 1e-4f)
                    << "aspect " << aspect << " view " << v << " corner " << i;
                EXPECT_LE(std::abs(q.y()), 0.88f + 1e-4f)
                    << "aspect " << aspect << " view " << v << " corner " << i;
                widest = std::max({widest, std::abs(q.x()), std::abs(q.y())});
            }
        }
        // tight: in some view a corner comes to the margin
        EXPECT_NEAR(widest, 0.88f, kFrameFillAbs) << "aspect " << aspect;
        // and closer than framing the square the box sweeps (what the turntable framed before)
        const Vec3f c = b.center();
        const float r = 0.5f * std::hypot(b.max.x() - b.min.x(), b.max.z() - b.min.z());
        Bounds square;
        square.extend(Vec3f(c.x() - r, b.min.y(), c.z() - r));
        square.extend(Vec3f(c.x() + r, b.max.y(), c.z() + r));
        const Camera loose = auto_frame(square, 35, aspect, 0.88f);
        EXPECT_LT((base.position - base.target).norm(),
                  0.8f * (loose.position - loose.target).norm());
        EXPECT_NEAR((base.target - c).norm(), 0, kOrbitAbs);
    }
}

TEST(Camera, ExplicitCameraIsKept) {
    CameraParams p;
    p.is_auto = false;
    p.position = Vec3(1, 2, 3);
    p.target = Vec3(0, 1, 0);
    p.fov_deg = 50;
    Bounds b;
    b.extend(Vec3f(-1, -1, -1));
    b.extend(Vec3f(1, 1, 1));
    const Camera cam = resolve_camera(p, b, 1.5f);
    EXPECT_NEAR((cam.position - resolve_camera(p, b, 1.5f, /*orbit=*/true).position).norm(), 0,
                tol::kFloat);
    EXPECT_NEAR((cam.position - Vec3f(1, 2, 3)).norm(), 0, tol::kFloat);
    EXPECT_NEAR((cam.target - Vec3f(0, 1, 0)).norm(), 0, tol::kFloat);
    EXPECT_FLOAT_EQ(cam.fov_deg, 50);
}

TEST(Camera, TurntableOrbitsAtConstantDistanceAndHeight) {
    Camera base;
    base.position = Vec3f(3, 2, 1);
    base.target = Vec3f(0.5f, 0.2f, -0.5f);
    const float d0 = (base.position - base.target).norm();
    const int views = 8;
    for (int v = 0; v < views; ++v) {
        const Camera c = turntable_camera(base, v, views);
        EXPECT_NEAR((c.position - c.target).norm(), d0, kOrbitAbs);
        EXPECT_NEAR(c.position.y(), base.position.y(), kFloatAbs);
    }
    // a quarter turn is two views of eight, and a full turn comes back
    const Camera q = turntable_camera(base, 2, views);
    const Vec3f r0 = base.position - base.target, r1 = q.position - q.target;
    EXPECT_NEAR(r0.x() * r1.x() + r0.z() * r1.z(), 0.0, kOrbitAbs);
    EXPECT_NEAR((turntable_camera(base, views, views).position - base.position).norm(), 0,
                kOrbitAbs);
}

TEST(Camera, ViewMatrixLooksDownMinusZ) {
    Camera c;
    c.position = Vec3f(0, 0, 5);
    c.target = Vec3f(0, 0, 0);
    const Eigen::Vector4f t = view_matrix(c) * Eigen::Vector4f(0, 0, 0, 1);
    EXPECT_NEAR(t.z(), -5, kFloatAbs);
    // straight down still gives a valid basis
    c.position = Vec3f(0, 5, 0);
    const Eigen::Matrix4f m = view_matrix(c);
    EXPECT_TRUE(m.allFinite());
    EXPECT_NEAR((m * Eigen::Vector4f(0, 0, 0, 1)).z(), -5, kFloatAbs);
}

}  // namespace
}  // namespace mudcrack
