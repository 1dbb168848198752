// mc-render: headless preview renders (issue 5). Reads DIR/surface/boundary.####.<ext> and
// crack.####.<ext> (or, for a shot without surfacing, DIR/sim/particles.####.vdb) and writes
// DIR/render/frame.####.png, turntable.####.png, contact_sheet.png, preview.mp4 and
// turntable.mp4 (when ffmpeg is on PATH), and manifest.json last. Everything is built in
// DIR/.render.partial/ and renamed on success, so a failed run leaves no half-written file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/io/atomic_output.h"
#include "pipeline/io/image_io.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "pipeline/shot/shot.h"
#include "render/contact_sheet.h"
#include "render/movie_encoder.h"
#include "render/renderer.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/stats.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

constexpr int kMaxSheetThumbnails = 48;   // the contact sheet samples long animations evenly
constexpr int kMaxThumbnailWidth = 320;   // [px]
constexpr float kParticleRadiusFactor = 0.55f;  // sprite radius / estimated particle spacing

/// Where the frames come from: surfaced meshes or the particle cache.
struct FrameSource {
    bool has_meshes = false;
    bool has_cracks = false;
    fs::path dir;        // DIR/surface or DIR/sim
    std::string format;  // mesh extension ("glb", ...) or "vdb"
    float particle_radius = 0;  // [m], particles only
    std::set<int> frames_without_cracks;  // mc-surface writes no crack file for a frame with no crack

    bool has_cracks_at(int f) const { return has_cracks && !frames_without_cracks.count(f); }
    fs::path boundary_path(int f) const { return frame_path(dir, "boundary", f, format); }
    fs::path crack_path(int f) const { return frame_path(dir, "crack", f, format); }
    fs::path particles_path(int f) const { return frame_path(dir, "particles", f, "vdb"); }

    /// Every file frame f needs.
    std::vector<fs::path> files(int f) const {
        if (!has_meshes) return {particles_path(f)};
        std::vector<fs::path> out = {boundary_path(f)};
        if (has_cracks_at(f)) out.push_back(crack_path(f));
        return out;
    }
};

std::string manifest_slice_hash(const json& m) {
    for (const char* key : {"shot_slice_hash", "slice_hash"}) {
        const auto it = m.find(key);
        if (it != m.end() && it->is_string()) return it->get<std::string>();
    }
    return {};
}

/// DIR/<stage>/manifest.json, checked to come from this shot's slice of that stage.
json read_input_manifest(const fs::path& dir, const Shot& shot, Stage stage, const char* producer) {
    const fs::path file = dir / "manifest.json";
    if (!fs::exists(file)) throw InputError(file.string() + ": missing: run " + producer + " first");
    json m = read_manifest(dir);
    const std::string expected = shot.slice_hash(stage), found = manifest_slice_hash(m);
    if (!found.empty() && found != expected)
        throw InputError(file.string() + ": slice hash \"" + found + "\": stale for this shot (expected \"" +
                         expected + "\"): re-run " + producer);
    return m;
}

ParticleFrame read_particle_frame(const fs::path& path) {
    return points_to_frame(read_points(path), path.string());
}

/// The scene of frame f, meshes tagged boundary/crack by the file they came from.
Scene load_scene(const FrameSource& src, int f) {
    Scene scene;
    if (src.has_meshes) {
        for (TriMesh& m : import_meshes(src.boundary_path(f))) scene.meshes.push_back({std::move(m), SurfaceKind::Boundary});
        if (src.has_cracks_at(f))
            for (TriMesh& m : import_meshes(src.crack_path(f))) scene.meshes.push_back({std::move(m), SurfaceKind::Crack});
        return scene;
    }
    ParticleFrame pf = read_particle_frame(src.particles_path(f));
    scene.particles.positions = std::move(pf.P);
    scene.particles.saturation = std::move(pf.saturation);
    scene.particles.alpha = std::move(pf.alpha);
    scene.particles.radius = src.particle_radius;
    return scene;
}

/// Particle spacing estimated from the cloud's bounding box volume per particle (the init
/// lattices fill their box), so sprites touch like the soil they sample.
float estimate_particle_radius(const ParticleFrame& pf, double h) {
    Bounds b;
    for (const Vec3f& p : pf.P) b.extend(p);
    if (pf.P.empty() || b.is_empty()) return float(0.25 * h);
    const Vec3f e = (b.max - b.min).cwiseMax(Vec3f::Constant(float(0.5 * h)));
    const double spacing = std::cbrt(double(e.x()) * e.y() * e.z() / double(pf.P.size()));
    return kParticleRadiusFactor * float(std::min(spacing, h));
}

/// The bounds of a turntable orbit: the frame's bounds swept around the vertical axis through
/// their center, so no view of the orbit leaves the frame.
Bounds orbit_bounds(const Bounds& b) {
    if (b.is_empty()) return b;
    const Vec3f c = b.center();
    const float r = 0.5f * std::hypot(b.max.x() - b.min.x(), b.max.z() - b.min.z());
    Bounds out;
    out.extend(Vec3f(c.x() - r, b.min.y(), c.z() - r));
    out.extend(Vec3f(c.x() + r, b.max.y(), c.z() + r));
    return out;
}

Image to_png_image(RenderedImage&& img) {
    Image out;
    out.width = img.width;
    out.height = img.height;
    out.channels = 4;
    out.pixels = std::move(img.rgba);
    return out;
}

std::string frame_file(const std::string& stem, int n) {
    char name[64];
    std::snprintf(name, sizeof name, "%s.%04d.png", stem.c_str(), n);
    return name;
}

int run(const StageOptions& opt, bool force_turntable) {
    WallTimer total;
    const Shot shot = load_shot(opt.shot);
    if (!shot.render)
        throw InputError(opt.shot + ": /render: missing: the shot has no render section (add \"render\": {})");
    RenderParams params = *shot.render;
    if (params.width < 1 || params.height < 1)
        throw InputError(opt.shot + ": /render/resolution = [" + std::to_string(params.width) + ", " +
                         std::to_string(params.height) + "]: must be >= 1 pixel per side");
    const bool do_turntable = params.turntable || force_turntable;

    // inputs: the surfacing's meshes, or the particle cache when the shot has no surfacing
    const fs::path out = opt.out;
    FrameSource src;
    src.has_meshes = shot.surface.has_value();
    src.has_cracks = src.has_meshes && shot.surface->cracks;
    src.dir = out / (src.has_meshes ? "surface" : "sim");
    src.format = src.has_meshes ? shot.surface->format : "vdb";
    const json input_manifest = src.has_meshes ? read_input_manifest(src.dir, shot, Stage::Surface, "mc-surface")
                                               : read_input_manifest(src.dir, shot, Stage::Sim, "mc-sim");
    if (src.has_meshes && input_manifest.contains("per_frame") && input_manifest["per_frame"].is_array())
        for (const json& entry : input_manifest["per_frame"])
            if (entry.contains("frame") && entry.contains("crack") && entry["crack"].is_object() &&
                entry["crack"].contains("file") && entry["crack"]["file"].is_null())
                src.frames_without_cracks.insert(entry["frame"].get<int>());
    int first = shot.sim.time.frame_start, last = shot.sim.time.frame_end;
    if (input_manifest.contains("frames") && input_manifest["frames"].is_object()) {
        const json& fr = input_manifest["frames"];
        if (fr.contains("first") && fr["first"].is_number_integer()) first = fr["first"].get<int>();
        if (fr.contains("last") && fr["last"].is_number_integer()) last = fr["last"].get<int>();
    }
    const int available_first = first, available_last = last;
    if (opt.frame_range.is_set()) {
        first = opt.frame_range.first;
        last = opt.frame_range.last;
        if (first < available_first || last > available_last)
            throw InputError("--frames " + opt.frames + ": outside the frames " + std::to_string(available_first) +
                             "-" + std::to_string(available_last) + " of " + (src.dir / "manifest.json").string());
    }
    int turntable_frame = params.turntable_frame < 0 ? last : params.turntable_frame;
    if (do_turntable && (turntable_frame < available_first || turntable_frame > available_last))
        throw InputError(opt.shot + ": /render/turntable/frame = " + std::to_string(turntable_frame) +
                         ": outside the frames " + std::to_string(available_first) + "-" +
                         std::to_string(available_last) + " of " + (src.dir / "manifest.json").string());

    // every input file exists before any work starts
    std::vector<int> needed;
    for (int f = first; f <= last; ++f) needed.push_back(f);
    if (do_turntable) needed.push_back(turntable_frame);
    for (int f : needed)
        for (const fs::path& p : src.files(f))
            if (!fs::is_regular_file(p))
                throw InputError(p.string() + ": missing: run " + (src.has_meshes ? "mc-surface" : "mc-sim") +
                                 " for frame " + std::to_string(f));

    if (!src.has_meshes)
        src.particle_radius = estimate_particle_radius(read_particle_frame(src.particles_path(first)), shot.sim.h);

    // stage bounds over all frames: the camera, the ground and the shadow stay put
    WallTimer scan;
    Bounds stage;
    for (int f = first; f <= last; ++f) stage.extend(scene_bounds(load_scene(src, f)));
    if (stage.is_empty())
        throw InputError(src.dir.string() + ": frames " + std::to_string(first) + "-" + std::to_string(last) +
                         ": no geometry to render (empty meshes or particle caches)");
    log::info("scanned " + std::to_string(last - first + 1) + " frames for bounds in " +
              std::to_string(scan.seconds()) + " s");

    // llvmpipe takes its thread count from the environment when the first context is made
    if (opt.threads > 0 && !std::getenv("LP_NUM_THREADS"))
        setenv("LP_NUM_THREADS", std::to_string(opt.threads).c_str(), 1);
    ShadingOptions shading;
    shading.alpha0 = shot.sim.nacc ? float(shot.sim.nacc->alpha0) : 0.0f;
    Renderer renderer(params, shading);
    const float aspect = float(params.width) / float(params.height);
    const Camera camera = resolve_camera(params.camera, stage, aspect);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    if (!has_ffmpeg) log::info("ffmpeg is not on PATH: writing PNGs only (no preview.mp4 / turntable.mp4)");

    StagingDir staging(out / "render", opt.keep_partial);
    const fs::path dir = staging.path();
    json movies = json::array();

    // the animation
    const int n_frames = last - first + 1;
    const int sheet_stride = (n_frames + kMaxSheetThumbnails - 1) / kMaxSheetThumbnails;
    const int thumb_width = std::min(params.width, kMaxThumbnailWidth);
    std::vector<std::pair<int, RenderedImage>> thumbnails;
    std::optional<MovieEncoder> preview;
    if (has_ffmpeg) preview.emplace(dir / "preview.mp4", params.width, params.height, params.fps);
    double render_seconds = 0;
    size_t max_triangles = 0, total_triangles = 0;
    for (int f = first; f <= last; ++f) {
        const Scene scene = load_scene(src, f);
        const size_t tris = triangle_count(scene);
        max_triangles = std::max(max_triangles, tris);
        total_triangles += tris;
        WallTimer t;
        renderer.set_scene(scene, stage);
        RenderedImage img = renderer.render(camera);
        render_seconds += t.seconds();
        if (preview) preview->add_frame(img);
        if ((f - first) % sheet_stride == 0) thumbnails.emplace_back(f, downscale(img, thumb_width));
        write_png(dir / frame_file("frame", f), to_png_image(std::move(img)));
        log::debug("frame " + std::to_string(f) + ": " + std::to_string(tris) + " triangles, " +
                   std::to_string(t.seconds()) + " s");
    }
    if (preview) {
        preview->finish();
        movies.push_back("preview.mp4");
    }
    const int columns = contact_sheet_columns(int(thumbnails.size()), double(params.width) / params.height);
    write_png(dir / "contact_sheet.png", to_png_image(contact_sheet(thumbnails, columns)));
    log::info("rendered frames " + std::to_string(first) + "-" + std::to_string(last));

    // the turntable: an orbit around one frame, framed so no view clips
    int views = 0;
    double turntable_seconds = 0;
    if (do_turntable) {
        views = params.turntable_views;
        const Scene scene = load_scene(src, turntable_frame);
        Bounds b = scene_bounds(scene);
        if (b.is_empty()) b = stage;
        const Camera base = resolve_camera(params.camera, orbit_bounds(b), aspect);
        renderer.set_scene(scene, b);
        std::optional<MovieEncoder> movie;
        if (has_ffmpeg) movie.emplace(dir / "turntable.mp4", params.width, params.height, params.fps);
        for (int v = 0; v < views; ++v) {
            WallTimer t;
            RenderedImage img = renderer.render(turntable_camera(base, v, views));
            turntable_seconds += t.seconds();
            if (movie) movie->add_frame(img);
            write_png(dir / frame_file("turntable", v + 1), to_png_image(std::move(img)));
        }
        if (movie) {
            movie->finish();
            movies.push_back("turntable.mp4");
        }
        log::info("rendered a " + std::to_string(views) + "-view turntable of frame " + std::to_string(turntable_frame));
    }

    // the manifest, last
    const double per_frame = render_seconds / n_frames;
    json m = make_manifest("render", shot.path, shot.slice_hash(Stage::Render));
    m["inputs"] = {{src.has_meshes ? "surface" : "sim",
                    {{"dir", src.dir.string()}, {"slice_hash", manifest_slice_hash(input_manifest)}}}};
    m["frames"] = {{"first", first}, {"last", last}, {"count", n_frames}, {"fps", params.fps}};
    m["source"] = src.has_meshes ? "meshes" : "particles";
    m["resolution"] = {params.width, params.height};
    m["samples"] = renderer.samples();
    m["color_mode"] = color_mode_name(params.color_mode);
    m["gl_renderer"] = renderer.gl_renderer();
    m["triangles"] = {{"max_per_frame", max_triangles}, {"total", total_triangles}};
    if (!src.has_meshes) m["particle_radius"] = src.particle_radius;
    m["seconds_per_frame"] = per_frame;
    m["turntable"] = do_turntable ? json{{"frame", turntable_frame}, {"views", views},
                                         {"seconds_per_view", turntable_seconds / std::max(views, 1)}}
                                  : json(nullptr);
    m["views"] = views;
    m["movies"] = movies;
    m["contact_sheet"] = {{"thumbnails", thumbnails.size()}, {"columns", columns}};
    m["wall_seconds"] = total.seconds();
    m["peak_rss_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    staging.commit();

    // measured results: a table on stdout
    std::printf("%-22s %s\n", "stage", "render");
    std::printf("%-22s %d-%d (%d)\n", "frames", first, last, n_frames);
    std::printf("%-22s %d\n", "turntable views", views);
    std::printf("%-22s %dx%d, %d samples\n", "resolution", params.width, params.height, renderer.samples());
    std::printf("%-22s %zu\n", "triangles (max/frame)", max_triangles);
    std::printf("%-22s %.3f\n", "seconds per frame", per_frame);
    std::printf("%-22s %s\n", "movies", has_ffmpeg ? "preview.mp4 turntable.mp4" : "none (no ffmpeg)");
    std::printf("%-22s %s\n", "output", (out / "render").string().c_str());
    return 0;
}

}  // namespace
}  // namespace mudcrack

int main(int argc, char** argv) {
    bool force_turntable = false;
    return mudcrack::run_stage(
        "mc-render",
        "Headless preview renders (OSMesa): DIR/render/frame.####.png, turntable.####.png, "
        "contact_sheet.png, preview.mp4 and turntable.mp4 (with ffmpeg)",
        argc, argv,
        [&](CLI::App& app) {
            app.add_flag("--turntable", force_turntable,
                         "also render the turntable when the shot has no /render/turntable section");
        },
        [&](const mudcrack::StageOptions& opt) { return mudcrack::run(opt, force_turntable); });
}
