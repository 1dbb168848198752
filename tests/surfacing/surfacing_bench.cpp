// Per-frame particle-core surfacing speed (docs/physics.md §5): tets/s and triangles/s on a ~1M-tet
// box lattice with a smooth synthetic deformation and ~1% broken edges, at 1 and 2 threads;
// bytes per tet of the preprocessed topology and of one frame's output.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "sim/core/parallel.h"
#include "surfacing/core_surface.h"
#include "surfacing/edge_breaks.h"
#include "surfacing/lattice_mesh.h"

namespace mudcrack {
namespace {

constexpr int kCells = 55;  // 55^3 cells x 6 = 998,250 tets

struct Scene {
    TetMesh mesh;
    CoreTopology topo;
    ParticleFrame frame;
    std::vector<int32_t> first_break;
};

const Scene& scene() {
    static const Scene s = [] {
        Scene s;
        s.mesh = test::box_lattice(kCells, kCells, kCells, 0.01);
        s.topo = build_core_topology(s.mesh);
        s.frame.frame = 10;
        for (const Vec3& X : s.mesh.X) {
            const Vec3 u =
                0.02 * Vec3(std::sin(9 * X.y()), std::sin(7 * X.z()), std::cos(8 * X.x()));
            s.frame.P.push_back((X + u).cast<float>());
            const Mat3 R = Eigen::AngleAxis<Real>(2 * X.x(), Vec3(0, 1, 0)).toRotationMatrix();
            s.frame.Fe.push_back((R * (1 + 0.1 * X.y())).cast<float>());
            s.frame.Jw.push_back(float(1 - 0.4 * X.x() / (kCells * 0.01)));
            s.frame.saturation.push_back(float(X.z()));
            s.frame.alpha.push_back(float(-X.y()));
        }
        // ~1% of the edges broken at earlier frames
        std::mt19937 rng(1);
        std::bernoulli_distribution coin(0.01);
        s.first_break = no_edge_breaks(s.topo);
        for (auto& f : s.first_break)
            if (coin(rng)) f = 5;
        return s;
    }();
    return s;
}

// each benchmark on 1 and 2 threads, in wall time
void on_one_and_two_threads(benchmark::internal::Benchmark* b) {
    b->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
}

void BM_SurfaceFrame(benchmark::State& state) {
    const Scene& s = scene();
    set_thread_count(static_cast<int>(state.range(0)));
    SurfaceParams params;
    int64_t triangles = 0;
    size_t output_bytes = 0;
    for (auto _ : state) {
        const SurfacedFrame out = surface_frame(s.topo, s.frame, s.first_break, params);
        triangles = static_cast<int64_t>(out.boundary.faces.size() + out.crack.faces.size());
        output_bytes = 0;
        for (const TriMesh* m : {&out.boundary, &out.crack})
            output_bytes +=
                m->positions.size() * (sizeof(Vec3f) * 2 + sizeof(Vec2f) + 2 * sizeof(float)) +
                m->faces.size() * (sizeof(Tri) + sizeof(int32_t));
        benchmark::DoNotOptimize(out.boundary.positions.data());
    }
    const double n_tets = s.topo.n_tets();
    state.counters["tets/s"] =
        benchmark::Counter(n_tets, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["triangles/s"] =
        benchmark::Counter(double(triangles), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["triangles"] = double(triangles);
    state.counters["tets"] = n_tets;
    state.counters["broken_edges"] = double(count_broken_edges(s.first_break, s.frame.frame));
    state.counters["topology_B/tet"] = double(s.topo.memory_bytes()) / n_tets;
    state.counters["output_B/tet"] = double(output_bytes) / n_tets;
}
BENCHMARK(BM_SurfaceFrame)->Apply(on_one_and_two_threads);

void BM_RecordEdgeBreaks(benchmark::State& state) {
    const Scene& s = scene();
    set_thread_count(static_cast<int>(state.range(0)));
    SurfaceParams params;
    std::vector<int32_t> fb = no_edge_breaks(s.topo);
    for (auto _ : state) benchmark::DoNotOptimize(record_edge_breaks(s.topo, s.frame, params, fb));
    state.counters["tets/s"] =
        benchmark::Counter(s.topo.n_tets(), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RecordEdgeBreaks)->Apply(on_one_and_two_threads);

void BM_BuildTopology(benchmark::State& state) {
    const Scene& s = scene();
    set_thread_count(static_cast<int>(state.range(0)));
    for (auto _ : state) {
        const CoreTopology topo = build_core_topology(s.mesh);
        benchmark::DoNotOptimize(topo.edges.data());
    }
    state.counters["tets/s"] =
        benchmark::Counter(s.topo.n_tets(), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_BuildTopology)->Apply(on_one_and_two_threads)->Iterations(2);

}  // namespace
}  // namespace mudcrack

BENCHMARK_MAIN();
