// Google Benchmark of the mesh source: check + CGAL Mesh_3 + boundary/UVs/volumes for a closed
// surface (default: the bunny) at several target edge lengths. Reports tets/s and particles/s
// plus the mesh figures; tools/bench_init.sh puts it side by side with TetGen.
//
//   init_mesh_bench [--mesh PATH] [--scale S] [--edges L1,L2,...] [--parallel] [--perturb]
//                   [--exude] [--facet-size-ratio R] [--cell-size-ratio R]
//                   [--facet-distance-ratio R] [--feature-angle DEG] [benchmark flags]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/init/boundary_uv.h"
#include "pipeline/init/cgal_mesher.h"
#include "pipeline/init/init_builder.h"
#include "pipeline/init/surface_check.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/stats.h"

namespace mudcrack {
namespace {

struct BenchConfig {
    std::string mesh = std::string(MUDCRACK_SOURCE_DIR) + "/shots/assets/bunny00.off";
    Real scale = 1;
    std::vector<Real> edges = {0.03, 0.019, 0.014};  // ~10K, ~40K, ~100K bunny particles
    MesherOptions mesher;
};

/// Takes our flags out of argv (benchmark::Initialize rejects unknown ones).
BenchConfig parse_flags(int& argc, char** argv) {
    BenchConfig c;
    std::vector<char*> rest = {argv[0]};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw InputError(a + ": missing value");
            return argv[++i];
        };
        if (a == "--mesh")
            c.mesh = value();
        else if (a == "--scale")
            c.scale = std::stod(value());
        else if (a == "--edges") {
            c.edges.clear();
            std::stringstream s(value());
            for (std::string e; std::getline(s, e, ',');) c.edges.push_back(std::stod(e));
        } else if (a == "--parallel")
            c.mesher.parallel = true;
        else if (a == "--perturb")
            c.mesher.perturb = true;
        else if (a == "--exude")
            c.mesher.exude = true;
        else if (a == "--facet-size-ratio")
            c.mesher.facet_size_ratio = std::stod(value());
        else if (a == "--cell-size-ratio")
            c.mesher.cell_size_ratio = std::stod(value());
        else if (a == "--facet-distance-ratio")
            c.mesher.facet_distance_ratio = std::stod(value());
        else if (a == "--feature-angle")
            c.mesher.feature_angle = std::stod(value());
        else
            rest.push_back(argv[i]);
    }
    argc = static_cast<int>(rest.size());
    for (int i = 0; i < argc; ++i) argv[i] = rest[i];
    return c;
}

void bench_mesh(benchmark::State& state, const BenchConfig& config, Real edge) {
    MeshSource source;
    source.path = config.mesh;
    source.scale = config.scale;
    const InputSurface surface = load_placed_surface(source);
    MesherOptions o = config.mesher;
    o.edge_length = edge;
    InitResult r;
    double seconds = 0, check_seconds = 0, mesh_seconds = 0;
    for (auto _ : state) {
        // what mc-init does for a mesh source after loading: check, mesh, finish
        WallTimer timer;
        const Real surface_volume = check_input_surface(surface, source.path);
        check_seconds += timer.seconds();
        WallTimer mesh_timer;
        TetMesh tets = tetrahedralize_surface(surface, o);
        mesh_seconds += mesh_timer.seconds();
        r = finish_tet_mesh(std::move(tets), &surface);
        r.surface_volume = surface_volume;
        seconds += timer.seconds();
    }
    const double n = static_cast<double>(state.iterations());
    state.counters["edge_mm"] = 1000 * edge;
    state.counters["particles"] = static_cast<double>(r.quality.particles);
    state.counters["tets"] = static_cast<double>(r.quality.tets);
    state.counters["tets/s"] = r.quality.tets * n / seconds;
    state.counters["particles/s"] = r.quality.particles * n / seconds;
    state.counters["min_dihedral"] = r.quality.min_dihedral_deg;
    state.counters["mean_edge_mm"] = 1000 * r.quality.mean_edge_length;
    state.counters["vol_err_pct"] = 100 * (r.quality.tet_volume / r.surface_volume - 1);
    state.counters["check_s"] = check_seconds / n;  // PMP checks (self-intersections, volume)
    state.counters["mesh_s"] = mesh_seconds / n;    // Mesh_3 itself
    state.counters["peak_MiB"] = peak_rss_bytes() / 1048576.0;
}

}  // namespace
}  // namespace mudcrack

int main(int argc, char** argv) {
    using namespace mudcrack;
    log::set_level(log::Level::Warning);
    BenchConfig config;
    try {
        config = parse_flags(argc, argv);
    } catch (const std::exception& e) {
        std::cerr << "init_mesh_bench: error: " << e.what() << "\n";
        return 2;
    }
    for (Real edge : config.edges) {
        char name[128];
        std::snprintf(name, sizeof name, "mesh/%s/edge:%.4g",
                      config.mesher.parallel ? "parallel" : "sequential", edge);
        benchmark::RegisterBenchmark(
            name, [config, edge](benchmark::State& s) { bench_mesh(s, config, edge); })
            ->Unit(benchmark::kSecond)
            ->Iterations(1)
            ->UseRealTime();
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
