// mc-render end to end on fabricated inputs (surfaced meshes, or a particle cache), plus bad input:
// exit codes, the files written, the manifest, and no half-written output on failure; and the
// farm's split (--frames chunks, then --assemble) against a full run, byte for byte.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

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
        m_dir = fs::temp_directory_path() /
                ("mudcrack_render_cli_" + std::to_string(getpid()) + "_" + info->name());
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
        // the files' checksums, which mc-render verifies
        nlohmann::json records = nlohmann::json::array();
        for (int f = 1; f <= frames; ++f) {
            TriMesh sphere = test::uv_sphere(Vec3f(0, 0.5f + 0.1f * f, 0), 0.5f, 16, 32);
            export_meshes(frame_path(dir, "boundary", f, "glb"), {sphere}, "glb");
            TriMesh crack = test::box_mesh(Vec3f(0.6f, 0, -0.2f), Vec3f(1.0f, 0.2f, 0.2f), "crack",
                                           [](const Vec3f&, float& s, float& a) {
                                               s = 0.8f;
                                               a = -0.2f;
                                           });
            export_meshes(frame_path(dir, "crack", f, "glb"), {crack}, "glb");
            records.push_back(file_record(frame_path(dir, "boundary", f, "glb")));
            records.push_back(file_record(frame_path(dir, "crack", f, "glb")));
        }
        nlohmann::json m = make_manifest("surface", shot.path, shot.slice_hash(Stage::Surface));
        m["frames"] = {{"first", 1}, {"last", frames}, {"count", frames}};
        m["outputs"] = records;
        write_manifest(dir, m);
    }

    void write_particles(const Shot& shot, int frames) {
        const fs::path dir = out() / "sim";
        fs::create_directories(dir);
        // the caches' checksums, which mc-render verifies
        nlohmann::json caches = nlohmann::json::array();
        for (int f = 1; f <= frames; ++f) {
            const ParticleSprites ps = test::particle_ball(Vec3f(0, 0.3f, 0), 0.3f, 0.05f);
            ParticleFrame pf;
            pf.frame = f;
            pf.P = ps.positions;
            pf.saturation = ps.saturation;
            write_points(frame_path(dir, "particles", f, "vdb"), frame_to_points(pf), 0.05);
            caches.push_back(file_record(frame_path(dir, "particles", f, "vdb")));
        }
        nlohmann::json m = make_manifest("sim", shot.path, shot.slice_hash(Stage::Sim));
        m["frames"] = {{"first", 1}, {"last", frames}, {"count", frames}};
        m["caches"] = caches;
        write_manifest(dir, m);
    }

    /// Runs mc-render; returns the exit code and keeps stderr in m_stderr.
    int run(const std::string& extra = "") {
        const fs::path err = m_dir / "stderr.txt";
        const std::string cmd = std::string(MUDCRACK_BIN_DIR) + "/mc-render --shot '" +
                                (m_dir / "shot.json").string() + "' --out '" + out().string() +
                                "' " + extra + " > '" + (m_dir / "stdout.txt").string() + "' 2> '" +
                                err.string() + "'";
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

TEST_F(McRenderCli, FrameRangeWritesOnlyThoseFramesInHardeningMode) {
    const Shot shot = write_shot(kSurfacedShot, "hardening");
    write_surface(shot, 3);
    ASSERT_EQ(run("--frames 2-3"), 0) << m_stderr;
    const fs::path r = out() / "render";
    EXPECT_FALSE(fs::exists(r / "frame.0001.png"));
    EXPECT_EQ(read_png(r / "frame.0003.png").width, 96);
    EXPECT_TRUE(fs::exists(r / "frame.0002.png"));
    // a chunk: no turntable, sheet, movie or manifest (--assemble writes them)
    EXPECT_FALSE(fs::exists(r / "turntable.0001.png"));
    EXPECT_FALSE(fs::exists(r / "contact_sheet.png"));
    EXPECT_FALSE(fs::exists(r / "preview.mp4"));
    EXPECT_FALSE(fs::exists(r / "manifest.json"));
    ASSERT_EQ(run("--frames 1-1"), 0) << m_stderr;
    ASSERT_EQ(run("--assemble"), 0) << m_stderr;
    const nlohmann::json m = read_manifest(r);
    EXPECT_EQ(m.at("color_mode"), "hardening");
    EXPECT_EQ(m.at("frames").at("count"), 3);
    EXPECT_EQ(m.at("views"), 6);
}

/// Every regular file of dir by name, with its bytes.
std::map<std::string, std::string> files_of(const fs::path& dir) {
    std::map<std::string, std::string> out;
    for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
        if (!e.is_regular_file()) continue;
        std::ifstream is(e.path(), std::ios::binary);
        std::stringstream ss;
        ss << is.rdbuf();
        out[e.path().filename().string()] = ss.str();
    }
    return out;
}

TEST_F(McRenderCli, ChunksPlusAssembleAreByteIdenticalToAFullRun) {
    // 5 frames of a sphere drifting up: chunk 1-2 alone would frame it lower than the full run
    const Shot shot =
        write_shot(std::string(kSurfacedShot)
                       .replace(std::string(kSurfacedShot).find("\"end\": 3"), 8, "\"end\": 5"));
    write_surface(shot, 5);
    ASSERT_EQ(run(), 0) << m_stderr;
    const fs::path r = out() / "render";
    const nlohmann::json full_manifest = read_manifest(r);
    std::map<std::string, std::string> full = files_of(r);
    fs::remove_all(r);

    ASSERT_EQ(run("--frames 3-5"), 0) << m_stderr;  // chunks in any order
    ASSERT_EQ(run("--frames 1-2"), 0) << m_stderr;
    EXPECT_TRUE(fs::exists(r / ".chunk.0001-0002.json"));
    EXPECT_FALSE(fs::exists(r / "manifest.json"));
    ASSERT_EQ(run("--assemble"), 0) << m_stderr;
    std::map<std::string, std::string> assembled = files_of(r);
    // the chunk statistics stay, hidden, with the frames' checksums for a later assembly
    EXPECT_EQ(assembled.erase(".chunk.0001-0002.json") + assembled.erase(".chunk.0003-0005.json"),
              2u);

    // same files; every PNG and movie byte for byte (the manifests differ in timings)
    full.erase("manifest.json");
    assembled.erase("manifest.json");
    std::vector<std::string> full_names, assembled_names;
    for (const auto& [name, bytes] : full) full_names.push_back(name);
    for (const auto& [name, bytes] : assembled) assembled_names.push_back(name);
    EXPECT_EQ(assembled_names, full_names);
    EXPECT_EQ(full.size(), 5u + 6u + 1u + (find_on_path("ffmpeg").empty() ? 0u : 2u));
    for (const auto& [name, bytes] : full) {
        ASSERT_TRUE(assembled.count(name)) << name;
        EXPECT_TRUE(assembled.at(name) == bytes) << name << " differs from the full run";
    }
    const nlohmann::json m = read_manifest(r);
    EXPECT_EQ(m.at("frames"), full_manifest.at("frames"));
    EXPECT_EQ(m.at("triangles"), full_manifest.at("triangles"));
    EXPECT_EQ(m.at("contact_sheet"), full_manifest.at("contact_sheet"));
    EXPECT_EQ(m.at("movies"), full_manifest.at("movies"));
    EXPECT_GT(m.at("seconds_per_frame").get<double>(), 0.0);
    // the peak memory under the key every stage's manifest uses (mc-shot summary reads it)
    EXPECT_GT(m.at("peak_memory_bytes").get<double>(), 0.0);
    EXPECT_GT(full_manifest.at("peak_memory_bytes").get<double>(), 0.0);
}

// The camera frames the bounds of every frame. mc-surface writes each frame's bounds into its
// manifest, so mc-render does not read every frame's meshes for them: the bounds the files give
// frame the shot exactly as reading them does, and the manifest's bounds are the ones used.
TEST_F(McRenderCli, FramesTheShotFromTheSurfaceManifestsBounds) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    const fs::path r = out() / "render";
    const auto frame_png = [&] { return files_of(r).at("frame.0002.png"); };
    // a manifest without bounds (an older mc-surface): read the meshes
    ASSERT_EQ(run(), 0) << m_stderr;
    EXPECT_NE(m_stderr.find("scanned 3 frames for bounds"), std::string::npos) << m_stderr;
    const std::string scanned = frame_png();

    // the files' own bounds in the manifest: the same image, without reading the meshes for them
    const fs::path manifest_dir = out() / "surface";
    nlohmann::json m = read_manifest(manifest_dir);
    m["per_frame"] = nlohmann::json::array();
    for (int f = 1; f <= 3; ++f) {
        Vec3f lo = Vec3f::Constant(INFINITY), hi = Vec3f::Constant(-INFINITY);
        for (const char* stem : {"boundary", "crack"})
            for (const TriMesh& mesh : import_meshes(frame_path(manifest_dir, stem, f, "glb")))
                for (const Vec3f& p : mesh.positions) {
                    lo = lo.cwiseMin(p);
                    hi = hi.cwiseMax(p);
                }
        m["per_frame"].push_back(
            {{"frame", f},
             {"bounds", {{"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}}}});
    }
    write_manifest(manifest_dir, m);
    fs::remove_all(r);
    ASSERT_EQ(run(), 0) << m_stderr;
    EXPECT_EQ(m_stderr.find("scanned"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("bounds of frames 1-3 from"), std::string::npos) << m_stderr;
    EXPECT_TRUE(frame_png() == scanned)
        << "the manifest's bounds framed the shot differently from the files'";

    // bounds twice as wide in the manifest: the camera pulls back, so they are what it reads
    for (nlohmann::json& e : m["per_frame"])
        for (int k = 0; k < 3; ++k) {
            e["bounds"]["min"][k] = 2 * e["bounds"]["min"][k].get<double>() - 0.5;
            e["bounds"]["max"][k] = 2 * e["bounds"]["max"][k].get<double>() + 0.5;
        }
    write_manifest(manifest_dir, m);
    fs::remove_all(r);
    ASSERT_EQ(run(), 0) << m_stderr;
    EXPECT_FALSE(frame_png() == scanned);
}

TEST_F(McRenderCli, AssembleNamesAMissingOrStaleFrame) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    ASSERT_EQ(run("--frames 1-2"), 0) << m_stderr;
    EXPECT_EQ(run("--assemble"), 1);
    EXPECT_NE(m_stderr.find("frame.0003.png: missing"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render/manifest.json"));
    ASSERT_EQ(run("--frames 3-3"), 0) << m_stderr;
    write_surface(shot, 3);  // new surfacing: the rendered frames no longer match it
    EXPECT_EQ(run("--assemble"), 1);
    EXPECT_NE(m_stderr.find("frame.0001.png: older than"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render/manifest.json"));
}

TEST_F(McRenderCli, AssembleRefusesAFrameRange) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    EXPECT_EQ(run("--assemble --frames 1-2"), 2);  // a usage error
    EXPECT_NE(m_stderr.find("--assemble with --frames 1-2"), std::string::npos) << m_stderr;
    EXPECT_EQ(run("--frames 4-5"), 2);
    EXPECT_NE(m_stderr.find("--frames 4-5: outside the frames 1-3"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render/frame.0001.png"));
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

// the surface manifest is read through the one input check every stage makes: a manifest without
// a slice hash, or with another shot's, is refused naming the file and key
TEST_F(McRenderCli, UnhashedOrStaleSurfaceIsRefused) {
    const Shot shot = write_shot(kSurfacedShot);
    write_surface(shot, 3);
    nlohmann::json m = read_manifest(out() / "surface");
    m.erase("shot_slice_hash");
    write_manifest(out() / "surface", m);
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("surface/manifest.json: /shot_slice_hash: missing"), std::string::npos)
        << m_stderr;
    m["shot_slice_hash"] = "0000000000000000";
    write_manifest(out() / "surface", m);
    EXPECT_EQ(run(), 1);
    EXPECT_NE(
        m_stderr.find("surface/manifest.json: /shot_slice_hash = \"0000000000000000\": stale"),
        std::string::npos)
        << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render"));
}

TEST_F(McRenderCli, BadShotValuesAreRefused) {
    // an unknown color mode and a zero resolution never get past the shot layer
    std::string text = kSurfacedShot;
    std::ofstream(m_dir / "shot.json")
        << std::string(text).replace(text.find("COLOR"), 5, "rainbow");
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("/render/color_mode"), std::string::npos) << m_stderr;
    text.replace(text.find("[96, 64]"), 8, "[0, 64]");
    std::ofstream(m_dir / "shot.json") << std::string(text).replace(text.find("COLOR"), 5, "plain");
    EXPECT_EQ(run(), 1);
    EXPECT_NE(m_stderr.find("/render/resolution"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(out() / "render"));
}

TEST_F(McRenderCli, UsageErrorsExit2) {
    const int status =
        std::system((std::string(MUDCRACK_BIN_DIR) + "/mc-render > /dev/null 2>&1").c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2);
}

}  // namespace
}  // namespace mudcrack
