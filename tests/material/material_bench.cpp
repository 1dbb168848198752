// Cost of the per-particle constitutive kernels: ns per svd3, per Kirchhoff stress and per NACC
// return mapping (inside and projected states), with Eigen's JacobiSVD for comparison.
// Each benchmark cycles through 4096 precomputed seeded inputs, so branch predictors see a
// realistic mix; items_per_second is kernel calls per second.
#include <benchmark/benchmark.h>

#include <Eigen/SVD>
#include <random>
#include <vector>

#include "material/material_samples.h"
#include "sim/material/nacc.h"
#include "sim/material/neo_hookean.h"
#include "sim/material/svd3.h"

namespace mudcrack {
namespace {

constexpr int kInputs = 4096;
const LameParams kLame{370.37, 1111.1};  // reference bench scene: E = 1000, nu = 0.35

/// Elastic deformation gradients as an MPM run sees them: arbitrary rotations, stretches
/// exp(N(0, spread)).
std::vector<Mat3> deformations(Real spread, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::vector<Mat3> F(kInputs);
    for (Mat3& f : F) f = test::random_deformation(rng, spread);
    return F;
}

NaccParams bench_nacc() {
    NaccParams n;
    n.alpha0 = std::log(0.99);
    n.M = 1.85;
    n.xi = 3;
    n.beta0 = n.beta1 = 2;
    return n;
}

void BM_Svd3(benchmark::State& state) {
    const std::vector<Mat3> F = deformations(state.range(0) * 1e-3, 1);
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(svd3(F[i++ & (kInputs - 1)]));
    }
    state.SetItemsProcessed(state.iterations());
}
// argument: stretch spread in units of 1e-3 (10: near-rotation, 300: large strains)
BENCHMARK(BM_Svd3)->Arg(10)->Arg(300);

void BM_Svd3_RandomEntries(benchmark::State& state) {
    std::mt19937_64 rng(2);
    std::vector<Mat3> F(kInputs);
    for (Mat3& f : F) f = test::random_matrix(rng);
    size_t i = 0;
    for (auto _ : state) benchmark::DoNotOptimize(svd3(F[i++ & (kInputs - 1)]));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Svd3_RandomEntries);

void BM_EigenJacobiSvd(benchmark::State& state) {
    const std::vector<Mat3> F = deformations(0.3, 1);
    size_t i = 0;
    for (auto _ : state) {
        Eigen::JacobiSVD<Mat3> svd(F[i++ & (kInputs - 1)],
                                   Eigen::ComputeFullU | Eigen::ComputeFullV);
        benchmark::DoNotOptimize(svd.singularValues());
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EigenJacobiSvd);

void BM_KirchhoffFromSvd(benchmark::State& state) {
    const std::vector<Mat3> F = deformations(0.05, 3);
    std::vector<Svd3> svd(kInputs);
    for (int k = 0; k < kInputs; ++k) svd[k] = svd3(F[k]);
    size_t i = 0;
    for (auto _ : state)
        benchmark::DoNotOptimize(neo_hookean_kirchhoff(svd[i++ & (kInputs - 1)], kLame));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KirchhoffFromSvd);

void BM_KirchhoffDirect(benchmark::State& state) {
    const std::vector<Mat3> F = deformations(0.05, 3);
    size_t i = 0;
    for (auto _ : state)
        benchmark::DoNotOptimize(neo_hookean_kirchhoff(F[i++ & (kInputs - 1)], kLame));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KirchhoffDirect);

/// Return mapping including its SVD. Arg 0: states inside the yield surface (small strain);
/// arg 1: states outside (large deviatoric strain, projected or tip).
void BM_NaccReturnMap(benchmark::State& state) {
    const bool outside = state.range(0) != 0;
    const std::vector<Mat3> F = deformations(outside ? 0.3 : 0.002, 4);
    const NaccParams n = bench_nacc();
    const Real alpha = outside ? -0.05 : -0.3;
    size_t i = 0;
    int projected = 0;
    for (auto _ : state) {
        const NaccReturn r = nacc_return_map(F[i++ & (kInputs - 1)], alpha, 2, n, kLame);
        projected += r.yield_case != kNaccInside;
        benchmark::DoNotOptimize(r);
    }
    state.counters["outside_fraction"] = Real(projected) / Real(state.iterations());
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NaccReturnMap)->Arg(0)->Arg(1);

/// nacc_project: the same mapping without an SVD (the matrix function of b; the SVD only for
/// inverted or extreme states); inside states return after the invariants.
void BM_NaccProject(benchmark::State& state) {
    const bool outside = state.range(0) != 0;
    const std::vector<Mat3> F = deformations(outside ? 0.3 : 0.002, 4);
    const NaccParams n = bench_nacc();
    const Real alpha = outside ? -0.05 : -0.3;
    size_t i = 0;
    for (auto _ : state)
        benchmark::DoNotOptimize(nacc_project(F[i++ & (kInputs - 1)], alpha, 2, n, kLame));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NaccProject)->Arg(0)->Arg(1);

/// What the MPM step does per particle after the trial Fe: return map (with its SVD) and the
/// Kirchhoff stress from the returned SVD.
void BM_ReturnMapAndStress(benchmark::State& state) {
    const bool outside = state.range(0) != 0;
    const std::vector<Mat3> F = deformations(outside ? 0.3 : 0.002, 5);
    const NaccParams n = bench_nacc();
    size_t i = 0;
    for (auto _ : state) {
        const NaccReturn r =
            nacc_return_map(F[i++ & (kInputs - 1)], outside ? -0.05 : -0.3, 2, n, kLame);
        benchmark::DoNotOptimize(neo_hookean_kirchhoff(r.svd, kLame));
        benchmark::DoNotOptimize(r.alpha);
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ReturnMapAndStress)->Arg(0)->Arg(1);

}  // namespace
}  // namespace mudcrack

BENCHMARK_MAIN();
