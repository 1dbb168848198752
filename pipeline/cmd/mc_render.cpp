// mc-render: headless preview renders (issue 5). Reads DIR/surface/boundary.####.<ext> and
// crack.####.<ext> (or, for a shot without surfacing, DIR/sim/particles.####.vdb) and writes
// DIR/render/frame.####.png, turntable.####.png, contact_sheet.png, preview.mp4 and
// turntable.mp4 (when ffmpeg is on PATH), and manifest.json last. A full run builds everything in
// DIR/.render.partial/ and renames it on success, so a failed run leaves no half-written file.
// A farm splits the same work in two (issue 8): `--frames A-B` jobs render chunks of frames into
// DIR/render/ (each PNG renamed into place), then one `--assemble` job makes the turntable, the
// contact sheet, the movies and the manifest from those PNGs. Both ways give the same bytes: every
// frame is framed from the bounds of all frames of the shot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
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

/// What one mc-render run does. A full run is a Frames run over every frame followed by an
/// Assemble run, done in one process; the farm runs them as separate jobs.
enum class Mode {
    Full,      // every frame, the turntable, the contact sheet, the movies, manifest.json
    Frames,    // --frames A-B: frame.A..B PNGs only, each renamed into DIR/render/ when complete
    Assemble,  // --assemble: the turntable, contact sheet, movies and manifest from the frame PNGs
};

/// The shot's render settings and inputs, resolved and checked.
struct RenderJob {
    Shot shot;
    RenderParams params;
    FrameSource src;
    json input_manifest;
    int first = 0, last = 0;  // every frame of the shot (those of the input stage)
    bool do_turntable = false;
    int turntable_frame = 0;
    float aspect() const { return float(params.width) / float(params.height); }
};

/// Per frame: triangles drawn and seconds spent in the renderer.
struct FrameStats {
    std::map<int, size_t> triangles;
    std::map<int, double> seconds;
};

RenderJob resolve_job(const StageOptions& opt, bool force_turntable) {
    RenderJob job;
    job.shot = load_shot(opt.shot);
    const Shot& shot = job.shot;
    if (!shot.render)
        throw InputError(opt.shot + ": /render: missing: the shot has no render section (add \"render\": {})");
    job.params = *shot.render;
    const RenderParams& params = job.params;
    if (params.width < 1 || params.height < 1)
        throw InputError(opt.shot + ": /render/resolution = [" + std::to_string(params.width) + ", " +
                         std::to_string(params.height) + "]: must be >= 1 pixel per side");
    job.do_turntable = params.turntable || force_turntable;

    // inputs: the surfacing's meshes, or the particle cache when the shot has no surfacing
    FrameSource& src = job.src;
    src.has_meshes = shot.surface.has_value();
    src.has_cracks = src.has_meshes && shot.surface->cracks;
    src.dir = fs::path(opt.out) / (src.has_meshes ? "surface" : "sim");
    src.format = src.has_meshes ? shot.surface->format : "vdb";
    job.input_manifest = src.has_meshes ? read_input_manifest(src.dir, shot, Stage::Surface, "mc-surface")
                                        : read_input_manifest(src.dir, shot, Stage::Sim, "mc-sim");
    const json& input = job.input_manifest;
    if (src.has_meshes && input.contains("per_frame") && input["per_frame"].is_array())
        for (const json& entry : input["per_frame"])
            if (entry.contains("frame") && entry.contains("crack") && entry["crack"].is_object() &&
                entry["crack"].contains("file") && entry["crack"]["file"].is_null())
                src.frames_without_cracks.insert(entry["frame"].get<int>());
    job.first = shot.sim.time.frame_start;
    job.last = shot.sim.time.frame_end;
    if (input.contains("frames") && input["frames"].is_object()) {
        const json& fr = input["frames"];
        if (fr.contains("first") && fr["first"].is_number_integer()) job.first = fr["first"].get<int>();
        if (fr.contains("last") && fr["last"].is_number_integer()) job.last = fr["last"].get<int>();
    }
    job.turntable_frame = params.turntable_frame < 0 ? job.last : params.turntable_frame;
    if (job.do_turntable && (job.turntable_frame < job.first || job.turntable_frame > job.last))
        throw InputError(opt.shot + ": /render/turntable/frame = " + std::to_string(job.turntable_frame) +
                         ": outside the frames " + std::to_string(job.first) + "-" + std::to_string(job.last) +
                         " of " + (src.dir / "manifest.json").string());

    // every input file exists before any work starts (the camera needs every frame's bounds)
    for (int f = job.first; f <= job.last; ++f)
        for (const fs::path& p : src.files(f))
            if (!fs::is_regular_file(p))
                throw InputError(p.string() + ": missing: run " + (src.has_meshes ? "mc-surface" : "mc-sim") +
                                 " for frame " + std::to_string(f));
    if (!src.has_meshes)
        src.particle_radius = estimate_particle_radius(read_particle_frame(src.particles_path(job.first)), shot.sim.h);
    return job;
}

/// The union of the surface manifest's per-frame "bounds" over frames first-last (mc-surface
/// writes the bounds of the geometry each frame's files hold), or nothing when a frame's entry is
/// missing or has none (a manifest of an older mc-surface): then the caller reads the meshes.
std::optional<Bounds> manifest_bounds(const RenderJob& job) {
    const json& input = job.input_manifest;
    if (!job.src.has_meshes || !input.contains("per_frame") || !input["per_frame"].is_array()) return std::nullopt;
    std::map<int, const json*> by_frame;
    for (const json& entry : input["per_frame"])
        if (entry.is_object() && entry.contains("frame") && entry["frame"].is_number_integer())
            by_frame[entry["frame"].get<int>()] = &entry;
    const auto corner = [](const json& b, const char* key, Vec3f& out) {
        if (!b.contains(key) || !b[key].is_array() || b[key].size() != 3) return false;
        for (int k = 0; k < 3; ++k) {
            if (!b[key][k].is_number()) return false;
            out[k] = b[key][k].get<float>();
        }
        return true;
    };
    const std::string manifest = (job.src.dir / "manifest.json").string();
    Bounds stage;
    for (int f = job.first; f <= job.last; ++f) {
        const auto it = by_frame.find(f);
        if (it == by_frame.end() || !it->second->contains("bounds")) {
            log::info(manifest + ": no bounds for frame " + std::to_string(f) +
                      " (an older mc-surface): reading every frame's meshes for them");
            return std::nullopt;
        }
        const json& b = (*it->second)["bounds"];
        if (b.is_null()) continue;  // a frame with no geometry
        Vec3f lo, hi;
        if (!b.is_object() || !corner(b, "min", lo) || !corner(b, "max", hi)) {
            log::warn("bad bounds", manifest + ": /per_frame bounds of frame " + std::to_string(f) + " = " + b.dump() +
                                        ": not {\"min\": [x, y, z], \"max\": [x, y, z]}; reading every frame's meshes instead");
            return std::nullopt;
        }
        stage.extend(lo);
        stage.extend(hi);
    }
    return stage;
}

/// Bounds over every frame of the shot: the camera, the ground and the shadow stay put, and a
/// chunk of frames rendered alone frames them exactly as a full run does. From the surface
/// manifest when it has them; else (particle renders, older manifests) by reading every frame.
Bounds stage_bounds(const RenderJob& job) {
    if (const std::optional<Bounds> from_manifest = manifest_bounds(job)) {
        if (from_manifest->is_empty())
            throw InputError((job.src.dir / "manifest.json").string() + ": frames " + std::to_string(job.first) + "-" +
                             std::to_string(job.last) + ": no geometry to render (every frame's bounds are null)");
        log::info("bounds of frames " + std::to_string(job.first) + "-" + std::to_string(job.last) + " from " +
                  (job.src.dir / "manifest.json").string());
        return *from_manifest;
    }
    WallTimer scan;
    Bounds stage;
    for (int f = job.first; f <= job.last; ++f) stage.extend(scene_bounds(load_scene(job.src, f)));
    if (stage.is_empty())
        throw InputError(job.src.dir.string() + ": frames " + std::to_string(job.first) + "-" +
                         std::to_string(job.last) + ": no geometry to render (empty meshes or particle caches)");
    log::info("scanned " + std::to_string(job.last - job.first + 1) + " frames for bounds in " +
              std::to_string(scan.seconds()) + " s");
    return stage;
}

std::unique_ptr<Renderer> make_renderer(const StageOptions& opt, const RenderJob& job) {
    // llvmpipe takes its thread count from the environment when the first context is made. One
    // thread is llvmpipe's 0: rasterize in this thread. Its 1 adds a rasterizer thread that only
    // hands work back and forth, and under it a farm test's local render once died in malloc on
    // a chunk of that thread's heap (heap corruption, with AddressSanitizer clean on our side).
    if (opt.threads > 0 && !std::getenv("LP_NUM_THREADS"))
        setenv("LP_NUM_THREADS", std::to_string(opt.threads == 1 ? 0 : opt.threads).c_str(), 1);
    ShadingOptions shading;
    shading.alpha0 = job.shot.sim.nacc ? float(job.shot.sim.nacc->alpha0) : 0.0f;
    return std::make_unique<Renderer>(job.params, shading);
}

/// Renders frames a..b into dir/frame.####.png (each written atomically) and hands every image to
/// `use` before it is written.
FrameStats render_frames(const RenderJob& job, Renderer& renderer, const Bounds& stage, int a, int b,
                         const fs::path& dir, const std::function<void(int, const RenderedImage&)>& use) {
    const Camera camera = resolve_camera(job.params.camera, stage, job.aspect());
    FrameStats stats;
    for (int f = a; f <= b; ++f) {
        const Scene scene = load_scene(job.src, f);
        const size_t tris = triangle_count(scene);
        WallTimer t;
        renderer.set_scene(scene, stage);
        RenderedImage img = renderer.render(camera);
        stats.seconds[f] = t.seconds();
        stats.triangles[f] = tris;
        if (use) use(f, img);
        write_png(dir / frame_file("frame", f), to_png_image(std::move(img)));
        log::debug("frame " + std::to_string(f) + ": " + std::to_string(tris) + " triangles, " +
                   std::to_string(stats.seconds[f]) + " s");
    }
    return stats;
}

/// The review products built from the animation's frames in order: the preview movie (with
/// ffmpeg) and the contact sheet (every sheet_stride-th frame, thumbnail-sized).
class FrameAssembly {
public:
    FrameAssembly(const RenderJob& job, const fs::path& dir, bool has_ffmpeg)
        : m_first(job.first), m_dir(dir),
          m_stride((job.last - job.first + 1 + kMaxSheetThumbnails - 1) / kMaxSheetThumbnails),
          m_thumb_width(std::min(job.params.width, kMaxThumbnailWidth)),
          m_thumb_aspect(double(job.params.width) / job.params.height) {
        if (has_ffmpeg) m_preview.emplace(dir / "preview.mp4", job.params.width, job.params.height, job.params.fps);
    }
    void add(int f, const RenderedImage& img) {
        if (m_preview) m_preview->add_frame(img);
        if ((f - m_first) % m_stride == 0) m_thumbnails.emplace_back(f, downscale(img, m_thumb_width));
    }
    /// Writes contact_sheet.png and finishes preview.mp4; returns the movie names written.
    json finish() {
        json movies = json::array();
        if (m_preview) {
            m_preview->finish();
            movies.push_back("preview.mp4");
        }
        m_columns = contact_sheet_columns(int(m_thumbnails.size()), m_thumb_aspect);
        write_png(m_dir / "contact_sheet.png", to_png_image(contact_sheet(m_thumbnails, m_columns)));
        return movies;
    }
    json sheet_summary() const { return {{"thumbnails", m_thumbnails.size()}, {"columns", m_columns}}; }

private:
    int m_first;
    fs::path m_dir;
    int m_stride, m_thumb_width;
    double m_thumb_aspect;
    int m_columns = 0;
    std::vector<std::pair<int, RenderedImage>> m_thumbnails;
    std::optional<MovieEncoder> m_preview;
};

struct TurntableResult {
    int views = 0;
    double seconds = 0;
    bool has_movie = false;
};

/// The turntable: an orbit around one frame, framed so no view clips. `stage` is called only when
/// that frame has no geometry of its own.
TurntableResult render_turntable(const RenderJob& job, Renderer& renderer, const fs::path& dir, bool has_ffmpeg,
                                 const std::function<Bounds()>& stage) {
    TurntableResult result;
    if (!job.do_turntable) return result;
    result.views = job.params.turntable_views;
    const Scene scene = load_scene(job.src, job.turntable_frame);
    Bounds b = scene_bounds(scene);
    if (b.is_empty()) b = stage();
    const Camera base = resolve_camera(job.params.camera, orbit_bounds(b), job.aspect());
    renderer.set_scene(scene, b);
    std::optional<MovieEncoder> movie;
    if (has_ffmpeg) movie.emplace(dir / "turntable.mp4", job.params.width, job.params.height, job.params.fps);
    for (int v = 0; v < result.views; ++v) {
        WallTimer t;
        RenderedImage img = renderer.render(turntable_camera(base, v, result.views));
        result.seconds += t.seconds();
        if (movie) movie->add_frame(img);
        write_png(dir / frame_file("turntable", v + 1), to_png_image(std::move(img)));
    }
    if (movie) {
        movie->finish();
        result.has_movie = true;
    }
    log::info("rendered a " + std::to_string(result.views) + "-view turntable of frame " +
              std::to_string(job.turntable_frame));
    return result;
}

/// The render manifest. `stats` may lack frames (an assembly whose chunks left no statistics):
/// the per-frame figures are then null.
json render_manifest(const RenderJob& job, const Renderer& renderer, const FrameStats& stats,
                     const TurntableResult& turntable, const json& movies, const json& sheet) {
    const int n_frames = job.last - job.first + 1;
    const bool has_stats = int(stats.seconds.size()) == n_frames;
    size_t max_triangles = 0, total_triangles = 0;
    double render_seconds = 0;
    for (const auto& [f, tris] : stats.triangles) {
        max_triangles = std::max(max_triangles, tris);
        total_triangles += tris;
    }
    for (const auto& [f, s] : stats.seconds) render_seconds += s;
    json m = make_manifest("render", job.shot.path, job.shot.slice_hash(Stage::Render));
    m["inputs"] = {{job.src.has_meshes ? "surface" : "sim",
                    {{"dir", job.src.dir.string()}, {"slice_hash", manifest_slice_hash(job.input_manifest)}}}};
    m["frames"] = {{"first", job.first}, {"last", job.last}, {"count", n_frames}, {"fps", job.params.fps}};
    m["source"] = job.src.has_meshes ? "meshes" : "particles";
    m["resolution"] = {job.params.width, job.params.height};
    m["samples"] = renderer.samples();
    m["color_mode"] = color_mode_name(job.params.color_mode);
    m["gl_renderer"] = renderer.gl_renderer();
    m["triangles"] = has_stats ? json{{"max_per_frame", max_triangles}, {"total", total_triangles}} : json(nullptr);
    if (!job.src.has_meshes) m["particle_radius"] = job.src.particle_radius;
    m["seconds_per_frame"] = has_stats ? json(render_seconds / n_frames) : json(nullptr);
    m["turntable"] = job.do_turntable ? json{{"frame", job.turntable_frame}, {"views", turntable.views},
                                             {"seconds_per_view", turntable.seconds / std::max(turntable.views, 1)}}
                                      : json(nullptr);
    m["views"] = turntable.views;
    m["movies"] = movies;
    m["contact_sheet"] = sheet;
    return m;
}

void print_table(const RenderJob& job, const Renderer* renderer, const char* mode, int a, int b,
                 const TurntableResult& turntable, double seconds_per_frame, const std::string& movies,
                 const fs::path& out) {
    std::printf("%-22s %s\n", "stage", "render");
    std::printf("%-22s %s\n", "mode", mode);
    std::printf("%-22s %d-%d (%d)\n", "frames", a, b, b - a + 1);
    std::printf("%-22s %d\n", "turntable views", turntable.views);
    std::printf("%-22s %dx%d, %d samples\n", "resolution", job.params.width, job.params.height,
                renderer ? renderer->samples() : job.params.samples);
    if (seconds_per_frame >= 0) std::printf("%-22s %.3f\n", "seconds per frame", seconds_per_frame);
    std::printf("%-22s %s\n", "movies", movies.c_str());
    std::printf("%-22s %s\n", "output", out.string().c_str());
}

/// The statistics file a Frames run leaves for the assembly: DIR/render/.chunk.AAAA-BBBB.json.
fs::path chunk_stats_path(const fs::path& dir, int a, int b) {
    char name[64];
    std::snprintf(name, sizeof name, ".chunk.%04d-%04d.json", a, b);
    return dir / name;
}
bool is_chunk_stats(const fs::path& p) {
    const std::string n = p.filename().string();
    return n.rfind(".chunk.", 0) == 0 && p.extension() == ".json";
}

/// "frame.0012.png" -> 12 for the given stem, or nullopt.
std::optional<int> numbered_png(const fs::path& p, const std::string& stem) {
    const std::string n = p.filename().string();
    if (n.size() != stem.size() + 9 || n.rfind(stem + ".", 0) != 0 || p.extension() != ".png") return std::nullopt;
    const std::string digits = n.substr(stem.size() + 1, 4);
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) return std::nullopt;
    return std::stoi(digits);
}

int run_full(const StageOptions& opt, const RenderJob& job) {
    WallTimer total;
    const Bounds stage = stage_bounds(job);
    std::unique_ptr<Renderer> renderer = make_renderer(opt, job);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    if (!has_ffmpeg) log::info("ffmpeg is not on PATH: writing PNGs only (no preview.mp4 / turntable.mp4)");

    StagingDir staging(fs::path(opt.out) / "render", opt.keep_partial);
    const fs::path dir = staging.path();
    FrameAssembly assembly(job, dir, has_ffmpeg);
    const FrameStats stats = render_frames(job, *renderer, stage, job.first, job.last, dir,
                                           [&](int f, const RenderedImage& img) { assembly.add(f, img); });
    json movies = assembly.finish();
    log::info("rendered frames " + std::to_string(job.first) + "-" + std::to_string(job.last));
    const TurntableResult turntable = render_turntable(job, *renderer, dir, has_ffmpeg, [&] { return stage; });
    if (turntable.has_movie) movies.push_back("turntable.mp4");

    json m = render_manifest(job, *renderer, stats, turntable, movies, assembly.sheet_summary());
    m["wall_seconds"] = total.seconds();
    m["peak_rss_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    staging.commit();
    print_table(job, renderer.get(), "full", job.first, job.last, turntable,
                m["seconds_per_frame"].get<double>(), has_ffmpeg ? "preview.mp4 turntable.mp4" : "none (no ffmpeg)",
                fs::path(opt.out) / "render");
    return 0;
}

/// --frames A-B: one chunk of a farm's job array. The frames land in DIR/render/ one by one (each
/// PNG renamed into place when complete); the folder's manifest is removed first because it no
/// longer describes the folder until --assemble writes a new one.
int run_frames(const StageOptions& opt, const RenderJob& job) {
    const int a = opt.frame_range.first, b = opt.frame_range.last;
    if (a < job.first || b > job.last)
        throw InputError("--frames " + opt.frames + ": outside the frames " + std::to_string(job.first) + "-" +
                         std::to_string(job.last) + " of " + (job.src.dir / "manifest.json").string());
    const Bounds stage = stage_bounds(job);
    std::unique_ptr<Renderer> renderer = make_renderer(opt, job);
    const fs::path dir = fs::path(opt.out) / "render";
    // a chunk that fails takes back the folder it made (other chunks' folder it leaves alone)
    std::error_code ec;
    const bool made_dir = !fs::exists(dir, ec);
    fs::create_directories(dir);
    double seconds = 0;
    try {
        fs::remove(dir / "manifest.json");
        const FrameStats stats = render_frames(job, *renderer, stage, a, b, dir, {});
        json chunk = {{"first", a}, {"last", b}, {"frames", json::array()}};
        for (int f = a; f <= b; ++f) {
            chunk["frames"].push_back(
                {{"frame", f}, {"triangles", stats.triangles.at(f)}, {"seconds", stats.seconds.at(f)}});
            seconds += stats.seconds.at(f);
        }
        write_text_atomically(chunk_stats_path(dir, a, b), chunk.dump(2) + "\n");
    } catch (...) {
        if (made_dir) fs::remove_all(dir, ec);
        throw;
    }
    log::info("rendered frames " + std::to_string(a) + "-" + std::to_string(b) + " (run --assemble when all are done)");
    print_table(job, renderer.get(), "frames (chunk)", a, b, {}, seconds / (b - a + 1), "none (--assemble makes them)", dir);
    return 0;
}

/// The per-frame statistics the chunks left in dir (a later file wins for a frame in two).
FrameStats read_chunk_stats(const fs::path& dir, int first, int last) {
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
        if (e.is_regular_file() && is_chunk_stats(e.path())) files.push_back(e.path());
    std::sort(files.begin(), files.end(),
              [](const fs::path& x, const fs::path& y) { return fs::last_write_time(x) < fs::last_write_time(y); });
    FrameStats stats;
    for (const fs::path& p : files) {
        try {
            std::ifstream is(p);
            const json c = json::parse(is);
            for (const json& e : c.at("frames")) {
                const int f = e.at("frame").get<int>();
                if (f < first || f > last) continue;
                stats.triangles[f] = e.at("triangles").get<size_t>();
                stats.seconds[f] = e.at("seconds").get<double>();
            }
        } catch (const json::exception& e) {
            // statistics only: the manifest then reports them as null, the images are unaffected
            log::warn("chunk-stats", p.string() + ": unreadable frame statistics (" + e.what() + "): ignored");
        }
    }
    return stats;
}

/// --assemble: from the frame PNGs in DIR/render/, the turntable, contact sheet, movies and the
/// manifest (last), each file written atomically, byte-identical to what a full run writes. Files a
/// full run would not leave (frames outside the shot, extra turntable views, chunk statistics,
/// movies not made) are removed.
int run_assemble(const StageOptions& opt, const RenderJob& job) {
    WallTimer total;
    const fs::path dir = fs::path(opt.out) / "render";
    const fs::path input_manifest = job.src.dir / "manifest.json";
    const auto input_time = fs::last_write_time(input_manifest);
    for (int f = job.first; f <= job.last; ++f) {
        const fs::path p = dir / frame_file("frame", f);
        if (!fs::is_regular_file(p))
            throw InputError(p.string() + ": missing: render it first (mc-render --frames " + std::to_string(f) + "-" +
                             std::to_string(f) + ")");
        if (fs::last_write_time(p) < input_time)
            throw InputError(p.string() + ": older than " + input_manifest.string() +
                             ": stale, re-render it (mc-render --frames " + std::to_string(f) + "-" +
                             std::to_string(f) + ")");
    }
    fs::remove(dir / "manifest.json");
    std::unique_ptr<Renderer> renderer = make_renderer(opt, job);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    if (!has_ffmpeg) log::info("ffmpeg is not on PATH: writing PNGs only (no preview.mp4 / turntable.mp4)");

    FrameAssembly assembly(job, dir, has_ffmpeg);
    for (int f = job.first; f <= job.last; ++f) {
        const fs::path p = dir / frame_file("frame", f);
        Image png = read_png(p);
        if (png.width != job.params.width || png.height != job.params.height || png.channels != 4)
            throw InputError(p.string() + ": " + std::to_string(png.width) + "x" + std::to_string(png.height) + ", " +
                             std::to_string(png.channels) + " channels: expected " + std::to_string(job.params.width) +
                             "x" + std::to_string(job.params.height) + " RGBA: re-render it");
        RenderedImage img;
        img.width = png.width;
        img.height = png.height;
        img.rgba = std::move(png.pixels);
        assembly.add(f, img);
    }
    json movies = assembly.finish();
    std::optional<Bounds> stage;
    const TurntableResult turntable = render_turntable(job, *renderer, dir, has_ffmpeg, [&] {
        if (!stage) stage = stage_bounds(job);
        return *stage;
    });
    if (turntable.has_movie) movies.push_back("turntable.mp4");

    // what a full run would not have written
    for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
        const fs::path& p = e.path();
        const auto frame = numbered_png(p, "frame"), view = numbered_png(p, "turntable");
        if ((frame && (*frame < job.first || *frame > job.last)) || (view && (*view < 1 || *view > turntable.views)))
            fs::remove(p);
    }
    if (!turntable.has_movie) fs::remove(dir / "turntable.mp4");
    if (!has_ffmpeg) fs::remove(dir / "preview.mp4");

    const FrameStats stats = read_chunk_stats(dir, job.first, job.last);
    if (int(stats.seconds.size()) != job.last - job.first + 1)
        log::info("frame statistics cover " + std::to_string(stats.seconds.size()) + " of " +
                  std::to_string(job.last - job.first + 1) + " frames: seconds_per_frame and triangles are null");
    json m = render_manifest(job, *renderer, stats, turntable, movies, assembly.sheet_summary());
    m["assembled"] = true;
    m["wall_seconds"] = total.seconds();
    m["peak_rss_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
        if (is_chunk_stats(e.path())) fs::remove(e.path());
    print_table(job, renderer.get(), "assemble", job.first, job.last, turntable,
                m["seconds_per_frame"].is_number() ? m["seconds_per_frame"].get<double>() : -1.0,
                has_ffmpeg ? "preview.mp4 turntable.mp4" : "none (no ffmpeg)", dir);
    return 0;
}

int run(const StageOptions& opt, bool force_turntable, bool assemble) {
    const Mode mode = assemble ? Mode::Assemble : opt.frame_range.is_set() ? Mode::Frames : Mode::Full;
    if (assemble && opt.frame_range.is_set())
        throw InputError("--assemble with --frames " + opt.frames +
                         ": --assemble takes every frame of the shot; render chunks with --frames, then assemble");
    if (mode == Mode::Frames && force_turntable)
        throw InputError("--turntable with --frames " + opt.frames +
                         ": a --frames run writes frame PNGs only; the turntable is rendered by --assemble");
    const RenderJob job = resolve_job(opt, force_turntable);
    switch (mode) {
        case Mode::Frames: return run_frames(opt, job);
        case Mode::Assemble: return run_assemble(opt, job);
        case Mode::Full: break;
    }
    return run_full(opt, job);
}

}  // namespace
}  // namespace mudcrack

int main(int argc, char** argv) {
    bool force_turntable = false, assemble = false;
    return mudcrack::run_stage(
        "mc-render",
        "Headless preview renders (OSMesa): DIR/render/frame.####.png, turntable.####.png, "
        "contact_sheet.png, preview.mp4 and turntable.mp4 (with ffmpeg); --frames A-B renders only those "
        "frame PNGs (a farm chunk), --assemble makes the rest from them",
        argc, argv,
        [&](CLI::App& app) {
            app.add_flag("--turntable", force_turntable,
                         "also render the turntable when the shot has no /render/turntable section");
            app.add_flag("--assemble", assemble,
                         "from the frame PNGs already in DIR/render/ (rendered by --frames chunks), render the "
                         "turntable and write contact_sheet.png, the movies and manifest.json");
        },
        [&](const mudcrack::StageOptions& opt) { return mudcrack::run(opt, force_turntable, assemble); });
}
