#include "pipeline/stages/render/render_job.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/stats.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

constexpr float kParticleRadiusFactor = 0.55f;  // sprite radius / estimated particle spacing

ParticleFrame read_particle_frame(const FrameSource& src, int f) {
    const fs::path path = src.particles_path(f);
    src.checksums.verify(path);
    return points_to_frame(read_points(path), path.string());
}

std::vector<TriMesh> import_verified_meshes(const FrameSource& src, const fs::path& file) {
    src.checksums.verify(file);
    return import_meshes(file);
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

}  // namespace

fs::path FrameSource::boundary_path(int f) const { return frame_path(dir, "boundary", f, format); }
fs::path FrameSource::crack_path(int f) const { return frame_path(dir, "crack", f, format); }
fs::path FrameSource::particles_path(int f) const { return frame_path(dir, "particles", f, "vdb"); }

std::vector<fs::path> FrameSource::files(int f) const {
    if (!has_meshes) return {particles_path(f)};
    std::vector<fs::path> out = {boundary_path(f)};
    if (has_cracks_at(f)) out.push_back(crack_path(f));
    return out;
}

SurfaceFrameIndex index_surface_frames(const json& surface_manifest) {
    SurfaceFrameIndex index;
    const auto per_frame = surface_manifest.find("per_frame");
    if (per_frame == surface_manifest.end() || !per_frame->is_array()) return index;
    for (const json& entry : *per_frame) {
        if (!entry.is_object() || !entry.contains("frame") || !entry["frame"].is_number_integer())
            continue;
        const int f = entry["frame"].get<int>();
        const auto crack = entry.find("crack");
        if (crack != entry.end() && crack->is_object() && crack->contains("file") &&
            (*crack)["file"].is_null())
            index.frames_without_cracks.insert(f);
        if (entry.contains("bounds"))
            index.bounds[f] = entry["bounds"];
        else
            index.bounds.erase(f);
    }
    return index;
}

std::optional<Bounds> manifest_bounds(const SurfaceFrameIndex& index, int first, int last,
                                      const std::string& manifest_name) {
    const auto corner = [](const json& b, const char* key, Vec3f& out) {
        if (!b.contains(key) || !b[key].is_array() || b[key].size() != 3) return false;
        for (int k = 0; k < 3; ++k) {
            if (!b[key][k].is_number()) return false;
            out[k] = b[key][k].get<float>();
        }
        return true;
    };
    Bounds stage;
    for (int f = first; f <= last; ++f) {
        const auto it = index.bounds.find(f);
        if (it == index.bounds.end()) {
            log::info(manifest_name + ": no bounds for frame " + std::to_string(f) +
                      " (an older mc-surface): reading every frame's meshes for them");
            return std::nullopt;
        }
        const json& b = it->second;
        if (b.is_null()) continue;  // a frame with no geometry
        Vec3f lo, hi;
        if (!b.is_object() || !corner(b, "min", lo) || !corner(b, "max", hi)) {
            log::warn(
                "bad bounds",
                manifest_name + ": /per_frame bounds of frame " + std::to_string(f) + " = " +
                    b.dump() +
                    ": not {\"min\": [x, y, z], \"max\": [x, y, z]}; reading every frame's meshes instead");
            return std::nullopt;
        }
        stage.extend(lo);
        stage.extend(hi);
    }
    return stage;
}

RenderJob resolve_render_job(const StageOptions& opt, bool force_turntable) {
    RenderJob job;
    job.shot = load_shot(opt.shot);
    const Shot& shot = job.shot;
    if (!shot.render)
        throw InputError(opt.shot +
                         ": /render: missing: the shot has no render section (add \"render\": {})");
    job.params = *shot.render;
    const RenderParams& params = job.params;
    job.do_turntable = params.turntable || force_turntable;

    // inputs: the surfacing's meshes, or the particle cache when the shot has no surfacing
    FrameSource& src = job.src;
    src.has_meshes = shot.surface.has_value();
    src.has_cracks = src.has_meshes && shot.surface->cracks;
    src.dir = fs::path(opt.out) / (src.has_meshes ? "surface" : "sim");
    src.format = src.has_meshes ? shot.surface->format : "vdb";
    job.input_manifest = read_current_manifest(
        src.dir, shot.slice_hash(src.has_meshes ? Stage::Surface : Stage::Sim));
    const json& input = job.input_manifest;
    src.checksums = RecordedChecksums(input, job.input_manifest_path());
    if (src.has_meshes) {
        job.surface_frames = index_surface_frames(input);
        src.frames_without_cracks = job.surface_frames.frames_without_cracks;
    }
    const ManifestFrames frames = manifest_frames(input, job.input_manifest_path());
    job.first = frames.first;
    job.last = frames.last;
    job.turntable_frame = params.turntable_frame < 0 ? job.last : params.turntable_frame;
    if (job.do_turntable && (job.turntable_frame < job.first || job.turntable_frame > job.last))
        throw InputError(opt.shot +
                         ": /render/turntable/frame = " + std::to_string(job.turntable_frame) +
                         ": outside the frames " + std::to_string(job.first) + "-" +
                         std::to_string(job.last) + " of " + job.input_manifest_path().string());

    // every input file exists before any work starts (the camera needs every frame's bounds)
    for (int f = job.first; f <= job.last; ++f)
        for (const fs::path& p : src.files(f))
            if (!fs::is_regular_file(p))
                throw InputError(p.string() + ": missing: run " +
                                 (src.has_meshes ? "mc-surface" : "mc-sim") + " for frame " +
                                 std::to_string(f));
    if (!src.has_meshes)
        src.particle_radius =
            estimate_particle_radius(read_particle_frame(src, job.first), shot.sim.h);
    return job;
}

Scene load_scene(const FrameSource& src, int f) {
    Scene scene;
    if (src.has_meshes) {
        for (TriMesh& m : import_verified_meshes(src, src.boundary_path(f)))
            scene.meshes.push_back({std::move(m), SurfaceKind::Boundary});
        if (src.has_cracks_at(f))
            for (TriMesh& m : import_verified_meshes(src, src.crack_path(f)))
                scene.meshes.push_back({std::move(m), SurfaceKind::Crack});
        return scene;
    }
    ParticleFrame pf = read_particle_frame(src, f);
    scene.particles.positions = std::move(pf.P);
    scene.particles.saturation = std::move(pf.saturation);
    scene.particles.alpha = std::move(pf.alpha);
    scene.particles.radius = src.particle_radius;
    return scene;
}

Bounds stage_bounds(const RenderJob& job) {
    const std::string manifest = job.input_manifest_path().string();
    const std::optional<Bounds> from_manifest =
        job.src.has_meshes ? manifest_bounds(job.surface_frames, job.first, job.last, manifest)
                           : std::nullopt;
    if (from_manifest) {
        if (from_manifest->is_empty())
            throw InputError(manifest + ": frames " + std::to_string(job.first) + "-" +
                             std::to_string(job.last) +
                             ": no geometry to render (every frame's bounds are null)");
        log::info("bounds of frames " + std::to_string(job.first) + "-" + std::to_string(job.last) +
                  " from " + manifest);
        return *from_manifest;
    }
    WallTimer scan;
    Bounds stage;
    for (int f = job.first; f <= job.last; ++f) stage.extend(scene_bounds(load_scene(job.src, f)));
    if (stage.is_empty())
        throw InputError(job.src.dir.string() + ": frames " + std::to_string(job.first) + "-" +
                         std::to_string(job.last) +
                         ": no geometry to render (empty meshes or particle caches)");
    log::info("scanned " + std::to_string(job.last - job.first + 1) + " frames for bounds in " +
              std::to_string(scan.seconds()) + " s");
    return stage;
}

}  // namespace mudcrack
