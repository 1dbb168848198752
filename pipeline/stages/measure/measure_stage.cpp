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

/// The edges broken at frame n by the break history (broken at or before n).
std::vector<uint8_t> broken_at(const BreakHistory& history, int n) {
    std::vector<uint8_t> is_broken(history.first_break.size());
    for (size_t e = 0; e < is_broken.size(); ++e) is_broken[e] = history.first_break[e] <= n ? 1 : 0;
    return is_broken;
}

/// A frame's fragment, surface polygon, crack network and crack depth figures, as the table's JSON
/// fields.
json crack_fields(const FragmentSizes& sizes, const SurfacePolygons& polygons, const CrackNetwork& network,
                  const CrackDepth& depth) {
    return {{"fragments", sizes.count},
            {"largest_fragment_fraction", sizes.largest_fraction},
            {"weighted_mean_fragment_volume", sizes.weighted_mean_volume},
            {"surface_polygons", polygons.count},
            {"weighted_mean_polygon_area", polygons.weighted_mean_area},
            {"largest_polygon_fraction", polygons.largest_fraction},
            {"effective_surface_polygons", polygons.effective_count},
            {"crack_points", network.crack_points},
            {"oriented_crack_points", network.oriented_points},
            {"axis_aligned_fraction", network.axis_aligned_fraction},
            {"junctions", network.junctions},
            {"t_junction_fraction", network.t_fraction},
            {"y_junction_fraction", network.y_fraction},
            {"cracked_top_fraction", depth.cracked_fraction},
            {"crack_depth_median", depth.depth_median},
            {"crack_depth_p90", depth.depth_p90},
            {"crack_depth_max", depth.depth_max},
            {"cracked_column_thickness_median", depth.thickness_median},
            {"crack_through_fraction", depth.through_fraction}};
}

/// The first mesh of a frame's surfacing file named by the surface manifest's entry `which`
/// ("boundary" or "crack"), verified against its recorded checksum, or an empty mesh when the
/// frame has none.
TriMesh read_frame_mesh(const fs::path& surface_dir, const RecordedChecksums& surface_files, const json& entry,
                        const char* which) {
    if (!entry.contains(which) || entry[which].value("file", json()).is_null()) return TriMesh();
    const fs::path file = surface_dir / entry[which]["file"].get<std::string>();
    surface_files.verify(file);
    std::vector<TriMesh> meshes = import_meshes(file);
    return meshes.empty() ? TriMesh() : std::move(meshes.front());
}

/// What a close-up sees in frame n's mesh files (mesh_measures.h), when the surface folder has them.
std::optional<MeshPieces> measure_frame_meshes(const fs::path& surface_dir, const json& surface_manifest,
                                               const RecordedChecksums& surface_files, int n, Real cell) {
    for (const json& entry : surface_manifest.value("per_frame", json::array()))
        if (entry.value("frame", 0) == n)
            return measure_mesh_pieces(read_frame_mesh(surface_dir, surface_files, entry, "boundary"),
                                       read_frame_mesh(surface_dir, surface_files, entry, "crack"), cell);
    return std::nullopt;
}

json mesh_fields(const MeshPieces& m) {
    return {{"mesh_pieces", m.pieces},
            {"mesh_chips", m.chips},
            {"mesh_chip_triangle_fraction", m.chip_triangle_fraction},
            {"mesh_open_pieces", m.open_pieces},
            {"mesh_open_edges", m.open_edges},
            {"crack_wall_roughness_deg", m.crack_roughness_deg},
            {"crack_wall_area", m.crack_area},
            {"top_crack_length", m.top_crack_length},
            {"crack_area_per_metre", m.crack_area_per_metre}};
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
    MotionTracker(const CoreTopology& topo, const BreakHistory& history, const SurfaceParams& params, Real cell,
                  std::optional<ShotFracture> fracture)
        : m_topo(topo), m_history(history), m_params(params), m_cell(cell), m_fracture(std::move(fracture)) {}
    /// Surfaces `frame`; the motion from the frame before, when there was one.
    std::optional<SurfaceMotion> step(ParticleFrame frame) {
        SurfacedFrame now = surface_frame(m_topo, frame, m_history.first_break, m_params,
                                          m_fracture ? &*m_fracture : nullptr);
        std::optional<SurfaceMotion> motion;
        if (m_previous) motion = measure_surface_motion(m_topo, *m_previous, m_previous_frame, now, frame, m_cell);
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

void print_mesh_row(int n, const std::optional<MeshPieces>& mesh, const std::optional<SurfaceMotion>& motion) {
    std::printf("%6d", n);
    if (mesh)
        std::printf(" %7d %6d %6lld %10.2f %11.4f", mesh->pieces, mesh->chips, static_cast<long long>(mesh->open_edges),
                    mesh->crack_roughness_deg, mesh->crack_area_per_metre);
    else
        std::printf(" %7s %6s %6s %10s %11s", "-", "-", "-", "-", "-");
    if (motion)
        std::printf(" %9.3f %9.3f %9lld\n", motion->jump_max_cells, motion->jump_p99_cells,
                    static_cast<long long>(motion->piece_changes));
    else
        std::printf(" %9s %9s %9s\n", "-", "-", "-");
}

}  // namespace

int run_measure_stage(const StageOptions& options, const MeasureStageOptions& measure_options) {
    const std::string& json_file = measure_options.json_file;
    const Shot shot = load_shot(options.shot);
    const fs::path out(options.out);
    const fs::path init_dir = out / "init", sim_dir = out / "sim", surface_dir = out / "surface";
    const json init_manifest = read_current_manifest(init_dir, shot.slice_hash(Stage::Init));
    const json sim_manifest = read_current_manifest(sim_dir, shot.slice_hash(Stage::Sim));
    const RecordedChecksums sim_files(sim_manifest, sim_dir / "manifest.json");
    const ManifestFrames cached = manifest_frames(sim_manifest, sim_dir / "manifest.json");
    int first = cached.first, last = cached.last;
    if (options.frame_range.is_set()) {
        if (options.frame_range.first < first || options.frame_range.last > last)
            throw InputError("--frames " + options.frames + ": outside the cached frames " + std::to_string(first) +
                             "-" + std::to_string(last) + " of " + (sim_dir / "manifest.json").string());
        first = options.frame_range.first;
        last = options.frame_range.last;
    }

    RecordedChecksums(init_manifest, init_dir / "manifest.json").verify(init_dir / "tets.vtu");
    const TetMesh mesh = read_tet_mesh_vtu(init_dir / "tets.vtu");
    const std::vector<Real> rest_volume = particle_rest_volumes(mesh);
    const Real spacing = particle_spacing(rest_volume);
    const RestColumns columns = build_rest_columns(mesh.X, spacing);
    // gaps within 1.5 cells of the ground are lift-off: the grid holds that band (GroundBand)
    GroundBand ground;
    ground.cell = shot.sim.h;
    if (shot.sim.ground) {
        ground.ground_y = shot.sim.ground->height;
        ground.band = kGroundBandCells * shot.sim.h;
    }
    // the boundary particles (the ones a render shows), for the hardening colormap's halves
    std::vector<int32_t> surface_particles;
    for (const auto& tri : mesh.boundary)
        for (int k = 0; k < 3; ++k) surface_particles.push_back(static_cast<int32_t>(tri[k]));
    std::sort(surface_particles.begin(), surface_particles.end());
    surface_particles.erase(std::unique(surface_particles.begin(), surface_particles.end()), surface_particles.end());
    const Real alpha0 = shot.sim.nacc ? shot.sim.nacc->alpha0 : Real(0);

    // fragments only when the surfacing ran: its break history is the one source of "broken"
    std::optional<CoreTopology> topo;
    std::optional<BreakHistory> history;
    int min_particles = 1;
    json surface_manifest;
    RecordedChecksums surface_files;
    if (fs::exists(surface_dir / "manifest.json")) {
        surface_manifest = read_current_manifest(surface_dir, shot.slice_hash(Stage::Surface));
        surface_files = RecordedChecksums(surface_manifest, surface_dir / "manifest.json");
        min_particles = surface_manifest.value("min_fragment_particles", 1);
        surface_files.verify(surface_dir / kBreakHistoryFile);
        topo = build_core_topology(mesh);
        history = read_break_history(surface_dir / kBreakHistoryFile, std::nullopt, topo->n_edges());
        if (!history)
            throw InputError((surface_dir / kBreakHistoryFile).string() +
                             ": missing or damaged (or from another mesh): re-run mc-surface");
        if (history->last_frame < last)
            throw InputError((surface_dir / kBreakHistoryFile).string() + ": covers frames up to " +
                             std::to_string(history->last_frame) + ", not " + std::to_string(last) +
                             ": re-run mc-surface");
    }

    if (!options.quiet) {
        std::printf("%s: %s, %zu particles in %d columns of %.4g m\n", kProgram, shot.name.c_str(), mesh.X.size(),
                    columns.n_columns(), spacing);
        std::printf("%6s %8s %11s %9s %9s %8s %10s %8s %10s %9s %7s %13s %8s %6s %6s %8s %8s\n", "frame", "time[s]",
                    "rise50[mm]", "curl[mm]", "split[%]", "splitH", "lifted[%]", "broken", "fragments", "polygons",
                    "plates", "polygon[m^2]", "axis[%]", "T[%]", "Y[%]", "str[%]", "comp[%]");
    }
    std::optional<MotionTracker> motion_tracker;
    if (measure_options.motion) {
        if (!topo || !shot.surface)
            throw InputError("--motion: " + shot.path + " has no surfacing output in " + surface_dir.string() +
                             ": run mc-surface first");
        std::optional<ShotFracture> fracture;
        if (shot.surface->mode == SurfaceMode::Plates) {
            const fs::path last_path = frame_path(sim_dir, "particles", history->last_frame, "vdb");
            sim_files.verify(last_path);
            fracture = plan_shot_fracture(*topo, points_to_frame(read_points(last_path), last_path.string()),
                                          history->first_break, *shot.surface);
        }
        motion_tracker.emplace(*topo, *history, *shot.surface, shot.sim.h, std::move(fracture));
    }
    json table = json::array();
    std::vector<std::pair<std::optional<MeshPieces>, std::optional<SurfaceMotion>>> mesh_rows;
    for (int n = first; n <= last; ++n) {
        const fs::path path = frame_path(sim_dir, "particles", n, "vdb");
        sim_files.verify(path);
        const PointCloud cloud = read_points(path);
        const ParticleFrame frame = points_to_frame(cloud, path.string());
        if (frame.size() != mesh.X.size())
            throw InputError(path.string() + ": " + std::to_string(frame.size()) + " particles, but " +
                             (init_dir / "tets.vtu").string() + " has " + std::to_string(mesh.X.size()));
        std::vector<Vec3> x(frame.size());
        for (size_t p = 0; p < x.size(); ++p) x[p] = frame.P[p].cast<Real>();
        const LayerShape shape = measure_layer_shape(columns, mesh.X, x, spacing, ground);
        const double time = cloud.meta_double.count("mudcrack:time") ? cloud.meta_double.at("mudcrack:time") : 0.0;
        json row = {{"frame", n},
                    {"time", time},
                    {"top_rise_median", shape.top_rise_median},
                    {"top_rise_p95", shape.top_rise_p95},
                    {"curl", shape.curl},
                    {"split_fraction", shape.split_fraction},
                    {"split_height_median_cells", shape.split_height_median},
                    {"split_height_p10_cells", shape.split_height_p10},
                    {"lifted_fraction", shape.lifted_fraction}};
        std::optional<HardeningHalves> halves;
        if (!frame.alpha.empty()) {
            halves = measure_hardening_halves(surface_particles, frame.alpha, alpha0);
            row["surface_stretched_fraction"] = halves->stretched_fraction;
            row["surface_compressed_fraction"] = halves->compressed_fraction;
        }
        int64_t broken = -1;
        FragmentSizes sizes;
        SurfacePolygons polygons;
        CrackNetwork network;
        if (topo) {
            broken = count_broken_edges(history->first_break, n);
            const std::vector<uint8_t> is_broken = broken_at(*history, n);
            sizes = measure_fragment_sizes(find_fragments(*topo, is_broken, min_particles), rest_volume);
            polygons = measure_surface_polygons(*topo, is_broken, columns, min_particles);
            network = measure_crack_network(*topo, is_broken, columns, min_particles);
            row["broken_edges"] = broken;
            row.update(crack_fields(sizes, polygons, network, measure_crack_depth(*topo, is_broken, columns)));
            const std::optional<MeshPieces> meshes =
                measure_frame_meshes(surface_dir, surface_manifest, surface_files, n, shot.sim.h);
            if (meshes) row.update(mesh_fields(*meshes));
            std::optional<SurfaceMotion> motion;
            if (motion_tracker) motion = motion_tracker->step(frame);
            if (motion) row.update(motion_fields(*motion));
            mesh_rows.emplace_back(meshes, motion);
        }
        if (!options.quiet) {
            std::printf("%6d %8.4f %11.2f %9.2f %9.2f %8.2f %10.2f", n, time, 1e3 * shape.top_rise_median,
                        1e3 * shape.curl, 100 * shape.split_fraction, shape.split_height_median,
                        100 * shape.lifted_fraction);
            if (topo)
                std::printf(" %8lld %10d %9d %7.2f %13.4g %8.1f %6.1f %6.1f", static_cast<long long>(broken),
                            sizes.count, polygons.count, polygons.effective_count, polygons.weighted_mean_area,
                            100 * network.axis_aligned_fraction, 100 * network.t_fraction, 100 * network.y_fraction);
            else
                std::printf(" %8s %10s %9s %7s %13s %8s %6s %6s", "-", "-", "-", "-", "-", "-", "-", "-");
            if (halves)
                std::printf(" %8.1f %8.1f\n", 100 * halves->stretched_fraction, 100 * halves->compressed_fraction);
            else
                std::printf(" %8s %8s\n", "-", "-");
        }
        table.push_back(std::move(row));
    }
    if (!options.quiet && !mesh_rows.empty()) {
        std::printf("\nsurfacing meshes (%s): pieces, chips under 2 h, edges not shared by two triangles, crack-wall "
                    "roughness, crack area per metre of top crack line%s\n",
                    surface_manifest.value("mode", "?").c_str(),
                    motion_tracker ? "; vertex jumps beyond the particles' moves (cells) and particles changing piece" : "");
        std::printf("%6s %7s %6s %6s %10s %11s %9s %9s %9s\n", "frame", "pieces", "chips", "open", "rough[deg]",
                    "wall[m2/m]", "jump_max", "jump_p99", "changes");
        for (size_t i = 0; i < mesh_rows.size(); ++i) print_mesh_row(first + int(i), mesh_rows[i].first, mesh_rows[i].second);
    }
    if (!json_file.empty()) {
        const json doc = {{"shot", shot.name},
                          {"particles", mesh.X.size()},
                          {"column_width", spacing},
                          {"columns", columns.n_columns()},
                          {"frames", std::move(table)}};
        write_text_atomically(json_file, doc.dump(2) + "\n");
    }
    return 0;
}

}  // namespace mudcrack
