// The preview renderer on small synthetic scenes: goldens, color modes, crack shading, MSAA,
// coverage, determinism and bad input.
#include <gtest/gtest.h>

#include <cmath>

#include "image_compare.h"
#include "render/colormap.h"
#include "render/renderer.h"
#include "sim/core/error.h"
#include "synthetic_scenes.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

// the lit halves of a symmetric scene: brightness ratio against 1
constexpr double kSymmetricLight = 0.06;

RenderParams small_params(ColorMode mode, int width = 160, int height = 120) {
    RenderParams p;
    p.width = width;
    p.height = height;
    p.color_mode = mode;
    p.samples = 4;
    return p;
}

/// A sphere (wet at the bottom, hardened at -x) next to a crack block.
Scene sphere_scene() {
    Scene s;
    s.meshes.push_back({test::uv_sphere(Vec3f(0, 0.5f, 0), 0.5f, 32, 64), SurfaceKind::Boundary});
    s.meshes.push_back({test::box_mesh(Vec3f(0.6f, 0, -0.3f), Vec3f(1.1f, 0.3f, 0.2f), "crack",
                                       [](const Vec3f& p, float& sat, float& a) {
                                           sat = p.y() / 0.3f;
                                           a = 0.3f;
                                       }),
                        SurfaceKind::Crack});
    return s;
}

RenderedImage render_auto(const RenderParams& params, const Scene& scene,
                          const ShadingOptions& options = {}) {
    Renderer r(params, options);
    r.set_scene(scene);
    return r.render(
        auto_frame(scene_bounds(scene), 35, float(params.width) / float(params.height)));
}

TEST(RenderGolden, SphereMoisture) {
    test::expect_matches_golden(render_auto(small_params(ColorMode::Moisture), sphere_scene()),
                                "sphere_moisture");
}

TEST(RenderGolden, SphereHardening) {
    test::expect_matches_golden(render_auto(small_params(ColorMode::Hardening), sphere_scene()),
                                "sphere_hardening");
}

TEST(RenderGolden, SpherePlain) {
    test::expect_matches_golden(render_auto(small_params(ColorMode::Plain), sphere_scene()),
                                "sphere_plain");
}

TEST(RenderGolden, ParticlesMoisture) {
    Scene s;
    s.particles = test::particle_ball(Vec3f(0, 0.3f, 0), 0.3f, 0.06f);
    test::expect_matches_golden(render_auto(small_params(ColorMode::Moisture), s),
                                "particles_moisture");
}

/// A slab split at x = 0 seen from the front (screen x follows world x): left half `left_s`,
/// right half `right_s` saturation. Returns (left, right) mean luma of object pixels.
std::pair<double, double> half_lumas(ColorMode mode, float left_s, float right_s,
                                     SurfaceKind kind) {
    Scene s;
    auto half = [&](float x0, float x1, float sat) {
        return test::box_mesh(Vec3f(x0, 0, -0.5f), Vec3f(x1, 0.1f, 0.5f), "boundary",
                              [sat](const Vec3f&, float& si, float& a) {
                                  si = sat;
                                  a = 0;
                              });
    };
    s.meshes.push_back({half(-1, 0, left_s), kind});
    s.meshes.push_back({half(0, 1, right_s), kind});
    const RenderParams p = small_params(mode);
    Renderer r(p);
    r.set_scene(s);
    Camera cam;
    cam.position = Vec3f(0, 2.0f, 2.0f);
    cam.target = Vec3f(0, 0.05f, 0);
    const RenderedImage img = r.render(cam);
    return {test::mean_object_luma(img, 0, 0, p.width / 2, p.height),
            test::mean_object_luma(img, p.width / 2, 0, p.width, p.height)};
}

TEST(RenderMoisture, WetHalfIsDarker) {
    const auto [wet, dry] = half_lumas(ColorMode::Moisture, 1.0f, 0.0f, SurfaceKind::Boundary);
    ASSERT_FALSE(std::isnan(wet) || std::isnan(dry));
    RecordProperty("wet_over_dry", std::to_string(wet / dry));
    EXPECT_LT(wet, 0.8 * dry) << "wet " << wet << " dry " << dry;
    EXPECT_GT(wet, 10.0) << "the wet half should still be readable, not black";
    // control: in plain mode the two halves are lit alike, so the difference is the moisture
    const auto [left, right] = half_lumas(ColorMode::Plain, 1.0f, 0.0f, SurfaceKind::Boundary);
    RecordProperty("plain_left_over_right", std::to_string(left / right));
    EXPECT_NEAR(left / right, 1.0, kSymmetricLight) << "left " << left << " right " << right;
}

TEST(RenderCracks, CrackFacesReadDarkerThanBoundary) {
    const auto [b, b2] = half_lumas(ColorMode::Plain, 0, 0, SurfaceKind::Boundary);
    const auto [c, c2] = half_lumas(ColorMode::Plain, 0, 0, SurfaceKind::Crack);
    RecordProperty("crack_over_boundary", std::to_string(c / b));
    EXPECT_LT(c, 0.85 * b) << "crack " << c << " boundary " << b;
    EXPECT_LT(c2, 0.85 * b2) << "crack " << c2 << " boundary " << b2;
}

/// Unlit render of two flat patches seen from above; mean RGB of each (full-coverage pixels).
std::pair<Vec3f, Vec3f> unlit_patch_colors(const RenderParams& p, const ShadingOptions& o,
                                           float s_left, float a_left, float s_right,
                                           float a_right) {
    Scene s;
    s.meshes.push_back({test::flat_patch(-1.0f, -0.05f, -0.5f, 0.5f, 0, 4, s_left, a_left),
                        SurfaceKind::Boundary});
    s.meshes.push_back({test::flat_patch(0.05f, 1.0f, -0.5f, 0.5f, 0, 4, s_right, a_right),
                        SurfaceKind::Boundary});
    Renderer r(p, o);
    r.set_scene(s);
    Camera cam;
    cam.position = Vec3f(0, 3, 0.3f);
    cam.target = Vec3f(0, 0, 0);
    const RenderedImage img = r.render(cam);
    auto mean_rgb = [&](int x0, int x1) {
        Vec3f sum = Vec3f::Zero();
        int n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = x0; x < x1; ++x) {
                const size_t i = size_t(y) * img.width + x;
                if (img.coverage[i] < 255) continue;
                for (int k = 0; k < 3; ++k) sum[k] += img.rgba[i * 4 + k];
                ++n;
            }
        EXPECT_GT(n, 100) << "patch not in view";
        return Vec3f(sum / float(std::max(n, 1)) / 255.0f);
    };
    return {mean_rgb(0, img.width / 2), mean_rgb(img.width / 2, img.width)};
}

void expect_rgb_near(const Vec3f& got, const Vec3f& want, const char* what) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k] * 255.0, want[k] * 255.0, tol::kColor8)
            << what << " channel " << k << ": got " << (got * 255).transpose() << " want "
            << (want * 255).transpose();
}

TEST(RenderHardening, FlatPatchShowsTheColormap) {
    RenderParams p = small_params(ColorMode::Hardening);
    p.alpha_range = 0.4;
    ShadingOptions o;
    o.alpha0 = -0.2f;  // off zero: the colormap is centered on the shot's alpha0
    o.is_unlit = true;
    o.has_ground = false;
    const float hardened = o.alpha0 - 0.2f, softened = o.alpha0 + 0.4f;
    const auto [left, right] = unlit_patch_colors(p, o, 0, hardened, 0, softened);
    expect_rgb_near(left, hardening_color(hardened, o.alpha0, float(p.alpha_range)),
                    "hardened patch");
    expect_rgb_near(right, hardening_color(softened, o.alpha0, float(p.alpha_range)),
                    "softened patch");
    // and those are the known colors: Moreland's light blue stop and the red end
    expect_rgb_near(left, Vec3f(141, 176, 254) / 255.0f, "hardened patch (known)");
    expect_rgb_near(right, Vec3f(180, 4, 38) / 255.0f, "softened patch (known)");
}

TEST(RenderMoisture, FlatPatchShowsTheDocumentedDarkening) {
    const RenderParams p = small_params(ColorMode::Moisture);
    ShadingOptions o;
    o.is_unlit = true;
    o.has_ground = false;
    const auto [wet, dry] = unlit_patch_colors(p, o, 1.0f, 0, 0.0f, 0);
    auto srgb = [](const Vec3f& c) {
        return Vec3f(linear_to_srgb(c.x()), linear_to_srgb(c.y()), linear_to_srgb(c.z()));
    };
    const Vec3f albedo = p.albedo.cast<float>();
    expect_rgb_near(wet, srgb(moisture_color(albedo, 1.0f)), "wet patch");
    expect_rgb_near(dry, srgb(albedo), "dry patch");
}

TEST(Render, MsaaSmoothsEdges) {
    auto partial_pixels = [](int samples) {
        RenderParams p = small_params(ColorMode::Plain);
        p.samples = samples;
        const RenderedImage img = render_auto(p, sphere_scene());
        int n = 0;
        for (uint8_t c : img.coverage) n += (c > 0 && c < 255);
        return n;
    };
    EXPECT_EQ(partial_pixels(1), 0);
    EXPECT_GT(partial_pixels(4), 100);
}

TEST(Render, CoverageAndBackground) {
    const RenderParams p = small_params(ColorMode::Moisture);
    const RenderedImage img = render_auto(p, sphere_scene());
    ASSERT_EQ(img.rgba.size(), size_t(p.width) * p.height * 4);
    const double cov = coverage_fraction(img);
    EXPECT_GT(cov, 0.1);
    EXPECT_LT(cov, 0.9);
    // the top row is gradient background: no coverage, grey, opaque
    for (int x = 0; x < p.width; ++x) {
        EXPECT_EQ(img.coverage[x], 0);
        EXPECT_EQ(img.rgba[x * 4 + 3], 255);
    }
    // an empty scene covers nothing
    Renderer r(p);
    r.set_scene(Scene{});
    EXPECT_EQ(coverage_fraction(r.render(Camera{})), 0.0);
}

TEST(Render, Deterministic) {
    const RenderParams p = small_params(ColorMode::Hardening);
    Renderer r(p);
    const Scene s = sphere_scene();
    r.set_scene(s);
    const Camera cam = auto_frame(scene_bounds(s), 35, 4.0f / 3.0f);
    const RenderedImage a = r.render(cam), b = r.render(cam);
    EXPECT_EQ(a.rgba, b.rgba);
}

TEST(Render, GroundSitsUnderTheStage) {
    // with the ground on, pixels under the object differ from the bare background
    const RenderParams p = small_params(ColorMode::Plain);
    ShadingOptions no_ground;
    no_ground.has_ground = false;
    const RenderedImage with = render_auto(p, sphere_scene());
    const RenderedImage without = render_auto(p, sphere_scene(), no_ground);
    const test::ImageDiff d =
        test::compare_rgb(test::to_rgb_image(with), test::to_rgb_image(without));
    EXPECT_GT(d.mean_abs, 5.0);
}

TEST(RenderErrors, BadInputIsRefused) {
    // a resolution out of kMinResolution..kMaxResolution is refused: the shot layer names the
    // file and key, and below it a bad size is a bug the renderer's precondition check stops
    RenderParams p = small_params(ColorMode::Plain);
    p.width = 0;
    ::testing::FLAGS_gtest_death_test_style = "threadsafe";
    EXPECT_DEATH(Renderer{p}, "params.width >= kMinResolution");
    p = small_params(ColorMode::Plain);
    p.height = 16385;
    EXPECT_DEATH(Renderer{p}, "params.height <= kMaxResolution");
    p = small_params(ColorMode::Plain);
    p.samples = 0;
    EXPECT_THROW(Renderer{p}, InputError);

    Renderer r(small_params(ColorMode::Plain));
    Scene bad_index;
    bad_index.meshes.push_back({test::flat_patch(0, 1, 0, 1, 0, 1, 0, 0), SurfaceKind::Boundary});
    bad_index.meshes[0].mesh.faces[0][2] = 99;
    try {
        r.set_scene(bad_index);
        ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
    }
    Scene bad_attr;
    bad_attr.meshes.push_back({test::flat_patch(0, 1, 0, 1, 0, 1, 0, 0), SurfaceKind::Boundary});
    bad_attr.meshes[0].mesh.saturation.pop_back();
    EXPECT_THROW(r.set_scene(bad_attr), InputError);
}

}  // namespace
}  // namespace mudcrack
