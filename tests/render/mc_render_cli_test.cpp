// mc-render end to end on fabricated inputs (surfaced meshes, or a particle cache), plus bad input:
// exit codes, the files written, the manifest, and no half-written output on failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/io/image_io.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "pipeline/shot/shot.h"
#include "render/movie_encoder.h"
#include "synthetic_scenes.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

const char* kSurfacedShot = R"({
  "mudcrack": 1, "name": "render_cli",
  "source": { "type": "box" }, "material": {},
  "plasticity": { "alpha0": -0.04 },
  "moisture": {},
  "frames": { "start": 1, "end": 3, "fps": 24 },
  "surfacing": { "format": "glb" },
  "render": { "resolution": [96, 64], "color_mode": "COLOR", "turntable": { "views": 6 } }
})";

const char* kParticleShot = R"({
  "mudcrack": 1, "name": "render_cli_points",
  "source": { "type": "box" }, "material": {},
  "moisture": {},
  "sim": { "h": 0.1 },
  "frames": { "start": 1, "end": 2, "fps": 24 },
  "render": { "resolution": [80, 60] }
})";

class McRenderCli : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() / ("mudcrack_render_cli_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir / "out");
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(m_dir, ec);
    }

    Shot write_shot(std::string text, const std::string& color_mode = "moisture") {
        const size_t at = text.find("COLOR");
        if (at != std::string::npos) text.replace(at, 5, color_mode);
        std::ofstream(m_dir / "shot.json") << text;
        return load_shot((m_dir / "shot.json").string());
    }

    /// A sphere drifting up by 0.1 m per frame plus a crack block, as mc-surface would write them.
    void write_surface(const Shot& shot, int frames) {
        const fs::path dir = out() / "surface";
        fs::create_directories(dir);
        for (int f = 1; f <= frames; ++f) {
            TriMesh sphere = test::uv_sphere(Vec3f(0, 0.5f + 0.1f * f, 0), 0.5f, 16, 32);
            export_meshes(frame_path(dir, "boundary", f, "glb"), {sphere}, "glb");
            TriMesh crack = test::box_mesh(Vec3f(0.6f, 0, -0.2f), Vec3f(1.0f, 0.2f, 0.2f), "crack",
                                           [](const Vec3f&, float& s, float& a) { s = 0.8f; a = -0.2f; });
            export_meshes(frame_path(dir, "crack", f, "glb"), {crack}, "glb");
        }
        nlohmann::json m = make_manifest("surface", shot.path, shot.slice_hash(Stage::Surface));
        m["frames"] = {{"first", 1}, {"last", frames}, {"count", frames}};
        write_manifest(dir, m);
    }

    void write_particles(const Shot& shot, int frames) {
        const fs::path dir = out() / "sim";
        fs::create_directories(dir);
        for (int f = 1; f <= frames; ++f) {
            const ParticleSprites ps = test::particle_ball(Vec3f(0, 0.3f, 0), 0.3f, 0.05f);
            ParticleFrame pf;
            pf.frame = f;
            pf.P = ps.positions;
            pf.saturation = ps.saturation;
            write_points(frame_path(dir, "particles", f, "vdb"), frame_to_points(pf), 0.05);
        }
        nlohmann::json m = make_manifest("sim", shot.path, shot.slice_hash(Stage::Sim));
        m["frames"] = {{"first", 1}, {"last", frames}, {"count", frames}};
        write_manifest(dir, m);
    }

    /// Runs mc-render; returns the exit code and keeps stderr in m_stderr.
    int run(const std::string& extra = "") {
        const fs::path err = m_dir / "stderr.txt";
        const std::string cmd = std::string(MUDCRACK_BIN_DIR) + "/mc-render --shot '" + (m_dir / "shot.json").string() +
                                "' --out '" + out().string() + "' " + extra + " > '" + (m_dir / "stdout.txt").string() +
                                "' 2> '" + err.string() + "'";
        const int status = std::system(cmd.c_str());
        std::ifstream is(err);
        std::stringstream ss;
        ss << is.rdbuf();
        m_stderr = ss.str();
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    fs::path out() const { return m_dir / "out"; }
    fs::path m_dir;
    std::string m_stderr;
};

TEST_F(McRenderCli, RendersFramesTurntableSheetAndManifest) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    ASSERT_EQ(run(), 0) << m_stderr;
    const fs::path r = out() / "render";
    for (int f = 1; f <= 3; ++f) {
        const Image img = read_png(frame_path(r, "frame", f, "png"));
        EXPECT_EQ(img.width, 96);
        EXPECT_EQ(img.height, 64);
    }
    for (int v = 1; v <= 6; ++v) EXPECT_TRUE(fs::exists(frame_path(r, "turntable", v, "png"))) << v;
    EXPECT_FALSE(fs::exists(frame_path(r, "turntable", 7, "png")));
    EXPECT_GT(read_png(r / "contact_sheet.png").width, 96);
    const nlohmann::json m = read_manifest(r);
    EXPECT_EQ(m.at("stage"), "render");
    EXPECT_EQ(m.at("frames").at("count"), 3);
    EXPECT_EQ(m.at("views"), 6);
    EXPECT_EQ(m.at("resolution"), nlohmann::json({96, 64}));
    EXPECT_GT(m.at("triangles").at("max_per_frame").get<int>(), 900);
    EXPECT_GT(m.at("seconds_per_frame").get<double>(), 0.0);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    EXPECT_EQ(fs::exists(r / "preview.mp4"), has_ffmpeg);
    EXPECT_EQ(fs::exists(r / "turntable.mp4"), has_ffmpeg);
    EXPECT_FALSE(fs::exists(out() / ".render.partial"));
}

TEST_F(McRenderCli, FrameRangeAndHardeningMode) {
    const Shot shot = write_shot(kSurfacedShot, "hardening");
    write_surface(shot, 3);
    ASSERT_EQ(run("--frames 2-3"), 0) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render/frame.0001.png"));
    EXPECT_TRUE(fs::exists(out() / "render/frame.0003.png"));
    EXPECT_EQ(read_manifest(out() / "render").at("color_mode"), "hardening");
}

TEST_F(McRenderCli, RendersParticlesWithoutSurfacing) {
    const Shot shot = write_shot(kParticleShot);
    write_particles(shot, 2);
    ASSERT_EQ(run("--turntable"), 0) << m_stderr;
    const nlohmann::json m = read_manifest(out() / "render");
    EXPECT_EQ(m.at("source"), "particles");
    EXPECT_EQ(m.at("views"), 36) << "--turntable uses the default view count";
    EXPECT_TRUE(fs::exists(out() / "render/frame.0002.png"));
    EXPECT_GT(m.at("particle_radius").get<double>(), 0.01);
}

TEST_F(McRenderCli, MissingMeshFailsCleanly) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    fs::remove(out() / "surface/crack.0002.glb");
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("crack.0002.glb"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render"));
    EXPECT_FALSE(fs::exists(out() / ".render.partial"));
}

TEST_F(McRenderCli, MissingSurfaceStageIsNamed) {
    write_shot(kSurfacedShot);
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("mc-surface"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render"));
}

TEST_F(McRenderCli, BadShotValuesAreRefused) {
    // an unknown color mode and a zero resolution never get past the shot layer
    std::string text = kSurfacedShot;
    std::ofstream(m_dir / "shot.json") << std::string(text).replace(text.find("COLOR"), 5, "rainbow");
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("/render/color_mode"), std::string::npos) << m_stderr;
    text.replace(text.find("[96, 64]"), 8, "[0, 64]");
    std::ofstream(m_dir / "shot.json") << std::string(text).replace(text.find("COLOR"), 5, "plain");
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("/render/resolution"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render"));
}

TEST_F(McRenderCli, UsageErrorsExit2) {
    const int status = std::system((std::string(MUDCRACK_BIN_DIR) + "/mc-render > /dev/null 2>&1").c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2);
}

}  // namespace
}  // namespace mudcrack
