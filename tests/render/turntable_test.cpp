// Turntables: coverage varies smoothly along the orbit; the movie is playable with one frame per
// view (when ffmpeg is installed); contact sheets and the bitmap font.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "render/bitmap_font.h"
#include "render/contact_sheet.h"
#include "render/movie_encoder.h"
#include "render/renderer.h"
#include "sim/core/error.h"
#include "synthetic_scenes.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

/// An asymmetric scene: a long slab and a ball, so coverage changes with the view angle.
Scene asymmetric_scene() {
    Scene s;
    s.meshes.push_back(
        {test::box_mesh(Vec3f(-1.0f, 0, -0.15f), Vec3f(1.0f, 0.3f, 0.15f), "boundary",
                        [](const Vec3f& p, float& sat, float& a) {
                            sat = 0.5f + 0.5f * p.x();
                            a = 0;
                        }),
         SurfaceKind::Boundary});
    s.meshes.push_back(
        {test::uv_sphere(Vec3f(0.6f, 0.55f, 0), 0.25f, 16, 32), SurfaceKind::Boundary});
    return s;
}

std::vector<RenderedImage> render_turntable(int views, int width, int height) {
    RenderParams p;
    p.width = width;
    p.height = height;
    p.samples = 4;
    Renderer r(p);
    const Scene s = asymmetric_scene();
    r.set_scene(s);
    // frame the whole orbit: the bounds of the scene's horizontal circle
    Bounds b = scene_bounds(s);
    const float R = std::max(
        {std::abs(b.min.x()), std::abs(b.max.x()), std::abs(b.min.z()), std::abs(b.max.z())});
    b.extend(Vec3f(-R, b.min.y(), -R));
    b.extend(Vec3f(R, b.max.y(), R));
    const Camera base = auto_frame(b, 35, float(width) / float(height));
    std::vector<RenderedImage> out;
    for (int v = 0; v < views; ++v) out.push_back(r.render(turntable_camera(base, v, views)));
    return out;
}

std::string run_and_read(const std::string& command) {
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
    if (!pipe) return {};
    std::string out;
    char buf[256];
    while (fgets(buf, sizeof buf, pipe.get())) out += buf;
    return out;
}

TEST(Turntable, CoverageVariesSmoothly) {
    const int views = 36;  // the shot default: 10 degrees apart
    const std::vector<RenderedImage> images = render_turntable(views, 96, 72);
    ASSERT_EQ(int(images.size()), views);
    std::vector<double> cov;
    for (const RenderedImage& img : images) cov.push_back(coverage_fraction(img));
    const auto [lo, hi] = std::minmax_element(cov.begin(), cov.end());
    const double range = *hi - *lo;
    double max_step = 0;
    for (int v = 0; v < views; ++v)
        max_step = std::max(max_step, std::abs(cov[(v + 1) % views] - cov[v]));
    EXPECT_GT(*lo, 0.02) << "the object is in every view";
    EXPECT_GT(range, 0.01) << "an asymmetric object changes its silhouette";
    RecordProperty("max_step_over_range", std::to_string(max_step / range));
    EXPECT_LT(max_step, 0.4 * range)
        << "coverage jumps: max step " << max_step << ", range " << range;
    // views half a turn apart see mirror-like silhouettes of similar area
    EXPECT_NEAR(cov[0], cov[views / 2], 0.25 * range);
}

TEST(Turntable, MovieHasOneFramePerView) {
    if (find_on_path("ffmpeg").empty() || find_on_path("ffprobe").empty())
        GTEST_SKIP() << "ffmpeg/ffprobe not on PATH: movies are skipped (PNGs only)";
    const int views = 12;
    const std::vector<RenderedImage> images = render_turntable(views, 121, 91);  // odd: padded
    const fs::path dir =
        fs::temp_directory_path() / ("mudcrack_render_movie_" + std::to_string(getpid()));
    fs::create_directories(dir);
    const fs::path movie = dir / "turntable.mp4";
    {
        MovieEncoder enc(movie, 121, 91, 24);
        for (const RenderedImage& img : images) enc.add_frame(img);
        EXPECT_FALSE(fs::exists(movie)) << "the movie appears only when finished";
        enc.finish();
    }
    ASSERT_TRUE(fs::exists(movie));
    EXPECT_FALSE(fs::exists(dir / "turntable.mp4.tmp"));
    const std::string probe = run_and_read(
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=nb_read_frames,width,height,codec_name,pix_fmt -of default=noprint_wrappers=1 '" +
        movie.string() + "'");
    EXPECT_NE(probe.find("nb_read_frames=" + std::to_string(views)), std::string::npos) << probe;
    EXPECT_NE(probe.find("codec_name=h264"), std::string::npos) << probe;
    EXPECT_NE(probe.find("pix_fmt=yuv420p"), std::string::npos) << probe;
    EXPECT_NE(probe.find("width=122"), std::string::npos) << probe;
    EXPECT_NE(probe.find("height=92"), std::string::npos) << probe;
    fs::remove_all(dir);
}

TEST(Turntable, UnfinishedMovieLeavesNothing) {
    if (find_on_path("ffmpeg").empty()) GTEST_SKIP() << "ffmpeg not on PATH";
    const fs::path dir =
        fs::temp_directory_path() / ("mudcrack_render_abort_" + std::to_string(getpid()));
    fs::create_directories(dir);
    RenderedImage frame;
    frame.width = 32;
    frame.height = 24;
    frame.rgba.assign(32 * 24 * 4, 128);
    {
        MovieEncoder enc(dir / "preview.mp4", 32, 24, 24);
        enc.add_frame(frame);
        RenderedImage wrong = frame;
        wrong.width = 31;
        EXPECT_THROW(enc.add_frame(wrong), InputError);
    }  // destroyed without finish(): a failed run
    EXPECT_TRUE(fs::is_empty(dir)) << "no movie and no temporary file";
    fs::remove_all(dir);
}

TEST(ContactSheet, GridWithFrameLabels) {
    std::vector<std::pair<int, RenderedImage>> frames;
    for (int f = 1; f <= 5; ++f) {
        RenderedImage img;
        img.width = 80;
        img.height = 60;
        img.rgba.assign(80 * 60 * 4, 255);
        fill_rect(img, 0, 0, 80, 60, {uint8_t(40 * f), 100, 100});
        frames.emplace_back(f * 10, img);
    }
    const RenderedImage sheet = contact_sheet(frames, 3);
    EXPECT_EQ(sheet.width, 6 + 3 * (80 + 6));
    EXPECT_EQ(sheet.height, 6 + 2 * (60 + 6));
    // thumbnail 4 (frame 40) sits at row 1, column 0; its top-left pixel keeps its color
    const size_t i = (size_t(6 + 66) * sheet.width + 6) * 4;
    EXPECT_EQ(sheet.rgba[i], 160);
    // its label is drawn in light text near the bottom left
    int text_pixels = 0;
    for (int y = 72 + 60 - 12; y < 72 + 60; ++y)
        for (int x = 6; x < 6 + 40; ++x)
            text_pixels += sheet.rgba[(size_t(y) * sheet.width + x) * 4 + 1] > 200;
    EXPECT_GT(text_pixels, 20);
    EXPECT_THROW(contact_sheet({}, 3), InputError);
}

TEST(BitmapFont, DrawsTheGlyphs) {
    RenderedImage img;
    img.width = 20;
    img.height = 10;
    img.rgba.assign(20 * 10 * 4, 0);
    draw_text(img, 1, 1, "1", 1, {255, 255, 255});
    auto lit = [&](int x, int y) { return img.rgba[(size_t(y) * img.width + x) * 4] == 255; };
    // "1": the stem at column 2 on every row, the foot spans columns 1..3 on the last row
    for (int r = 0; r < kGlyphHeight; ++r) EXPECT_TRUE(lit(1 + 2, 1 + r)) << "row " << r;
    EXPECT_TRUE(lit(1 + 1, 7) && lit(1 + 3, 7));
    EXPECT_FALSE(lit(1 + 0, 1));
    EXPECT_EQ(text_width("0012", 2), (4 * 6 - 1) * 2);
}

TEST(ContactSheet, DownscaleAveragesBoxes) {
    RenderedImage img;
    img.width = 4;
    img.height = 2;
    img.rgba = {0, 0, 0, 255, 100, 100, 100, 255, 200, 200, 200, 255, 40, 40, 40, 255,
                0, 0, 0, 255, 100, 100, 100, 255, 200, 200, 200, 255, 40, 40, 40, 255};
    const RenderedImage half = downscale(img, 2);
    ASSERT_EQ(half.height, 1);
    EXPECT_EQ(half.rgba[0], 50);
    EXPECT_EQ(half.rgba[4], 120);
}

}  // namespace
}  // namespace mudcrack
