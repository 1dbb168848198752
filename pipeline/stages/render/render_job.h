#pragma once
/// What an mc-render run renders, resolved from the shot and the input stage's manifest before
/// any work starts: the frames, where they come from, and the bounds that frame every one of them.
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/manifest.h"
#include "pipeline/shot/shot.h"
#include "pipeline/stages/stage_options.h"
#include "render/render_params.h"
#include "render/scene.h"

namespace mudcrack {

/// Where the frames come from: surfaced meshes or the particle cache.
struct FrameSource {
    bool has_meshes = false;
    bool has_cracks = false;
    std::filesystem::path dir;  // DIR/surface or DIR/sim
    std::string format;         // mesh extension ("glb", ...) or "vdb"
    float particle_radius = 0;  // [m], particles only
    // mc-surface writes no crack file for a frame with no crack
    std::set<int> frames_without_cracks;
    // of every file, from the input manifest: each is verified as it is read
    RecordedChecksums checksums;

    bool has_cracks_at(int f) const { return has_cracks && !frames_without_cracks.count(f); }
    std::filesystem::path boundary_path(int f) const;
    std::filesystem::path crack_path(int f) const;
    std::filesystem::path particles_path(int f) const;
    /// Every file frame f needs.
    std::vector<std::filesystem::path> files(int f) const;
};

/// The surface manifest's /per_frame entries, read once: the frames whose crack file is null (no
/// crack) and each frame's "bounds" value (null: a frame with no geometry). A frame missing from
/// `bounds` has no entry, or an entry without bounds (a manifest of an older mc-surface).
struct SurfaceFrameIndex {
    std::set<int> frames_without_cracks;
    std::map<int, nlohmann::json> bounds;
};

/// Indexes a surface manifest's /per_frame (entries that are not objects with an integer
/// "frame" are skipped; a later entry of a frame wins).
SurfaceFrameIndex index_surface_frames(const nlohmann::json& surface_manifest);

/// The union of the per-frame bounds of frames first..last, or nothing when a frame has no bounds
/// or malformed ones (logged, naming `manifest_name`): the caller then reads the meshes. Null
/// bounds (no geometry) add nothing, so frames with none give empty bounds.
std::optional<Bounds> manifest_bounds(const SurfaceFrameIndex& index, int first, int last,
                                      const std::string& manifest_name);

/// The shot's render settings and inputs, resolved and checked.
struct RenderJob {
    Shot shot;
    RenderParams params;
    FrameSource src;
    nlohmann::json input_manifest;
    SurfaceFrameIndex surface_frames;  // meshes only
    int first = 0, last = 0;           // every frame of the shot (those of the input stage)
    bool do_turntable = false;
    int turntable_frame = 0;
    float aspect() const { return float(params.width) / float(params.height); }
    std::filesystem::path input_manifest_path() const { return src.dir / "manifest.json"; }
};

/// Loads the shot, reads and checks the input stage's manifest (DIR/surface, or DIR/sim for a
/// shot without surfacing), and checks every input file of every frame exists.
/// @throws InputError naming the file, key and value of what is missing, stale or out of range
RenderJob resolve_render_job(const StageOptions& opt, bool force_turntable);

/// The scene of frame f, meshes tagged boundary/crack by the file they came from, each file
/// verified against its recorded checksum (InputError naming a damaged one).
Scene load_scene(const FrameSource& src, int f);

/// Bounds over every frame of the shot: the camera, the ground and the shadow stay put, and a
/// chunk of frames rendered alone frames them exactly as a full run does. From the surface
/// manifest when it has them; else (particle renders, older manifests) by reading every frame.
/// @throws InputError when no frame has geometry
Bounds stage_bounds(const RenderJob& job);

}  // namespace mudcrack
