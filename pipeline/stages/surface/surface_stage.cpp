#include "pipeline/stages/surface/surface_stage.h"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/break_history_io.h"
#include "pipeline/io/checksum.h"
#include "pipeline/io/debris_io.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "pipeline/io/tet_mesh_io.h"
#include "pipeline/shot/shot.h"
#include "sim/core/bounds.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"
#include "surfacing/core_surface.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/pieces.h"
#include "surfacing/shot_fracture.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

/// Hash of everything the break history depends on: the sim run (its manifest), Eq. 14's
/// parameters, and the mesh.
uint64_t break_source_hash(const json& sim_manifest, const SurfaceParams& params,
                           const CoreTopology& topo) {
    std::ostringstream os;
    os << sim_manifest.dump() << "|" << surface_mode_name(params.mode) << "|";
    os.precision(17);
    os << params.zeta << "|" << params.length_consistent << "|" << topo.n_edges() << "|"
       << topo.n_tets();
    const std::string s = os.str();
    return fnv1a64_of(s);
}

/// Loads one sim cache, verified against the checksum the sim manifest records, and checks that it
/// is the expected frame of this mesh.
ParticleFrame load_frame(const fs::path& sim_dir, const RecordedChecksums& sim_files,
                         int frame_number, const CoreTopology& topo) {
    const fs::path path = frame_path(sim_dir, "particles", frame_number, "vdb");
    sim_files.verify(path);
    // missing, truncated, foreign or other-version files throw
    const PointCloud cloud = read_points(path);
    ParticleFrame frame = points_to_frame(cloud, path.string());
    const auto it = cloud.meta_int.find("mudcrack:frame");
    if (it != cloud.meta_int.end() && it->second != frame_number)
        throw InputError(path.string() + ": mudcrack:frame = " + std::to_string(it->second) +
                         ": expected " + std::to_string(frame_number));
    frame.frame = frame_number;
    try {
        check_frame_fits(topo, frame);
    } catch (const InputError& e) {
        throw InputError(path.string() + ": " + e.what() + " in DIR/init/tets.vtu");
    }
    return frame;
}

/// Whether the break history of an existing surface folder is the file its manifest recorded: a
/// damaged one is not reused but scanned again.
bool is_intact_break_history(const fs::path& surface_dir, const json& manifest) {
    try {
        RecordedChecksums(manifest, surface_dir / "manifest.json")
            .verify(surface_dir / kBreakHistoryFile);
        return true;
    } catch (const InputError& e) {
        log::warn("break history", std::string(e.what()) + ": scanning the frames again");
        return false;
    }
}

/// Runs fn(i) for i in [0, n), over items in parallel when there are enough of them (each item
/// then runs single-threaded inside), else one by one with the threads inside each item.
/// Rethrows the exception of the lowest failing index, so errors are deterministic.
template <class Fn>
void for_each_item(int n, Fn&& fn) {
    std::vector<std::exception_ptr> error(n);
    auto guarded = [&](int64_t i) {
        try {
            fn(static_cast<int>(i));
        } catch (...) {
            error[i] = std::current_exception();
        }
    };
    if (n >= thread_count() && thread_count() > 1)
        parallel_for(n, guarded);
    else
        for (int i = 0; i < n; ++i) guarded(i);
    for (const auto& e : error)
        if (e) std::rethrow_exception(e);
}

/// Gives `to` every file of `from` (same file system): hard links, so nothing is copied and the
/// files keep their times (make trusts them); a copy with the time kept where links fail.
/// Writers replace files by rename, so a link never carries a change back to `from`.
void link_folder_contents(const fs::path& from, const fs::path& to) {
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(from)) {
        const fs::path target = to / fs::relative(e.path(), from);
        if (e.is_directory()) {
            fs::create_directories(target);
            continue;
        }
        std::error_code ec;
        fs::create_hard_link(e.path(), target, ec);
        if (ec) {
            fs::copy_file(e.path(), target);
            fs::last_write_time(target, fs::last_write_time(e.path()));
        }
    }
}

/// The break history of frames first..last: Eq. 14 on every cached frame (order-free: a minimum).
BreakHistory scan_breaks(const fs::path& sim_dir, const RecordedChecksums& sim_files, int first,
                         int last, const CoreTopology& topo, const SurfaceParams& params,
                         uint64_t source_hash) {
    BreakHistory h;
    h.source_hash = source_hash;
    h.first_frame = first;
    h.last_frame = last;
    h.first_break = no_edge_breaks(topo);
    std::mutex merge;
    for_each_item(last - first + 1, [&](int i) {
        const ParticleFrame frame = load_frame(sim_dir, sim_files, first + i, topo);
        std::vector<int32_t> mine = no_edge_breaks(topo);
        record_edge_breaks(topo, frame, params, mine);
        const std::lock_guard<std::mutex> lock(merge);
        merge_edge_breaks(h.first_break, mine);
    });
    return h;
}

/// The bounds of the vertices the frame's faces use, over every mesh, as the manifest's
/// {"min": [x, y, z], "max": [x, y, z]} (null when no mesh has a face). A reader of the files
/// gets the same floats (every format we write keeps float32 positions exactly, and readers that
/// rebuild vertices from face corners drop unused ones), so mc-render frames a shot from the
/// manifest alone, exactly as from the files, instead of reading every frame's meshes.
json bounds_json(const std::vector<const TriMesh*>& meshes) {
    Bounds b;
    for (const TriMesh* m : meshes) b.extend(used_vertex_bounds(*m));
    if (b.is_empty()) return nullptr;
    return {{"min", {b.min.x(), b.min.y(), b.min.z()}}, {"max", {b.max.x(), b.max.y(), b.max.z()}}};
}

/// The mesh as a one-mesh export list, leaving `mesh` empty (its memory goes with the list).
std::vector<TriMesh> take_mesh(TriMesh& mesh) {
    std::vector<TriMesh> list;
    list.push_back(std::move(mesh));
    mesh = TriMesh();
    return list;
}

/// A plate must fit in the soil: a min_piece_size wider than the whole rest soil leaves no plate.
void check_piece_size(const Shot& shot, const SurfaceParams& params, const CoreTopology& topo) {
    Vec3 sum = Vec3::Zero();
    Mat3 sum_outer = Mat3::Zero();
    for (const Vec3& x : topo.X) {
        sum += x;
        sum_outer += x * x.transpose();
    }
    const Real soil = piece_width(sum, sum_outer, topo.n_particles, mean_particle_spacing(topo));
    const Real asked = params.min_piece_size * params.cell_size;
    if (asked > soil)
        throw InputError(shot.path + ": /surfacing/min_piece_size = " +
                         std::to_string(params.min_piece_size) + ": " + std::to_string(asked) +
                         " m (in cells of /sim/h) is wider than the soil itself (" +
                         std::to_string(soil) + " m across): no piece could be a plate");
}

struct FrameResult {
    json entry;
    double surfacing_seconds = 0;  // surface_frame only (no file I/O)
    int64_t triangles = 0;
};

// the shot's surfacing settings with the --mode and --format flags applied
SurfaceParams flagged_params(const Shot& shot, const SurfaceStageOptions& surface_options) {
    const std::string& mode_flag = surface_options.mode;
    const std::string& format_flag = surface_options.format;
    if (!shot.surface)
        throw InputError(
            shot.path +
            ": /surfacing: missing: this shot has no surfacing stage (add a \"surfacing\" section)");
    SurfaceParams params = *shot.surface;
    if (!mode_flag.empty()) {
        const std::optional<SurfaceMode> mode = parse_surface_mode(mode_flag);
        if (!mode) throw UsageError("--mode " + mode_flag + ": not a surfacing mode");
        params.mode = *mode;
        if (debris_needs_plates(params))
            throw UsageError("--mode " + mode_flag + ": " + shot.path +
                             " asks for /surfacing/debris, which only the plates mode writes");
    }
    // the shot's own format passed the spec's check; only the flag's can be refused here
    if (!format_flag.empty()) params.format = format_flag;
    if (!is_supported_mesh_format(params.format))
        throw UsageError("--format " + params.format + ": " + mesh_format_refusal(params.format));
    return params;
}

// the stage's inputs: init's and sim's folders and manifests, the cached and the requested frames
struct SurfaceInputs {
    fs::path init_dir, sim_dir;
    json init_manifest, sim_manifest;
    RecordedChecksums sim_files;
    int sim_first = 0, sim_last = -1;  // the cached frames
    int first = 0, last = -1;          // the frames this run surfaces
};

SurfaceInputs read_surface_inputs(const Shot& shot, const StageOptions& options) {
    SurfaceInputs in;
    in.init_dir = fs::path(options.out) / "init";
    in.sim_dir = fs::path(options.out) / "sim";
    const fs::path sim_dir = in.sim_dir;
    in.init_manifest = read_current_manifest(in.init_dir, shot.slice_hash(Stage::Init));
    in.sim_manifest = read_current_manifest(sim_dir, shot.slice_hash(Stage::Sim));
    in.sim_files = RecordedChecksums(in.sim_manifest, sim_dir / "manifest.json");
    const ManifestFrames sim_frames = manifest_frames(in.sim_manifest, sim_dir / "manifest.json");
    in.sim_first = sim_frames.first;
    in.sim_last = sim_frames.last;
    const FrameRange frames = frames_to_process(options, {sim_frames.first, sim_frames.last},
                                                (sim_dir / "manifest.json").string());
    in.first = frames.first;
    in.last = frames.last;
    return in;
}

// preprocessing, once per tet mesh: the tet mesh lives only while its topology is built (the
// frames need only the topology)
CoreTopology load_topology(const Shot& shot, const SurfaceParams& params, const SurfaceInputs& in) {
    WallTimer timer;
    const fs::path tets_file = in.init_dir / "tets.vtu";
    RecordedChecksums(in.init_manifest, in.init_dir / "manifest.json").verify(tets_file);
    const CoreTopology topo = [&] {
        const TetMesh mesh = read_tet_mesh_vtu(tets_file);
        try {
            return build_core_topology(mesh);
        } catch (const InputError& e) {
            throw InputError(tets_file.string() + ": " + e.what());
        }
    }();
    if (params.mode == SurfaceMode::Plates) check_piece_size(shot, params, topo);
    log::info("particle cores: " + std::to_string(topo.n_particles) + " particles, " +
              std::to_string(topo.n_tets()) + " tets, " + std::to_string(topo.n_edges()) +
              " edges, " + std::to_string(topo.skin_faces.size()) + " boundary faces (" +
              std::to_string(timer.seconds()) + " s)");
    return topo;
}

// the manifest of an existing surface folder of the same shot, mode and format, which --frames
// updates in place; nullopt when there is none (or no --frames)
std::optional<json> in_place_manifest(const Shot& shot, const StageOptions& options,
                                      const SurfaceParams& params, const fs::path& surface_dir) {
    if (!options.frame_range.is_set() || !fs::exists(surface_dir / "manifest.json"))
        return std::nullopt;
    json previous;
    try {
        previous = read_manifest(surface_dir);
    } catch (const InputError&) {
        return std::nullopt;
    }
    if (manifest_slice_hash(previous) == shot.slice_hash(Stage::Surface) &&
        previous.value("mode", "") == surface_mode_name(params.mode) &&
        previous.value("format", "") == params.format)
        return previous;
    return std::nullopt;
}

// the edge-break history, and in the plates mode the shot's fracture
struct Breaks {
    BreakHistory history;
    std::optional<ShotFracture> fracture;
    bool reused = false;  // the history of the folder updated in place
    double seconds = 0;
};

// the break history: reused when it matches the inputs and covers the frames, else scanned and
// written into `dir`; the plates mode's fracture, decided once from the shot's last frame
// (surfacing/shot_fracture.h)
Breaks plan_breaks(const SurfaceInputs& in, const SurfaceParams& params, const CoreTopology& topo,
                   const fs::path& surface_dir, const std::optional<json>& previous,
                   const fs::path& dir) {
    WallTimer timer;
    const uint64_t source_hash = break_source_hash(in.sim_manifest, params, topo);
    std::optional<BreakHistory> history;
    if (previous && is_intact_break_history(surface_dir, *previous))
        history = read_break_history(surface_dir / kBreakHistoryFile, source_hash, topo.n_edges());
    Breaks breaks;
    breaks.reused =
        history && history->first_frame <= in.sim_first && history->last_frame >= in.last;
    if (!breaks.reused) {
        log::info("break history: scanning frames " + std::to_string(in.sim_first) + "-" +
                  std::to_string(in.sim_last));
        history = scan_breaks(in.sim_dir, in.sim_files, in.sim_first, in.sim_last, topo, params,
                              source_hash);
        write_break_history(dir / kBreakHistoryFile, *history);
    }
    breaks.history = std::move(*history);
    if (params.mode == SurfaceMode::Plates) {
        breaks.fracture =
            plan_shot_fracture(topo, load_frame(in.sim_dir, in.sim_files, in.sim_last, topo),
                               breaks.history.first_break, params);
        // where each cut edge's particles stood the frame before it
        if (params.open_speed > 0)
            record_cut_edges_for(
                topo, *breaks.fracture, in.sim_first, in.first, in.last, easing_frames(params),
                [&](int n) { return load_frame(in.sim_dir, in.sim_files, n, topo); });
        log::info("plates: the fracture of frame " + std::to_string(in.sim_last) + ": " +
                  std::to_string(breaks.fracture->last.count) + " pieces, " +
                  std::to_string(breaks.fracture->last.debris) + " debris particles, " +
                  std::to_string(breaks.fracture->walls.size()) + " wall points");
    }
    breaks.seconds = timer.seconds();
    return breaks;
}

// an obj mesh's material file (<stem>.mtl, which its readers load with it) recorded in the
// mesh's record, so it is verified as the mesh is
void record_material(json& record, const fs::path& mesh_file) {
    const fs::path material = mesh_material_file(mesh_file);
    std::error_code ec;
    if (!material.empty() && fs::is_regular_file(material, ec))
        record["material"] = file_record(material);
}

// frame n's meshes (and debris) written into `dir`, each atomically, and its manifest entry
FrameResult surface_one_frame(const SurfaceInputs& in, const SurfaceParams& params,
                              const CoreTopology& topo, const Breaks& breaks, const fs::path& dir,
                              int n) {
    FrameResult result;
    const ParticleFrame frame = load_frame(in.sim_dir, in.sim_files, n, topo);
    WallTimer t;
    SurfacedFrame s = surface_frame(topo, frame, breaks.history.first_break, params,
                                    breaks.fracture ? &*breaks.fracture : nullptr);
    result.surfacing_seconds = t.seconds();
    result.triangles = int64_t(s.boundary.faces.size() + s.crack.faces.size());
    const fs::path boundary_file = frame_path(dir, "boundary", n, params.format);
    json entry = {{"frame", n},
                  {"boundary",
                   {{"file", boundary_file.filename().string()},
                    {"vertices", s.boundary.positions.size()},
                    {"faces", s.boundary.faces.size()}}},
                  {"broken_edges", s.broken_edges},
                  {"fragments", s.fragments},
                  {"culled_fragments", s.culled_fragments},
                  {"surfacing_seconds", result.surfacing_seconds}};
    entry["bounds"] =
        params.cracks ? bounds_json({&s.boundary, &s.crack}) : bounds_json({&s.boundary});
    if (params.mode == SurfaceMode::Plates) {
        entry["pieces"] = s.fragments;
        entry["debris_particles"] = s.debris_particles;
        entry["wall_points_smoothed"] = s.wall_points_smoothed;
    }
    if (params.debris == DebrisOutput::Points) {
        const fs::path debris_file = frame_path(dir, "debris", n, "ply");
        write_debris_ply(debris_file, s.debris);
        entry["debris"] = file_record(debris_file);
        entry["debris"]["points"] = s.debris.size();
    }
    // each mesh moves into its export and is freed after it: a frame's peak memory holds one
    // copy of its meshes
    export_meshes(boundary_file, take_mesh(s.boundary), params.format);
    entry["boundary"]["crc32"] = file_crc32(boundary_file);
    record_material(entry["boundary"], boundary_file);
    if (params.cracks) {
        // a frame without cracks gets no crack file: a glTF mesh cannot be empty, and assimp
        // writes an empty mesh that no reader (assimp included) accepts; the manifest records
        // "file": null
        const fs::path crack_file = frame_path(dir, "crack", n, params.format);
        std::error_code ec;
        fs::remove(crack_file, ec);  // a stale file of an earlier run
        entry["crack"] = {
            {"file", s.crack.faces.empty() ? json(nullptr) : json(crack_file.filename().string())},
            {"vertices", s.crack.positions.size()},
            {"faces", s.crack.faces.size()}};
        if (!s.crack.faces.empty()) {
            export_meshes(crack_file, take_mesh(s.crack), params.format);
            entry["crack"]["crc32"] = file_crc32(crack_file);
            record_material(entry["crack"], crack_file);
        }
    }
    result.entry = std::move(entry);
    return result;
}

// the manifest: this run's frames merged with those already there when updating in place
json surface_manifest(const Shot& shot, const SurfaceInputs& in, const SurfaceParams& params,
                      const CoreTopology& topo, const Breaks& breaks,
                      const std::optional<json>& previous, const std::vector<FrameResult>& results,
                      const fs::path& dir, double preprocessing_seconds) {
    std::map<int, json> frames;
    if (previous && previous->contains("per_frame"))
        for (const json& e : (*previous)["per_frame"]) frames[e.value("frame", 0)] = e;
    double surfacing_seconds = 0;
    int64_t triangles = 0;
    for (const FrameResult& r : results) {
        frames[r.entry["frame"].get<int>()] = r.entry;
        surfacing_seconds += r.surfacing_seconds;
        triangles += r.triangles;
    }
    json per_frame = json::array();
    for (auto& [n, e] : frames) per_frame.push_back(e);
    json m = make_manifest("surface", shot.path, shot.slice_hash(Stage::Surface));
    m["inputs"] = {
        {"init",
         {{"dir", in.init_dir.string()}, {"slice_hash", manifest_slice_hash(in.init_manifest)}}},
        {"sim",
         {{"dir", in.sim_dir.string()}, {"slice_hash", manifest_slice_hash(in.sim_manifest)}}}};
    m["mode"] = surface_mode_name(params.mode);
    m["format"] = params.format;
    m["zeta"] = params.zeta;
    m["length_consistent"] = params.length_consistent;
    m["cracks"] = params.cracks;
    m["min_fragment_particles"] = params.min_fragment_particles;
    if (params.mode == SurfaceMode::Plates)
        m["plates"] = {{"min_piece_size", params.min_piece_size},
                       {"cell_size", params.cell_size},
                       {"debris_gap", params.debris_gap},
                       {"close_gaps", params.close_gaps},
                       {"open_speed", params.open_speed},
                       {"wall_smoothing", params.wall_smoothing},
                       {"debris", params.debris == DebrisOutput::Points ? "points" : "none"}};
    // fps: the shot's (/frames/fps), so a DCC importer sets its scene's rate from this manifest
    // alone
    m["frames"] = {{"first", frames.begin()->first},
                   {"last", frames.rbegin()->first},
                   {"count", frames.size()},
                   {"fps", shot.sim.time.fps},
                   {"this_run", {{"first", in.first}, {"last", in.last}}}};
    m["particles"] = topo.n_particles;
    m["tets"] = topo.n_tets();
    m["edges"] = topo.n_edges();
    m["boundary_faces"] = topo.skin_faces.size();
    m["preprocessing_seconds"] = preprocessing_seconds;
    m["topology_bytes"] = topo.memory_bytes();
    m["topology_bytes_per_tet"] = double(topo.memory_bytes()) / topo.n_tets();
    m["break_history"] = {{"file", kBreakHistoryFile},
                          {"crc32", file_crc32(dir / kBreakHistoryFile)},
                          {"reused", breaks.reused},
                          {"frames_scanned", breaks.reused ? 0 : in.sim_last - in.sim_first + 1},
                          {"seconds", breaks.seconds}};
    const int n_frames = in.last - in.first + 1;
    m["surfacing_seconds"] = surfacing_seconds;
    m["tets_per_second"] =
        surfacing_seconds > 0 ? double(topo.n_tets()) * n_frames / surfacing_seconds : 0.0;
    m["triangles_per_second"] = surfacing_seconds > 0 ? double(triangles) / surfacing_seconds : 0.0;
    m["threads"] = thread_count();
    m["per_frame"] = per_frame;
    return m;
}

// the results table on stdout
void print_surface_results(const std::vector<FrameResult>& results, const json& manifest,
                           double wall_seconds) {
    std::printf("frame  boundary_faces  crack_faces  broken_edges  fragments\n");
    for (const FrameResult& r : results)
        std::printf(
            "%5d  %14lld  %11lld  %12lld  %9d\n", r.entry["frame"].get<int>(),
            (long long)r.entry["boundary"]["faces"].get<int64_t>(),
            (long long)(r.entry.contains("crack") ? r.entry["crack"]["faces"].get<int64_t>() : 0),
            (long long)r.entry["broken_edges"].get<int64_t>(), r.entry["fragments"].get<int>());
    std::printf(
        "surfaced %d frames: %.3g tets/s, %.3g triangles/s per frame compute; wall %.2f s\n",
        int(results.size()), manifest["tets_per_second"].get<double>(),
        manifest["triangles_per_second"].get<double>(), wall_seconds);
}

}  // namespace

int run_surface_stage(const StageOptions& options, const SurfaceStageOptions& surface_options) {
    WallTimer wall;
    const Shot shot = load_shot(options.shot);
    const SurfaceParams params = flagged_params(shot, surface_options);
    const SurfaceInputs in = read_surface_inputs(shot, options);
    const fs::path surface_dir = fs::path(options.out) / "surface";

    // preprocessing, once per tet mesh
    WallTimer timer;
    const CoreTopology topo = load_topology(shot, params, in);
    const double preprocessing_seconds = timer.seconds();

    // an update in place is staged like a full run, its folder starting as hard links to the
    // current files: a failed run leaves the previous outputs exactly as they were
    const std::optional<json> previous = in_place_manifest(shot, options, params, surface_dir);
    StagingDir staging(surface_dir, options.keep_partial);
    if (previous) link_folder_contents(surface_dir, staging.path());
    const fs::path dir = staging.path();
    const Breaks breaks = plan_breaks(in, params, topo, surface_dir, previous, dir);

    // frames, in parallel; each writes its own files atomically
    std::vector<FrameResult> results(in.last - in.first + 1);
    for_each_item(int(results.size()), [&](int i) {
        results[i] = surface_one_frame(in, params, topo, breaks, dir, in.first + i);
    });

    // the manifest, last
    json m = surface_manifest(shot, in, params, topo, breaks, previous, results, dir,
                              preprocessing_seconds);
    m["wall_seconds"] = wall.seconds();
    m["peak_memory_bytes"] = peak_rss_bytes();
    write_manifest(dir, m);
    staging.commit();
    print_surface_results(results, m, wall.seconds());
    return 0;
}

}  // namespace mudcrack
