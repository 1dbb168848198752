// The issue-3 reference scene: a 0.49 m cube of 125,000 NACC particles (2x2x2 per cell, h = 0.02)
// falling at 2 m/s onto a sticky ground, dt = 2e-4 fixed, with and without moisture, on 1 and 2
// threads, stepped as mc-sim steps (through sim/mpm/step_retry.h), with a double state and with
// a float one (BM_ReferenceSceneFloat), and the moisture step's floor (BM_ReferenceSceneNoCg-
// Iteration). Reports particle-steps/s, bytes per particle of simulation state (grid and the
// rollback copy included), and the wall ns per particle-step of each phase of the step (ns_bin
// ... ns_g2p, StepPhaseSeconds) and of the loop's rest (ns_rest): the per-phase table, whose 1-
// and 2-thread columns show which phase does not scale.
//
//   build/bin/mpm_bench                        # 404 steps per run, 3 runs each, medians
//   MUDCRACK_BENCH_STEPS=100 build/bin/mpm_bench --benchmark_filter=NoMoisture/1
//   MUDCRACK_BENCH_REPETITIONS=1 ...           # one run per configuration
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <ctime>

#include "sim/core/parallel.h"
#include "sim/core/stats.h"
#include "sim/mpm/simulation.h"
#include "sim/mpm/step_retry.h"

namespace mudcrack {
namespace {

constexpr int kDefaultSteps = 404;

// process CPU time [s]: on a loaded machine wall time measures the other jobs too; with one
// thread, steps per CPU second is what an idle machine would give
double process_cpu_seconds() {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

int bench_steps() {
    const char* env = std::getenv("MUDCRACK_BENCH_STEPS");
    return env ? std::max(1, std::atoi(env)) : kDefaultSteps;
}

// repetitions per configuration (3; tools/bench_moisture_cost.sh interleaves single runs)
int bench_repetitions() {
    const char* env = std::getenv("MUDCRACK_BENCH_REPETITIONS");
    return env ? std::max(1, std::atoi(env)) : 3;
}

using DiffusionOperator = MoistureParams::DiffusionOperator;

// moisture_interval: 0 = no moisture section, k = solve the moisture every k steps, with L
// discretised by `diffusion_operator` (docs/physics.md §4.9) and at most cg_max_iterations
// iterations a solve
SimModel reference_model(int moisture_interval,
                         DiffusionOperator diffusion_operator = DiffusionOperator::Particles,
                         int cg_max_iterations = MoistureParams{}.cg_max_iterations) {
    SimModel m;
    m.h = 0.02;
    m.gravity = Vec3(0, -9.81, 0);
    m.initial_velocity = Vec3(0, -2, 0);
    m.elastic.density = 2;
    m.elastic.youngs_modulus = 1000;
    m.elastic.poisson_ratio = 0.35;
    m.nacc = NaccParams{};
    m.nacc->alpha0 = std::log(0.99);
    m.nacc->M = 1.85;
    m.nacc->beta0 = m.nacc->beta1 = 2;
    m.nacc->xi = 3;
    m.ground = GroundParams{};
    m.ground->height = 0;
    m.ground->mode = ColliderMode::Sticky;
    m.time.dt_fixed = 2e-4;
    if (moisture_interval > 0) {
        m.moisture = MoistureParams{};
        m.moisture->interval = moisture_interval;
        m.moisture->diffusion_operator = diffusion_operator;
        m.moisture->cg_max_iterations = cg_max_iterations;
    }
    return m;
}

// 50^3 particles at spacing 0.01 (2 per cell per axis), the cube's bottom 2 cells above the ground
void reference_particles(std::vector<Vec3>& X, std::vector<Real>& V0) {
    constexpr int n = 50;
    constexpr Real spacing = 0.01;
    X.clear();
    V0.clear();
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                X.emplace_back(spacing * (i + 0.5), 0.04 + spacing * (j + 0.5),
                               spacing * (k + 0.5));
                V0.push_back(spacing * spacing * spacing);
            }
}

template <class S>
void run_reference_scene(benchmark::State& bs, const SimModel& model) {
    const int threads = static_cast<int>(bs.range(0));
    set_thread_count(threads);
    std::vector<Vec3> X;
    std::vector<Real> V0;
    reference_particles(X, V0);
    const int steps = bench_steps();
    int64_t particle_steps = 0;
    double bytes_per_particle = 0, cg_iterations = 0, cpu_seconds = 0, loop_seconds = 0;
    StepPhaseSeconds phases;  // of the accepted steps
    for (auto _ : bs) {
        bs.PauseTiming();
        SimStateOf<S> state = make_initial_state<S>(model, X, V0);
        bs.ResumeTiming();
        const double cpu0 = process_cpu_seconds();
        const WallTimer loop;
        // mc-sim's step loop: through the rollback and retry of failed substeps
        RetryingStepperOf<S> stepper;
        stepper.restart(state);
        int cg = 0;
        for (int i = 0; i < steps;) {
            const StepAttempt a =
                stepper.attempt(model, state, stable_dt(model, state) * stepper.dt_scale());
            if (!a.is_accepted) continue;
            cg += a.stats.cg_iterations;
            phases += a.stats.seconds;
            ++i;
        }
        loop_seconds += loop.seconds();
        cpu_seconds += process_cpu_seconds() - cpu0;
        particle_steps += static_cast<int64_t>(state.size()) * steps;
        bytes_per_particle =
            static_cast<double>(state_memory_bytes(state) + stepper.memory_bytes()) / state.size();
        cg_iterations = static_cast<double>(cg) / steps;
    }
    bs.counters["particle_steps_per_s"] =
        benchmark::Counter(static_cast<double>(particle_steps), benchmark::Counter::kIsRate);
    bs.counters["particle_steps_per_cpu_s"] = static_cast<double>(particle_steps) / cpu_seconds;
    bs.counters["bytes_per_particle"] = bytes_per_particle;
    bs.counters["cg_iters_per_step"] = cg_iterations;
    bs.counters["peak_rss_MB"] = static_cast<double>(peak_rss_bytes()) / (1 << 20);
    // the per-phase table: wall ns per particle-step of each phase of step(), and the rest of the
    // loop (the stable dt's reduction, the rollback copies, failed attempts)
    const auto ns = [&](double seconds) {
        return 1e9 * seconds / static_cast<double>(particle_steps);
    };
    bs.counters["ns_bin"] = ns(phases.bin);
    bs.counters["ns_p2g"] = ns(phases.p2g);
    bs.counters["ns_grid"] = ns(phases.grid);
    bs.counters["ns_moisture"] = ns(phases.moisture);
    bs.counters["ns_g2p"] = ns(phases.g2p);
    bs.counters["ns_rest"] = ns(loop_seconds - phases.total());
}

void BM_ReferenceScene(benchmark::State& bs, int moisture_interval,
                       DiffusionOperator diffusion_operator) {
    run_reference_scene<double>(bs, reference_model(moisture_interval, diffusion_operator));
}
// A cost probe, not a solver setting: every step sets up the solve and forms its first residual
// (one operator pass) but runs no CG iteration, so its ns_moisture is the floor of a solve every
// step with the paper's operator, whatever a better start or preconditioner would save
void BM_ReferenceSceneNoCgIteration(benchmark::State& bs) {
    run_reference_scene<double>(bs, reference_model(1, DiffusionOperator::Particles, 0));
}
// the same scene with a float state (/sim/precision "float"): its speed and bytes per particle
void BM_ReferenceSceneFloat(benchmark::State& bs, int moisture_interval,
                            DiffusionOperator diffusion_operator) {
    run_reference_scene<float>(bs, reference_model(moisture_interval, diffusion_operator));
}

// the rollback point of sim/mpm/step_retry.h: a copy of the reference state (moisture arrays
// included), taken at every frame start and every 64 steps; its cost per particle against a
// step's is what rollback and retry add to a run where nothing fails
void BM_RollbackPoint(benchmark::State& bs) {
    const SimModel model = reference_model(1);
    std::vector<Vec3> X;
    std::vector<Real> V0;
    reference_particles(X, V0);
    SimState state = make_initial_state(model, X, V0);
    RetryingStepper stepper;
    stepper.restart(state);  // the first copy allocates; the ones measured reuse the arrays
    for (auto _ : bs) stepper.restart(state);
    bs.counters["ns_per_particle"] = benchmark::Counter(
        static_cast<double>(state.size()),
        benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
    bs.counters["bytes_per_particle"] = static_cast<double>(stepper.memory_bytes()) / state.size();
}

BENCHMARK(BM_RollbackPoint)->Unit(benchmark::kMillisecond);

// each variant on 1 and 2 threads, one timed run per repetition, in wall time
void reference_scene_runs(benchmark::internal::Benchmark* b) {
    b->Arg(1)->Arg(2)->Iterations(1)->Repetitions(bench_repetitions())->UseRealTime();
    b->Unit(benchmark::kSecond);
}

constexpr DiffusionOperator kParticles = DiffusionOperator::Particles;
BENCHMARK_CAPTURE(BM_ReferenceScene, NoMoisture, 0, kParticles)->Apply(reference_scene_runs);
BENCHMARK_CAPTURE(BM_ReferenceScene, Moisture, 1, kParticles)->Apply(reference_scene_runs);
BENCHMARK_CAPTURE(BM_ReferenceScene, MoistureEvery2Steps, 2, kParticles)
    ->Apply(reference_scene_runs);
BENCHMARK_CAPTURE(BM_ReferenceScene, MoistureEvery4Steps, 4, kParticles)
    ->Apply(reference_scene_runs);
// the grid operator's L (/moisture/diffusion_operator "grid"): no particle pass in the CG
BENCHMARK_CAPTURE(BM_ReferenceScene, MoistureGridOperator, 1, DiffusionOperator::Grid)
    ->Apply(reference_scene_runs);
BENCHMARK(BM_ReferenceSceneNoCgIteration)->Apply(reference_scene_runs);
BENCHMARK_CAPTURE(BM_ReferenceSceneFloat, NoMoisture, 0, kParticles)->Apply(reference_scene_runs);
BENCHMARK_CAPTURE(BM_ReferenceSceneFloat, Moisture, 1, kParticles)->Apply(reference_scene_runs);

}  // namespace
}  // namespace mudcrack

BENCHMARK_MAIN();
