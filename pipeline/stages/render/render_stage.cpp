#include "pipeline/stages/render/render_stage.h"

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
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/image_io.h"
#include "pipeline/io/manifest.h"
#include "pipeline/stages/render/render_job.h"
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

constexpr int kMaxSheetThumbnails = 48;  // the contact sheet samples long animations evenly
constexpr int kMaxThumbnailWidth = 320;  // [px]

/// What one mc-render run does. A full run is a Frames run over every frame followed by an
/// Assemble run, done in one process; the farm runs them as separate jobs.
enum class Mode {
    Full,  // every frame, the turntable, the contact sheet, the movies, manifest.json
    // --frames A-B: frame.A..B PNGs only, each renamed into DIR/render/ when complete, and their
    // statistics and checksums in DIR/render/.chunk.AAAA-BBBB.json
    Frames,
    Assemble,  // --assemble: the turntable, contact sheet, movies and manifest from the frame PNGs
};

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

/// Per frame: triangles drawn and seconds spent in the renderer.
struct FrameStats {
    std::map<int, size_t> triangles;
    std::map<int, double> seconds;
};

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
FrameStats render_frames(const RenderJob& job, Renderer& renderer, const Bounds& stage, int a,
                         int b, const fs::path& dir,
                         const std::function<void(int, const RenderedImage&)>& use) {
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
        : m_first(job.first),
          m_dir(dir),
          m_stride((job.last - job.first + 1 + kMaxSheetThumbnails - 1) / kMaxSheetThumbnails),
          m_thumb_width(std::min(job.params.width, kMaxThumbnailWidth)),
          m_thumb_aspect(double(job.params.width) / job.params.height) {
        if (has_ffmpeg)
            m_preview.emplace(dir / "preview.mp4", job.params.width, job.params.height,
                              job.params.fps);
    }
    void add(int f, const RenderedImage& img) {
        if (m_preview) m_preview->add_frame(img);
        if ((f - m_first) % m_stride == 0)
            m_thumbnails.emplace_back(f, downscale(img, m_thumb_width));
    }
    /// Writes contact_sheet.png and finishes preview.mp4; returns the movie names written.
    json finish() {
        json movies = json::array();
        if (m_preview) {
            m_preview->finish();
            movies.push_back("preview.mp4");
        }
        m_columns = contact_sheet_columns(int(m_thumbnails.size()), m_thumb_aspect);
        write_png(m_dir / "contact_sheet.png",
                  to_png_image(contact_sheet(m_thumbnails, m_columns)));
        return movies;
    }
    json sheet_summary() const {
        return {{"thumbnails", m_thumbnails.size()}, {"columns", m_columns}};
    }

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
TurntableResult render_turntable(const RenderJob& job, Renderer& renderer, const fs::path& dir,
                                 bool has_ffmpeg, const std::function<Bounds()>& stage) {
    TurntableResult result;
    if (!job.do_turntable) return result;
    result.views = job.params.turntable_views;
    const Scene scene = load_scene(job.src, job.turntable_frame);
    Bounds b = scene_bounds(scene);
    if (b.is_empty()) b = stage();
    const Camera base = resolve_camera(job.params.camera, b, job.aspect(), /*orbit=*/true);
    renderer.set_scene(scene, b);
    std::optional<MovieEncoder> movie;
    if (has_ffmpeg)
        movie.emplace(dir / "turntable.mp4", job.params.width, job.params.height, job.params.fps);
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
    m["inputs"] = {
        {job.src.has_meshes ? "surface" : "sim",
         {{"dir", job.src.dir.string()}, {"slice_hash", manifest_slice_hash(job.input_manifest)}}}};
    m["frames"] = {
        {"first", job.first}, {"last", job.last}, {"count", n_frames}, {"fps", job.params.fps}};
    m["source"] = job.src.has_meshes ? "meshes" : "particles";
    m["resolution"] = {job.params.width, job.params.height};
    m["samples"] = renderer.samples();
    m["color_mode"] = color_mode_name(job.params.color_mode);
    m["gl_renderer"] = renderer.gl_renderer();
    m["triangles"] = has_stats ? json{{"max_per_frame", max_triangles}, {"total", total_triangles}}
                               : json(nullptr);
    if (!job.src.has_meshes) m["particle_radius"] = job.src.particle_radius;
    m["seconds_per_frame"] = has_stats ? json(render_seconds / n_frames) : json(nullptr);
    m["turntable"] =
        job.do_turntable
            ? json{{"frame", job.turntable_frame},
                   {"views", turntable.views},
                   {"seconds_per_view", turntable.seconds / std::max(turntable.views, 1)}}
            : json(nullptr);
    m["views"] = turntable.views;
    m["movies"] = movies;
    m["contact_sheet"] = sheet;
    return m;
}

void print_table(const RenderJob& job, const Renderer* renderer, const char* mode, int a, int b,
                 const TurntableResult& turntable, double seconds_per_frame,
                 const std::string& movies, const fs::path& out) {
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
    if (n.size() != stem.size() + 9 || n.rfind(stem + ".", 0) != 0 || p.extension() != ".png")
        return std::nullopt;
    const std::string digits = n.substr(stem.size() + 1, 4);
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
    return std::stoi(digits);
}

/// The records (file_record) of the images and movies a finished render folder holds, in one
/// order for a full run and an assembly: frames, turntable views, the contact sheet, the movies.
json image_records(const RenderJob& job, const fs::path& dir, int views, const json& movies) {
    json records = json::array();
    for (int f = job.first; f <= job.last; ++f)
        records.push_back(file_record(dir / frame_file("frame", f)));
    for (int v = 1; v <= views; ++v)
        records.push_back(file_record(dir / frame_file("turntable", v)));
    records.push_back(file_record(dir / "contact_sheet.png"));
    for (const json& movie : movies) records.push_back(file_record(dir / movie.get<std::string>()));
    return records;
}

int run_full(const StageOptions& opt, const RenderJob& job) {
    WallTimer total;
    const Bounds stage = stage_bounds(job);
    std::unique_ptr<Renderer> renderer = make_renderer(opt, job);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    if (!has_ffmpeg)
        log::info("ffmpeg is not on PATH: writing PNGs only (no preview.mp4 / turntable.mp4)");

    StagingDir staging(fs::path(opt.out) / "render", opt.keep_partial);
    const fs::path dir = staging.path();
    FrameAssembly assembly(job, dir, has_ffmpeg);
    const FrameStats stats =
        render_frames(job, *renderer, stage, job.first, job.last, dir,
                      [&](int f, const RenderedImage& img) { assembly.add(f, img); });
    json movies = assembly.finish();
    log::info("rendered frames " + std::to_string(job.first) + "-" + std::to_string(job.last));
    const TurntableResult turntable =
        render_turntable(job, *renderer, dir, has_ffmpeg, [&] { return stage; });
    if (turntable.has_movie) movies.push_back("turntable.mp4");

    json m = render_manifest(job, *renderer, stats, turntable, movies, assembly.sheet_summary());
    m["images"] = image_records(job, dir, turntable.views, movies);
    m["wall_seconds"] = total.seconds();
    m["peak_memory_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    staging.commit();
    print_table(job, renderer.get(), "full", job.first, job.last, turntable,
                m["seconds_per_frame"].get<double>(),
                has_ffmpeg ? "preview.mp4 turntable.mp4" : "none (no ffmpeg)",
                fs::path(opt.out) / "render");
    return 0;
}

/// --frames A-B: one chunk of a farm's job array. The frames land in DIR/render/ one by one (each
/// PNG renamed into place when complete); the folder's manifest is removed first because it no
/// longer describes the folder until --assemble writes a new one.
int run_frames(const StageOptions& opt, const RenderJob& job) {
    const FrameRange frames =
        frames_to_process(opt, {job.first, job.last}, job.input_manifest_path().string());
    const int a = frames.first, b = frames.last;
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
        // the statistics file grows frame by frame: a chunk stopped midway leaves the checksums of
        // the frames it finished, which the assembly verifies them against
        json chunk = {{"first", a}, {"last", b}, {"frames", json::array()}};
        for (int f = a; f <= b; ++f) {
            const FrameStats stats = render_frames(job, *renderer, stage, f, f, dir, {});
            json record = file_record(dir / frame_file("frame", f));
            record.update({{"frame", f},
                           {"triangles", stats.triangles.at(f)},
                           {"seconds", stats.seconds.at(f)}});
            chunk["frames"].push_back(record);
            write_text_atomically(chunk_stats_path(dir, a, b), chunk.dump(2) + "\n");
            seconds += stats.seconds.at(f);
        }
    } catch (...) {
        if (made_dir) fs::remove_all(dir, ec);
        throw;
    }
    log::info("rendered frames " + std::to_string(a) + "-" + std::to_string(b) +
              " (run --assemble when all are done)");
    print_table(job, renderer.get(), "frames (chunk)", a, b, {}, seconds / (b - a + 1),
                "none (--assemble makes them)", dir);
    return 0;
}

/// The per-frame statistics the chunks left in dir (a later file wins for a frame in two), and the
/// checksums of the frames they rendered (added to `images`).
FrameStats read_chunk_stats(const fs::path& dir, int first, int last, RecordedChecksums& images) {
    std::vector<fs::path> files;
    for (const fs::directory_entry& e : fs::directory_iterator(dir))
        if (e.is_regular_file() && is_chunk_stats(e.path())) files.push_back(e.path());
    std::sort(files.begin(), files.end(), [](const fs::path& x, const fs::path& y) {
        return fs::last_write_time(x) < fs::last_write_time(y);
    });
    FrameStats stats;
    for (const fs::path& p : files) {
        try {
            std::ifstream is(p);
            const json c = json::parse(is);
            images.add(c, p);
            for (const json& e : c.at("frames")) {
                const int f = e.at("frame").get<int>();
                if (f < first || f > last) continue;
                stats.triangles[f] = e.at("triangles").get<size_t>();
                stats.seconds[f] = e.at("seconds").get<double>();
            }
        } catch (const json::exception& e) {
            // statistics only: the manifest then reports them as null, the images are unaffected
            log::warn("chunk-stats",
                      p.string() + ": unreadable frame statistics (" + e.what() + "): ignored");
        }
    }
    return stats;
}

/// --assemble: from the frame PNGs in DIR/render/, the turntable, contact sheet, movies and the
/// manifest (last), each file written atomically, byte-identical to what a full run writes. Files a
/// full run would not leave (frames outside the shot, extra turntable views, movies not made) are
/// removed; the chunk statistics stay, hidden: they hold the checksums a later assembly (after
/// some chunks are rendered again) verifies the frames it did not re-render against.
int run_assemble(const StageOptions& opt, const RenderJob& job) {
    WallTimer total;
    const fs::path dir = fs::path(opt.out) / "render";
    const fs::path input_manifest = job.input_manifest_path();
    const auto input_time = fs::last_write_time(input_manifest);
    for (int f = job.first; f <= job.last; ++f) {
        const fs::path p = dir / frame_file("frame", f);
        if (!fs::is_regular_file(p))
            throw InputError(p.string() + ": missing: render it first (mc-render --frames " +
                             std::to_string(f) + "-" + std::to_string(f) + ")");
        if (fs::last_write_time(p) < input_time)
            throw InputError(p.string() + ": older than " + input_manifest.string() +
                             ": stale, re-render it (mc-render --frames " + std::to_string(f) +
                             "-" + std::to_string(f) + ")");
    }
    // every frame is verified against the checksum its chunk recorded before anything is written
    RecordedChecksums frame_images;
    const FrameStats stats = read_chunk_stats(dir, job.first, job.last, frame_images);
    for (int f = job.first; f <= job.last; ++f) frame_images.verify(dir / frame_file("frame", f));
    fs::remove(dir / "manifest.json");
    std::unique_ptr<Renderer> renderer = make_renderer(opt, job);
    const bool has_ffmpeg = !find_on_path("ffmpeg").empty();
    if (!has_ffmpeg)
        log::info("ffmpeg is not on PATH: writing PNGs only (no preview.mp4 / turntable.mp4)");

    FrameAssembly assembly(job, dir, has_ffmpeg);
    for (int f = job.first; f <= job.last; ++f) {
        const fs::path p = dir / frame_file("frame", f);
        Image png = read_png(p);
        if (png.width != job.params.width || png.height != job.params.height || png.channels != 4)
            throw InputError(p.string() + ": " + std::to_string(png.width) + "x" +
                             std::to_string(png.height) + ", " + std::to_string(png.channels) +
                             " channels: expected " + std::to_string(job.params.width) + "x" +
                             std::to_string(job.params.height) + " RGBA: re-render it");
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
        if ((frame && (*frame < job.first || *frame > job.last)) ||
            (view && (*view < 1 || *view > turntable.views)))
            fs::remove(p);
    }
    if (!turntable.has_movie) fs::remove(dir / "turntable.mp4");
    if (!has_ffmpeg) fs::remove(dir / "preview.mp4");

    if (int(stats.seconds.size()) != job.last - job.first + 1)
        log::info("frame statistics cover " + std::to_string(stats.seconds.size()) + " of " +
                  std::to_string(job.last - job.first + 1) +
                  " frames: seconds_per_frame and triangles are null");
    json m = render_manifest(job, *renderer, stats, turntable, movies, assembly.sheet_summary());
    m["images"] = image_records(job, dir, turntable.views, movies);
    m["assembled"] = true;
    m["wall_seconds"] = total.seconds();
    m["peak_memory_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    print_table(job, renderer.get(), "assemble", job.first, job.last, turntable,
                m["seconds_per_frame"].is_number() ? m["seconds_per_frame"].get<double>() : -1.0,
                has_ffmpeg ? "preview.mp4 turntable.mp4" : "none (no ffmpeg)", dir);
    return 0;
}

}  // namespace

int run_render_stage(const StageOptions& opt, const RenderStageOptions& render_options) {
    const bool force_turntable = render_options.force_turntable, assemble = render_options.assemble;
    const Mode mode = assemble                   ? Mode::Assemble
                      : opt.frame_range.is_set() ? Mode::Frames
                                                 : Mode::Full;
    if (assemble && opt.frame_range.is_set())
        throw UsageError(
            "--assemble with --frames " + opt.frames +
            ": --assemble takes every frame of the shot; render chunks with --frames, then assemble");
    if (mode == Mode::Frames && force_turntable)
        throw UsageError(
            "--turntable with --frames " + opt.frames +
            ": a --frames run writes frame PNGs only; the turntable is rendered by --assemble");
    const RenderJob job = resolve_render_job(opt, force_turntable);
    switch (mode) {
        case Mode::Frames: return run_frames(opt, job);
        case Mode::Assemble: return run_assemble(opt, job);
        case Mode::Full: break;
    }
    return run_full(opt, job);
}

}  // namespace mudcrack
