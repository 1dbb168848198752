#include "pipeline/stages/measure/measure_stage.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/break_history_io.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "pipeline/io/tet_mesh_io.h"
#include "pipeline/measure/mesh_measures.h"
#include "pipeline/measure/shape_measures.h"
#include "pipeline/shot/shot.h"
#include "sim/core/error.h"
#include "surfacing/core_surface.h"
#include "surfacing/core_topology.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/fragments.h"
#include "surfacing/shot_fracture.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

constexpr const char* kProgram = "mc-measure";
/// Gaps whose lower particle lies within this many cells of the ground count as lift-off: the
/// ground's nodes hold the particles whose quadratic stencil reaches them, 1.5 cells deep.
constexpr Real kGroundBandCells = 1.5;

/// The edges parted at frame n: per edge, the first frame it parts (kNeverBroken: never), so
/// parted at or before n. From the break history, or from the plates mode's fracture.
std::vector<uint8_t> parted_at(const std::vector<int32_t>& first_frame, int n) {
    std::vector<uint8_t> is_parted(first_frame.size());
    for (size_t e = 0; e < is_parted.size(); ++e) is_parted[e] = first_frame[e] <= n ? 1 : 0;
    return is_parted;
}

/// The typical polygon's side, the square root of its area weighted by area, over the cracked
/// layer's thickness: the ratio that desiccation experiments find about constant as a layer
/// gets thicker (Groisman and Kaplan 1994). 0 where either is unknown.
double polygon_size_over_thickness(const SurfacePolygons& polygons, const CrackDepth& depth) {
    if (!(polygons.weighted_mean_area > 0 && depth.thickness_median > 0)) return 0;
    return std::sqrt(polygons.weighted_mean_area) / depth.thickness_median;
}

/// A frame's fragment, surface polygon, crack network and crack depth figures, as the table's JSON
/// fields.
json crack_fields(const FragmentSizes& sizes, const SurfacePolygons& polygons,
                  const CrackNetwork& network, const CrackDepth& depth) {
    return {{"fragments", sizes.count},
            {"largest_fragment_fraction", sizes.largest_fraction},
            {"weighted_mean_fragment_volume", sizes.weighted_mean_volume},
            {"surface_polygons", polygons.count},
            {"weighted_mean_polygon_area", polygons.weighted_mean_area},
            {"largest_polygon_fraction", polygons.largest_fraction},
            {"effective_surface_polygons", polygons.effective_count},
            {"crack_points", network.crack_points},
            {"oriented_crack_points", network.oriented_points},
            {"oriented_crack_length", network.oriented_length},
            {"axis_aligned_fraction", network.axis_aligned_fraction},
            {"oriented_cracks", network.oriented_cracks},
            {"axis_aligned_fraction_stderr", network.axis_aligned_fraction_stderr},
            {"crack_square_order", network.square_order},
            {"crack_square_phase_deg", network.square_phase_deg},
            {"junctions", network.junctions},
            {"t_junction_fraction", network.t_fraction},
            {"y_junction_fraction", network.y_fraction},
            {"crack_direction_histogram", network.direction_histogram},
            {"junction_angle_histogram", network.junction_angle_histogram},
            {"junction_right_angle_fraction", network.junction_right_angle_fraction},
            {"cracked_top_fraction", depth.cracked_fraction},
            {"crack_depth_median", depth.depth_median},
            {"crack_depth_p90", depth.depth_p90},
            {"crack_depth_max", depth.depth_max},
            {"cracked_column_thickness_median", depth.thickness_median},
            {"crack_through_fraction", depth.through_fraction},
            {"polygon_size_over_thickness", polygon_size_over_thickness(polygons, depth)}};
}

/// The pace fields of the document: when the first crack appears and when half of the last
/// measured frame's broken edges exist, in frames and as a share of the shot's range.
json pace_fields(const CrackPace& pace) {
    return {{"first_crack_frame", pace.first_crack_frame},
            {"half_broken_frame", pace.half_broken_frame},
            {"half_broken_range_fraction", pace.half_broken_range_fraction}};
}

/// The first mesh of a frame's surfacing file named by the surface manifest's entry `which`
/// ("boundary" or "crack"), verified against its recorded checksum, or an empty mesh when the
/// frame has none.
TriMesh read_frame_mesh(const fs::path& surface_dir, const RecordedChecksums& surface_files,
                        const json& entry, const char* which) {
    if (!entry.contains(which) || entry[which].value("file", json()).is_null()) return TriMesh();
    const fs::path file = surface_dir / entry[which]["file"].get<std::string>();
    surface_files.verify(file);
    std::vector<TriMesh> meshes = import_meshes(file);
    return meshes.empty() ? TriMesh() : std::move(meshes.front());
}

/// What a close-up sees in frame n's mesh files (mesh_measures.h), when the surface folder has
/// them.
std::optional<MeshPieces> measure_frame_meshes(const fs::path& surface_dir,
                                               const json& surface_manifest,
                                               const RecordedChecksums& surface_files, int n,
                                               Real cell) {
    for (const json& entry : surface_manifest.value("per_frame", json::array()))
        if (entry.value("frame", 0) == n)
            return measure_mesh_pieces(
                read_frame_mesh(surface_dir, surface_files, entry, "boundary"),
                read_frame_mesh(surface_dir, surface_files, entry, "crack"), cell);
    return std::nullopt;
}

json mesh_fields(const MeshPieces& m) {
    return {{"mesh_pieces", m.pieces},
            {"mesh_chips", m.chips},
            {"mesh_chip_triangle_fraction", m.chip_triangle_fraction},
            {"mesh_open_pieces", m.open_pieces},
            {"mesh_open_edges", m.open_edges},
            {"mesh_hole_edges", m.hole_edges},
            {"crack_wall_roughness_deg", m.crack_roughness_deg},
            {"crack_wall_area", m.crack_area},
            {"top_crack_length", m.top_crack_length},
            {"crack_area_per_metre", m.crack_area_per_metre}};
}

/// The plates mode's top polygons and crack directions, measured on the edges its meshes cut
/// (the shot's fracture) where the fields without the prefix read the broken ones.
json cut_fields(const SurfacePolygons& polygons, const CrackNetwork& network,
                const UnopenedWalls& unopened) {
    return {{"mesh_surface_polygons", polygons.count},
            {"mesh_effective_surface_polygons", polygons.effective_count},
            {"mesh_largest_polygon_fraction", polygons.largest_fraction},
            {"mesh_weighted_mean_polygon_area", polygons.weighted_mean_area},
            {"mesh_oriented_crack_points", network.oriented_points},
            {"mesh_oriented_crack_length", network.oriented_length},
            {"mesh_axis_aligned_fraction", network.axis_aligned_fraction},
            {"mesh_oriented_cracks", network.oriented_cracks},
            {"mesh_axis_aligned_fraction_stderr", network.axis_aligned_fraction_stderr},
            {"mesh_crack_square_order", network.square_order},
            {"mesh_crack_square_phase_deg", network.square_phase_deg},
            {"mesh_crack_direction_histogram", network.direction_histogram},
            {"mesh_top_wall_edges", unopened.wall_edges},
            {"mesh_unopened_wall_fraction", unopened.unopened_fraction},
            {"mesh_unopened_wall_strain_median", unopened.unopened_strain_median}};
}

json motion_fields(const SurfaceMotion& m) {
    return {{"vertices_compared", m.vertices_compared},
            {"vertex_jump_max_cells", m.jump_max_cells},
            {"vertex_jump_p99_cells", m.jump_p99_cells},
            {"piece_changes", m.piece_changes}};
}

/// The surfacing of consecutive frames, kept one frame back, for the motion measures (--motion).
class MotionTracker {
public:
    /// @param fracture the plates mode's fracture of the shot (as mc-surface planned it)
    MotionTracker(const CoreTopology& topo, const BreakHistory& history,
                  const SurfaceParams& params, Real cell, std::optional<ShotFracture> fracture)
        : m_topo(topo),
          m_history(history),
          m_params(params),
          m_cell(cell),
          m_fracture(std::move(fracture)) {}
    /// Surfaces `frame`; the motion from the frame before, when there was one.
    std::optional<SurfaceMotion> step(ParticleFrame frame) {
        SurfacedFrame now = surface_frame(m_topo, frame, m_history.first_break, m_params,
                                          m_fracture ? &*m_fracture : nullptr);
        std::optional<SurfaceMotion> motion;
        if (m_previous)
            motion =
                measure_surface_motion(m_topo, *m_previous, m_previous_frame, now, frame, m_cell);
        m_previous = std::move(now);
        m_previous_frame = std::move(frame);
        return motion;
    }

private:
    const CoreTopology& m_topo;
    const BreakHistory& m_history;
    SurfaceParams m_params;
    Real m_cell;
    std::optional<ShotFracture> m_fracture;
    std::optional<SurfacedFrame> m_previous;
    ParticleFrame m_previous_frame;
};

// what the mesh table prints of one frame
struct MeshRow {
    std::optional<MeshPieces> meshes;
    std::optional<SurfacePolygons> cut_polygons;
    std::optional<CrackNetwork> cut_network;
    std::optional<SurfaceMotion> motion;
};

void print_mesh_row(int n, const MeshRow& row) {
    std::printf("%6d", n);
    if (const auto& mesh = row.meshes)
        std::printf(" %7d %6d %6lld %6lld %10.2f %11.4f", mesh->pieces, mesh->chips,
                    static_cast<long long>(mesh->open_edges),
                    static_cast<long long>(mesh->hole_edges), mesh->crack_roughness_deg,
                    mesh->crack_area_per_metre);
    else
        std::printf(" %7s %6s %6s %6s %10s %11s", "-", "-", "-", "-", "-", "-");
    if (row.cut_polygons && row.cut_network)
        std::printf(" %9d %7.2f %8.1f %8.1f %6.1f", row.cut_polygons->count,
                    row.cut_polygons->effective_count, 100 * row.cut_polygons->largest_fraction,
                    100 * row.cut_network->axis_aligned_fraction,
                    100 * row.cut_network->axis_aligned_fraction_stderr);
    else
        std::printf(" %9s %7s %8s %8s %6s", "-", "-", "-", "-", "-");
    if (const auto& motion = row.motion)
        std::printf(" %9.3f %9.3f %9lld\n", motion->jump_max_cells, motion->jump_p99_cells,
                    static_cast<long long>(motion->piece_changes));
    else
        std::printf(" %9s %9s %9s\n", "-", "-", "-");
}

// the rest state every frame is measured against: the tet mesh, its columns and the ground band
struct RestSetup {
    TetMesh mesh;
    std::vector<Real> rest_volume;
    Real spacing = 0;
    RestColumns columns;
    GroundBand ground;
    std::vector<int32_t> surface_particles;  // the boundary particles (the ones a render shows)
    Real alpha0 = 0;
};

RestSetup read_rest_setup(const Shot& shot, const fs::path& init_dir, const json& init_manifest) {
    RestSetup r;
    RecordedChecksums(init_manifest, init_dir / "manifest.json").verify(init_dir / "tets.vtu");
    r.mesh = read_tet_mesh_vtu(init_dir / "tets.vtu");
    r.rest_volume = particle_rest_volumes(r.mesh);
    r.spacing = particle_spacing(r.rest_volume);
    r.columns = build_rest_columns(r.mesh.X, r.spacing);
    // gaps within 1.5 cells of the ground are lift-off: the grid holds that band (GroundBand)
    r.ground.cell = shot.sim.h;
    if (shot.sim.ground) {
        r.ground.ground_y = shot.sim.ground->height;
        r.ground.band = kGroundBandCells * shot.sim.h;
    }
    // the boundary particles, for the hardening colormap's halves
    for (const auto& tri : r.mesh.boundary)
        for (int k = 0; k < 3; ++k) r.surface_particles.push_back(static_cast<int32_t>(tri[k]));
    std::sort(r.surface_particles.begin(), r.surface_particles.end());
    r.surface_particles.erase(std::unique(r.surface_particles.begin(), r.surface_particles.end()),
                              r.surface_particles.end());
    r.alpha0 = shot.sim.nacc ? shot.sim.nacc->alpha0 : Real(0);
    return r;
}

// the surfacing's outputs, when it ran: its break history is the one source of "broken"
struct SurfaceOutputs {
    std::optional<CoreTopology> topo;
    std::optional<BreakHistory> history;
    int min_particles = 1;
    json manifest;
    RecordedChecksums files;
    // per edge, the frame the plates mode's fracture cuts it (none in the other modes): all the
    // mesh_ measures need of it, so --motion's tracker can take the fracture itself
    std::optional<std::vector<int32_t>> cut_frame;
};

void read_surface_outputs(const Shot& shot, const fs::path& surface_dir, const TetMesh& mesh,
                          int last, SurfaceOutputs& s) {
    if (!fs::exists(surface_dir / "manifest.json")) return;
    s.manifest = read_current_manifest(surface_dir, shot.slice_hash(Stage::Surface));
    s.files = RecordedChecksums(s.manifest, surface_dir / "manifest.json");
    s.min_particles = s.manifest.value("min_fragment_particles", 1);
    s.files.verify(surface_dir / kBreakHistoryFile);
    s.topo = build_core_topology(mesh);
    s.history =
        read_break_history(surface_dir / kBreakHistoryFile, std::nullopt, s.topo->n_edges());
    if (!s.history)
        throw InputError((surface_dir / kBreakHistoryFile).string() +
                         ": missing or damaged (or from another mesh): re-run mc-surface");
    if (s.history->last_frame < last)
        throw InputError((surface_dir / kBreakHistoryFile).string() + ": covers frames up to " +
                         std::to_string(s.history->last_frame) + ", not " + std::to_string(last) +
                         ": re-run mc-surface");
}

// A sim frame, verified against the sim manifest's checksum.
ParticleFrame load_sim_frame(const fs::path& sim_dir, const RecordedChecksums& sim_files, int n) {
    const fs::path path = frame_path(sim_dir, "particles", n, "vdb");
    sim_files.verify(path);
    return points_to_frame(read_points(path), path.string());
}

// The plates mode's fracture of the shot, planned as mc-surface plans it: from the break history's
// last frame. The mesh_ measures of the top read its cuts, the edges the meshes part
// (docs/measures.md), and --motion surfaces each frame with it. None in the other modes.
std::optional<ShotFracture> plan_surfacing_fracture(const Shot& shot, const fs::path& sim_dir,
                                                    const RecordedChecksums& sim_files,
                                                    const SurfaceOutputs& surfacing) {
    if (!surfacing.topo || !shot.surface || shot.surface->mode != SurfaceMode::Plates)
        return std::nullopt;
    return plan_shot_fracture(*surfacing.topo,
                              load_sim_frame(sim_dir, sim_files, surfacing.history->last_frame),
                              surfacing.history->first_break, *shot.surface);
}

// --motion: the tracker that surfaces each frame again, with the shot's fracture in the plates mode
std::optional<MotionTracker> make_motion_tracker(const Shot& shot, const SurfaceOutputs& surfacing,
                                                 const fs::path& sim_dir,
                                                 const fs::path& surface_dir,
                                                 const RecordedChecksums& sim_files,
                                                 std::optional<ShotFracture> fracture) {
    if (!surfacing.topo || !shot.surface)
        throw InputError("--motion: " + shot.path + " has no surfacing output in " +
                         surface_dir.string() + ": run mc-surface first");
    // where each cut edge's particles stood the frame before it, as mc-surface records it
    if (fracture && shot.surface->open_speed > 0)
        record_cut_edges_for(*surfacing.topo, *fracture, surfacing.history->first_frame,
                             surfacing.history->first_frame, surfacing.history->last_frame,
                             easing_frames(*shot.surface),
                             [&](int n) { return load_sim_frame(sim_dir, sim_files, n); });
    return std::make_optional<MotionTracker>(*surfacing.topo, *surfacing.history, *shot.surface,
                                             shot.sim.h, std::move(fracture));
}

// one frame's measures: its JSON row and what the table prints
struct FrameMeasures {
    json row;
    double time = 0;
    LayerShape shape;
    std::optional<HardeningHalves> halves;
    int64_t broken = -1;  // -1: no surfacing output
    FragmentSizes sizes;
    SurfacePolygons polygons;
    CrackNetwork network;
    std::optional<MeshPieces> meshes;
    std::optional<SurfacePolygons> cut_polygons;  // the plates mode's, on the edges it cuts
    std::optional<CrackNetwork> cut_network;
    std::optional<SurfaceMotion> motion;
};

FrameMeasures measure_frame(const Shot& shot, const RestSetup& rest,
                            const SurfaceOutputs& surfacing, const fs::path& init_dir,
                            const fs::path& sim_dir, const fs::path& surface_dir,
                            const RecordedChecksums& sim_files,
                            std::optional<MotionTracker>& motion_tracker, int n) {
    const fs::path path = frame_path(sim_dir, "particles", n, "vdb");
    sim_files.verify(path);
    const PointCloud cloud = read_points(path);
    const ParticleFrame frame = points_to_frame(cloud, path.string());
    if (frame.size() != rest.mesh.X.size())
        throw InputError(path.string() + ": " + std::to_string(frame.size()) + " particles, but " +
                         (init_dir / "tets.vtu").string() + " has " +
                         std::to_string(rest.mesh.X.size()));
    std::vector<Vec3> x(frame.size());
    for (size_t p = 0; p < x.size(); ++p) x[p] = frame.P[p].cast<Real>();
    FrameMeasures f;
    f.shape = measure_layer_shape(rest.columns, rest.mesh.X, x, rest.spacing, rest.ground);
    f.time = cloud.meta_double.count("mudcrack:time") ? cloud.meta_double.at("mudcrack:time") : 0.0;
    f.row = {{"frame", n},
             {"time", f.time},
             {"top_rise_median", f.shape.top_rise_median},
             {"top_rise_p95", f.shape.top_rise_p95},
             {"curl", f.shape.curl},
             {"split_fraction", f.shape.split_fraction},
             {"split_height_median_cells", f.shape.split_height_median},
             {"split_height_p10_cells", f.shape.split_height_p10},
             {"lifted_fraction", f.shape.lifted_fraction}};
    if (!frame.alpha.empty()) {
        f.halves = measure_hardening_halves(rest.surface_particles, frame.alpha, rest.alpha0);
        f.row["surface_stretched_fraction"] = f.halves->stretched_fraction;
        f.row["surface_compressed_fraction"] = f.halves->compressed_fraction;
    }
    if (!surfacing.topo) return f;
    const CoreTopology& topo = *surfacing.topo;
    f.broken = count_broken_edges(surfacing.history->first_break, n);
    const std::vector<uint8_t> is_broken = parted_at(surfacing.history->first_break, n);
    f.sizes = measure_fragment_sizes(find_fragments(topo, is_broken, surfacing.min_particles),
                                     rest.rest_volume);
    f.polygons = measure_surface_polygons(topo, is_broken, rest.columns, surfacing.min_particles);
    f.network = measure_crack_network(topo, is_broken, rest.columns, surfacing.min_particles);
    const PolygonSides sides =
        measure_polygon_sides(topo, is_broken, rest.columns, surfacing.min_particles);
    f.row["broken_edges"] = f.broken;
    f.row["inland_plates"] = sides.inland_plates;
    f.row["polygon_sides_mean"] = sides.mean_sides;
    f.row["polygon_sides_histogram"] = sides.histogram;
    f.row.update(crack_fields(f.sizes, f.polygons, f.network,
                              measure_crack_depth(topo, is_broken, rest.columns)));
    f.meshes =
        measure_frame_meshes(surface_dir, surfacing.manifest, surfacing.files, n, shot.sim.h);
    if (f.meshes) f.row.update(mesh_fields(*f.meshes));
    if (surfacing.cut_frame) {
        // the top as the plates meshes part it: a torn band's broken edges that the mode welds
        // into one side join, and an unbroken edge between its two sides parts
        const std::vector<uint8_t> is_cut = parted_at(*surfacing.cut_frame, n);
        f.cut_polygons =
            measure_surface_polygons(topo, is_cut, rest.columns, surfacing.min_particles);
        f.cut_network = measure_crack_network(topo, is_cut, rest.columns, surfacing.min_particles);
        f.row.update(
            cut_fields(*f.cut_polygons, *f.cut_network,
                       measure_unopened_walls(topo, is_broken, is_cut, rest.columns, x, frame.Jw)));
    }
    if (motion_tracker) f.motion = motion_tracker->step(frame);
    if (f.motion) f.row.update(motion_fields(*f.motion));
    return f;
}

void print_frame_header(const Shot& shot, const RestSetup& rest) {
    std::printf("%s: %s, %zu particles in %d columns of %.4g m\n", kProgram, shot.name.c_str(),
                rest.mesh.X.size(), rest.columns.n_columns(), rest.spacing);
    std::printf("%6s %8s %11s %9s %9s %8s %10s %8s %10s %9s %7s %13s %8s %6s %6s %6s %8s %8s\n",
                "frame", "time[s]", "rise50[mm]", "curl[mm]", "split[%]", "splitH", "lifted[%]",
                "broken", "fragments", "polygons", "plates", "polygon[m^2]", "axis[%]", "+-[%]",
                "T[%]", "Y[%]", "str[%]", "comp[%]");
}

void print_frame_row(int n, const FrameMeasures& f, bool has_surfacing) {
    std::printf("%6d %8.4f %11.2f %9.2f %9.2f %8.2f %10.2f", n, f.time,
                1e3 * f.shape.top_rise_median, 1e3 * f.shape.curl, 100 * f.shape.split_fraction,
                f.shape.split_height_median, 100 * f.shape.lifted_fraction);
    if (has_surfacing)
        std::printf(" %8lld %10d %9d %7.2f %13.4g %8.1f %6.1f %6.1f %6.1f",
                    static_cast<long long>(f.broken), f.sizes.count, f.polygons.count,
                    f.polygons.effective_count, f.polygons.weighted_mean_area,
                    100 * f.network.axis_aligned_fraction,
                    100 * f.network.axis_aligned_fraction_stderr, 100 * f.network.t_fraction,
                    100 * f.network.y_fraction);
    else
        std::printf(" %8s %10s %9s %7s %13s %8s %6s %6s %6s", "-", "-", "-", "-", "-", "-", "-",
                    "-", "-");
    if (f.halves)
        std::printf(" %8.1f %8.1f\n", 100 * f.halves->stretched_fraction,
                    100 * f.halves->compressed_fraction);
    else
        std::printf(" %8s %8s\n", "-", "-");
}

void print_pace(const CrackPace& pace, int last) {
    if (pace.first_crack_frame < 0) {
        std::printf("\npace: no crack by frame %d\n", last);
        return;
    }
    std::printf(
        "\npace: first crack in frame %d; half of frame %d's broken edges by frame %d (%.0f %% "
        "of the shot's frame range)\n",
        pace.first_crack_frame, last, pace.half_broken_frame,
        100 * pace.half_broken_range_fraction);
}

void print_mesh_table(const json& surface_manifest, bool has_motion, int first,
                      const std::vector<MeshRow>& rows) {
    std::printf(
        "\nsurfacing meshes (%s): pieces, chips under 2 h, edges not shared by two triangles and those of "
        "an odd number (holes), crack-wall roughness, crack area per metre of top crack line; in "
        "the plates mode the top's polygons, effective plates, largest polygon and axis share as "
        "its meshes cut it, with the share's standard error over its cracks%s\n",
        surface_manifest.value("mode", "?").c_str(),
        has_motion
            ? "; vertex jumps beyond the particles' moves (cells) and particles changing piece"
            : "");
    std::printf("%6s %7s %6s %6s %6s %10s %11s %9s %7s %8s %8s %6s %9s %9s %9s\n", "frame",
                "pieces", "chips", "open", "holes", "rough[deg]", "wall[m2/m]", "polygons",
                "plates", "largest", "axis[%]", "+-[%]", "jump_max", "jump_p99", "changes");
    for (size_t i = 0; i < rows.size(); ++i) print_mesh_row(first + int(i), rows[i]);
}

}  // namespace

int run_measure_stage(const StageOptions& options, const MeasureStageOptions& measure_options) {
    const Shot shot = load_shot(options.shot);
    const fs::path out(options.out);
    const fs::path init_dir = out / "init", sim_dir = out / "sim", surface_dir = out / "surface";
    const json init_manifest = read_current_manifest(init_dir, shot.slice_hash(Stage::Init));
    const json sim_manifest = read_current_manifest(sim_dir, shot.slice_hash(Stage::Sim));
    const RecordedChecksums sim_files(sim_manifest, sim_dir / "manifest.json");
    const ManifestFrames cached = manifest_frames(sim_manifest, sim_dir / "manifest.json");
    const FrameRange frames = frames_to_process(options, {cached.first, cached.last},
                                                (sim_dir / "manifest.json").string());
    const int first = frames.first, last = frames.last;

    // the rest state, the surfacing's outputs when it ran, the motion tracker on --motion
    const RestSetup rest = read_rest_setup(shot, init_dir, init_manifest);
    SurfaceOutputs surfacing;
    read_surface_outputs(shot, surface_dir, rest.mesh, last, surfacing);
    std::optional<ShotFracture> fracture =
        plan_surfacing_fracture(shot, sim_dir, sim_files, surfacing);
    if (fracture) surfacing.cut_frame = fracture->cut_frame;
    if (!options.quiet) print_frame_header(shot, rest);
    std::optional<MotionTracker> motion_tracker =
        measure_options.motion ? make_motion_tracker(shot, surfacing, sim_dir, surface_dir,
                                                     sim_files, std::move(fracture))
                               : std::nullopt;

    // the frames, in order (the motion tracker carries one frame to the next)
    json table = json::array();
    std::vector<MeshRow> mesh_rows;
    for (int n = first; n <= last; ++n) {
        FrameMeasures f = measure_frame(shot, rest, surfacing, init_dir, sim_dir, surface_dir,
                                        sim_files, motion_tracker, n);
        if (surfacing.topo)
            mesh_rows.push_back({f.meshes, f.cut_polygons, f.cut_network, f.motion});
        if (!options.quiet) print_frame_row(n, f, surfacing.topo.has_value());
        table.push_back(std::move(f.row));
    }
    if (!options.quiet && !mesh_rows.empty())
        print_mesh_table(surfacing.manifest, motion_tracker.has_value(), first, mesh_rows);
    // the pace, from the break history: every frame up to the last measured, measured or not
    std::optional<CrackPace> pace;
    if (surfacing.history) {
        pace = measure_crack_pace(surfacing.history->first_break, shot.sim.time.frame_start,
                                  shot.sim.time.frame_end, last);
        if (!options.quiet) print_pace(*pace, last);
    }
    if (!measure_options.json_file.empty()) {
        json doc = {{"shot", shot.name},
                    {"particles", rest.mesh.X.size()},
                    {"column_width", rest.spacing},
                    {"columns", rest.columns.n_columns()},
                    {"frames", std::move(table)}};
        if (pace) doc["pace"] = pace_fields(*pace);
        write_text_atomically(measure_options.json_file, doc.dump(2) + "\n");
    }
    return 0;
}

}  // namespace mudcrack
