#include "pipeline/stages/init/init_stage.h"

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/init/init_builder.h"
#include "pipeline/io/atomic_output.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/points_io.h"
#include "pipeline/io/tet_mesh_io.h"
#include "pipeline/shot/measured_body.h"
#include "pipeline/shot/shot.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/stats.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

/// The particles as a points cache: P, id (= index), the rest volume "volume0" and, for a
/// heterogeneous soil, the p0 multiplier "strength" (an artist may repaint it in Houdini).
PointCloud init_points(const InitResult& r) {
    PointCloud cloud;
    const size_t n = r.mesh.X.size();
    cloud.P.resize(n);
    cloud.id.resize(n);
    std::vector<float> volume0(n);
    for (size_t i = 0; i < n; ++i) {
        cloud.P[i] = r.mesh.X[i].cast<float>();
        cloud.id[i] = static_cast<int32_t>(i);
        volume0[i] = static_cast<float>(r.volume0[i]);
    }
    cloud.floats.emplace_back("volume0", std::move(volume0));
    if (!r.strength.empty()) {
        std::vector<float> strength(n);
        for (size_t i = 0; i < n; ++i) strength[i] = static_cast<float>(r.strength[i]);
        cloud.floats.emplace_back("strength", std::move(strength));
    }
    cloud.meta_string["mudcrack:stage"] = "init";
    return cloud;
}

json vec_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

/// The init-specific manifest fields: source, counts, quality, timing.
void add_init_fields(json& m, const InitParams& params, bool parallel_mesh, const InitResult& r,
                     double build_seconds) {
    const MeshQuality& q = r.quality;
    m["source"] = source_type_name(params.type);
    m["parallel_mesh"] = parallel_mesh;
    m["seed"] = params.seed;
    m["counts"] = {
        {"particles", q.particles}, {"tets", q.tets}, {"boundary_faces", q.boundary_faces}};
    json quality = {
        {"min_dihedral_deg", q.min_dihedral_deg}, {"max_dihedral_deg", q.max_dihedral_deg},
        {"mean_edge_length", q.mean_edge_length}, {"tet_volume", q.tet_volume},
        {"bbox_min", vec_json(q.bbox_min)},       {"bbox_max", vec_json(q.bbox_max)}};
    if (r.surface_volume > 0) {  // Mesh_3's tets of a surface: a mesh, or a box's (lattice mesh)
        quality["surface_volume"] = r.surface_volume;
        quality["volume_error_pct"] = 100 * (q.tet_volume / r.surface_volume - 1);
        m["edge_length"] = r.edge_length;
    }
    m["quality"] = quality;
    m["uv_method"] = r.uv_method;
    m["build_seconds"] = build_seconds;
    m["rates"] = {{"tets_per_s", q.tets / build_seconds},
                  {"particles_per_s", q.particles / build_seconds}};
}

void print_summary(const InitParams& params, const InitResult& r, double build_seconds,
                   double wall_seconds, const fs::path& dir) {
    const MeshQuality& q = r.quality;
    std::printf("mc-init %s -> %s\n", source_type_name(params.type), dir.string().c_str());
    std::printf("  %-22s %14lld\n", "particles", static_cast<long long>(q.particles));
    std::printf("  %-22s %14lld\n", "tets", static_cast<long long>(q.tets));
    std::printf("  %-22s %14lld\n", "boundary faces", static_cast<long long>(q.boundary_faces));
    std::printf("  %-22s %14.2f\n", "min dihedral [deg]", q.min_dihedral_deg);
    std::printf("  %-22s %14.6g\n", "volume [m^3]", q.tet_volume);
    if (r.surface_volume > 0)
        std::printf("  %-22s %+14.3f\n", "vs surface [%]",
                    100 * (q.tet_volume / r.surface_volume - 1));
    std::printf("  %-22s %14.2f\n", "build [s]", build_seconds);
    std::printf("  %-22s %14.0f\n", "tets/s", q.tets / build_seconds);
    std::printf("  %-22s %14.2f\n", "total [s]", wall_seconds);
    std::printf("  %-22s %14.1f\n", "peak memory [MiB]", peak_rss_bytes() / 1048576.0);
    std::fflush(stdout);  // before run_stage's closing log line on stderr
}

}  // namespace

int run_init_stage(const StageOptions& opt, bool parallel_mesh) {
    WallTimer wall;
    const Shot shot = load_shot(opt.shot);
    // the rest state serves every frame, so --frames selects nothing here; a range outside the
    // shot is still refused, as in every other stage
    frames_to_process(opt, {shot.sim.time.frame_start, shot.sim.time.frame_end},
                      opt.shot + " (/frames/start, /frames/end)");
    InitParams params = shot.init;
    if (opt.seed != 0) params.seed = opt.seed;
    MesherOptions mesher = mesher_options(params, shot.sim.h);
    mesher.parallel = parallel_mesh;

    // build everything in memory first: a bad source fails before any folder exists
    WallTimer build_timer;
    std::optional<MeasuredBody> mesh_body;
    const InitResult r = [&] {
        try {
            return build_init(params, mesher, [&](const Vec3& lo, const Vec3& hi) {
                mesh_body = placed_mesh_body(params.mesh.path, lo, hi);
                check_measured_body(shot, *mesh_body);
            });
        } catch (const ShotValueError& e) {
            // the builders name the key, not the file
            throw InputError(opt.shot + ": " + e.what());
        }
    }();
    const double build_seconds = build_timer.seconds();

    StagingDir staging(fs::path(opt.out) / "init", opt.keep_partial);
    write_points(staging.path() / "particles.vdb", init_points(r), shot.sim.h);
    write_tet_mesh_vtu(staging.path() / "tets.vtu", r.mesh);
    json manifest = make_manifest("init", opt.shot, shot.slice_hash(Stage::Init));
    add_init_fields(manifest, params, mesher.parallel, r, build_seconds);
    // mc-sim checks a ground edited after this run against them (it is not in the init slice)
    if (mesh_body)
        manifest["mesh_bounds"] = {{"min", vec_json(mesh_body->lo)},
                                   {"max", vec_json(mesh_body->hi)}};
    // what the later stages read, with the checksums they verify
    manifest["outputs"] = json::array(
        {file_record(staging.path() / "particles.vdb"), file_record(staging.path() / "tets.vtu")});
    manifest["wall_seconds"] = wall.seconds();
    manifest["peak_memory_bytes"] = peak_rss_bytes();
    write_manifest(staging.path(), manifest);  // last: its presence means the stage completed
    staging.commit();
    if (!opt.quiet) print_summary(params, r, build_seconds, wall.seconds(), staging.final_path());
    return 0;
}

}  // namespace mudcrack
