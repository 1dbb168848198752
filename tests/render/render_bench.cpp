// Seconds per 1920x1080 preview frame of a ~1M-triangle mesh (target: <= 1 s on 2 cores;
// set LP_NUM_THREADS=2 to give llvmpipe two threads). Reports the render alone (mesh already
// uploaded, what a turntable pays per view) and upload + render (what an animation pays).
#include <benchmark/benchmark.h>

#include "render/renderer.h"
#include "synthetic_scenes.h"

namespace mudcrack {
namespace {

/// A UV sphere of ~1M triangles with a crack block.
const Scene& million_triangle_scene() {
    static const Scene scene = [] {
        Scene s;
        s.meshes.push_back(
            {test::uv_sphere(Vec3f(0, 0.5f, 0), 0.5f, 500, 1000), SurfaceKind::Boundary});
        s.meshes.push_back({test::box_mesh(Vec3f(0.6f, 0, -0.3f), Vec3f(1.1f, 0.3f, 0.2f), "crack",
                                           [](const Vec3f& p, float& sat, float& a) {
                                               sat = p.y();
                                               a = 0;
                                           }),
                            SurfaceKind::Crack});
        return s;
    }();
    return scene;
}

RenderParams hd_params() {
    RenderParams p;
    p.width = 1920;
    p.height = 1080;
    p.samples = 4;
    return p;
}

void BM_RenderFrame1080p(benchmark::State& state) {
    const Scene& s = million_triangle_scene();
    Renderer r(hd_params());
    r.set_scene(s);
    const Camera cam = auto_frame(scene_bounds(s), 35, 16.0f / 9.0f);
    for (auto _ : state) benchmark::DoNotOptimize(r.render(cam));
    state.counters["triangles"] = double(triangle_count(s));
    state.counters["samples"] = r.samples();
}
BENCHMARK(BM_RenderFrame1080p)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

void BM_UploadAndRenderFrame1080p(benchmark::State& state) {
    const Scene& s = million_triangle_scene();
    Renderer r(hd_params());
    const Camera cam = auto_frame(scene_bounds(s), 35, 16.0f / 9.0f);
    for (auto _ : state) {
        r.set_scene(s);
        benchmark::DoNotOptimize(r.render(cam));
    }
    state.counters["triangles"] = double(triangle_count(s));
}
BENCHMARK(BM_UploadAndRenderFrame1080p)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

}  // namespace
}  // namespace mudcrack

BENCHMARK_MAIN();
