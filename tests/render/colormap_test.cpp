// The color conventions of the renderer on the CPU side (render/colormap.h).
#include <gtest/gtest.h>

#include "render/colormap.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
constexpr double kSrgbRoundTrip = 1e-5;  // sRGB -> linear -> sRGB in float
constexpr double kTabulated = 1e-3;      // a value against its 4-digit reference

Vec3f rgb8(int r, int g, int b) { return Vec3f(float(r), float(g), float(b)) / 255.0f; }

void expect_color_near(const Vec3f& got, const Vec3f& want, double tol8) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k] * 255.0, want[k] * 255.0, tol8)
            << "channel " << k << " got " << got.transpose() * 255 << " want "
            << want.transpose() * 255;
}

TEST(Colormap, HardeningMapsKnownAlphasToKnownColors) {
    const float alpha0 = -0.2f, range = 0.4f;
    // half way to the hardened end (alpha0 - range/2 -> t = 0.25): Moreland's light blue stop
    expect_color_near(hardening_color(alpha0 - 0.5f * range, alpha0, range), rgb8(141, 176, 254),
                      0.01);
    // fully softened (alpha0 + range -> t = 1): the dark red end
    expect_color_near(hardening_color(alpha0 + range, alpha0, range), rgb8(180, 4, 38), 0.01);
    // the center is neutral grey, beyond the range it saturates
    expect_color_near(hardening_color(alpha0, alpha0, range), rgb8(221, 221, 221), 0.01);
    expect_color_near(hardening_color(alpha0 - 5 * range, alpha0, range), rgb8(59, 76, 192), 0.01);
}

TEST(Colormap, BlueMeansHardenedRedMeansSoftened) {
    const Vec3f hardened = hardening_color(-0.3f, 0.0f, 0.5f);
    const Vec3f softened = hardening_color(+0.3f, 0.0f, 0.5f);
    EXPECT_GT(hardened.z(), hardened.x()) << hardened.transpose();
    EXPECT_GT(softened.x(), softened.z()) << softened.transpose();
}

TEST(Colormap, InterpolatesBetweenStops) {
    // t = 1/16 is half way between the first two stops
    const Vec3f mid = coolwarm(1.0f / 16.0f);
    expect_color_near(mid, 0.5f * (rgb8(59, 76, 192) + rgb8(98, 130, 234)), 0.01);
    EXPECT_FLOAT_EQ(hardening_coordinate(0.1f, 0.0f, 0.2f), 0.75f);
}

TEST(Colormap, WetterIsDarker) {
    const Vec3f albedo(0.55f, 0.42f, 0.30f);
    float previous = 2;
    for (float s = 0; s <= 1.0f; s += 0.125f) {
        const Vec3f c = moisture_color(albedo, s);
        EXPECT_LT(c.sum(), previous) << "s = " << s;
        previous = c.sum();
    }
    EXPECT_NEAR(moisture_color(albedo, 1).x(), 0.55 * (1 - kMoistureDarkening), tol::kFloat);
    EXPECT_NEAR(moisture_color(albedo, 0).x(), 0.55, tol::kFloat);
    EXPECT_NEAR(moisture_color(albedo, 7).x(), 0.55 * (1 - kMoistureDarkening), tol::kFloat)
        << "s clamps";
}

TEST(Colormap, SrgbRoundTrip) {
    for (float c = 0; c <= 1.0f; c += 0.05f)
        EXPECT_NEAR(linear_to_srgb(srgb_to_linear(c)), c, kSrgbRoundTrip) << c;
    EXPECT_NEAR(linear_to_srgb(0.18f), 0.4613, kTabulated);  // middle grey
}

}  // namespace
}  // namespace mudcrack
