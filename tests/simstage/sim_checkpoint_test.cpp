// mc-sim's checkpoints: bitwise round trip of every SimState array, corruption detection, and a
// mid-run save/restore that continues bitwise identically to an uninterrupted run.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "pipeline/io/checkpoint_io.h"
#include "pipeline/stages/sim/sim_checkpoint.h"
#include "pipeline/stages/sim/sim_frame_stepper.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/mpm/simulation.h"

namespace fs = std::filesystem;
using namespace mudcrack;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() /
                         ("mudcrack_simstage_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

template <class S>
bool same_bits(const Eigen::Matrix<S, 3, 1>& a, const Eigen::Matrix<S, 3, 1>& b) {
    return std::memcmp(a.data(), b.data(), sizeof(a)) == 0;
}

// every array and scalar of the state, bit for bit (the workspace is scratch)
template <class S>
void expect_same_state(const SimStateOf<S>& a, const SimStateOf<S>& b) {
    EXPECT_EQ(std::memcmp(&a.time, &b.time, sizeof(double)), 0) << a.time << " vs " << b.time;
    EXPECT_EQ(a.step_count, b.step_count);
    EXPECT_EQ(std::memcmp(&a.moisture_lag, &b.moisture_lag, sizeof(double)), 0);
    EXPECT_TRUE(same_bits(a.id, b.id));
    EXPECT_TRUE(same_bits(a.x, b.x));
    EXPECT_TRUE(same_bits(a.v, b.v));
    EXPECT_TRUE(same_bits(a.C, b.C));
    EXPECT_TRUE(same_bits(a.Fe, b.Fe));
    EXPECT_TRUE(same_bits(a.J, b.J));
    EXPECT_TRUE(same_bits(a.alpha, b.alpha));
    EXPECT_TRUE(same_bits(a.V0, b.V0));
    EXPECT_TRUE(same_bits(a.mass, b.mass));
    EXPECT_TRUE(same_bits(a.theta, b.theta));
    EXPECT_TRUE(same_bits(a.Jw, b.Jw));
    EXPECT_TRUE(same_bits(a.strength, b.strength));
    EXPECT_TRUE(same_bits(a.damage, b.damage));
    EXPECT_EQ(a.moisture_flux.count, b.moisture_flux.count);
    EXPECT_EQ(std::memcmp(&a.moisture_flux.dt, &b.moisture_flux.dt, sizeof(Real)), 0);
    EXPECT_EQ(std::memcmp(&a.moisture_flux.dt_prev, &b.moisture_flux.dt_prev, sizeof(Real)), 0);
    EXPECT_TRUE(same_bits(a.moisture_flux.keys, b.moisture_flux.keys));
    EXPECT_TRUE(same_bits(a.moisture_flux.flux, b.moisture_flux.flux));
    EXPECT_TRUE(same_bits(a.moisture_flux.flux_prev, b.moisture_flux.flux_prev));
    EXPECT_TRUE(same_bits(a.domain_min, b.domain_min));
    EXPECT_TRUE(same_bits(a.domain_max, b.domain_max));
}

// a state with random bits in every array, including values a text format would round
template <class S = double>
SimStateOf<S> random_state(size_t n, bool has_moisture, bool has_plasticity, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    SimStateOf<S> s;
    s.time = 0.1 + 1e-17;
    s.step_count = 12345;
    s.moisture_lag = 3e-4 / 7;  // owed to the next solve (/moisture/interval)
    for (size_t i = 0; i < n; ++i) {
        s.id.push_back(int32_t((i * 7) % n));  // a permuted slot order
        s.x.push_back((Vec3(u(rng), u(rng), u(rng)) / 3.0).cast<S>());
        s.v.push_back((Vec3(u(rng), u(rng), u(rng)) * 1e-3).cast<S>());
        s.C.push_back((Mat3::Random() / 7.0).cast<S>());
        s.Fe.push_back((Mat3::Identity() + Mat3::Random() * 1e-9).cast<S>());
        s.J.push_back(1 + u(rng) * 1e-13);
        s.V0.push_back(1e-6 * (1 + u(rng)));
        s.mass.push_back(2e-6 * (1 + u(rng)));
        if (has_plasticity) {
            s.alpha.push_back(std::log(0.99) + u(rng) * 1e-3);
            s.strength.push_back(1 + 0.5 * u(rng));
            s.damage.push_back(0.5 + 0.5 * u(rng));
        }
        if (has_moisture) {
            s.theta.push_back(0.25 + 0.2 * u(rng));
            s.Jw.push_back(0.5 + 0.5 * u(rng));
        }
    }
    s.domain_min = Vec3(-1.0 / 3, 0, -0.7);
    s.domain_max = Vec3(1.0 / 3, 1.1, 0.7);
    return s;
}

template <class S = double>
SimCheckpointOf<S> sample_checkpoint(bool has_moisture, bool has_plasticity) {
    SimCheckpointOf<S> c;
    c.frame = 42;
    c.slice_hash = "0123456789abcdef";
    c.threads = 2;
    c.state = random_state<S>(101, has_moisture, has_plasticity, 7);
    if (has_moisture) {  // a flux history on three blocks, one with a key above INT32_MAX
        MoistureFluxHistory& h = c.state.moisture_flux;
        h.count = 2;
        h.dt = 1e-3 / 3;
        h.dt_prev = 1e-3 / 7;
        h.keys = {3u, 77u, 0xfffffff0u};
        for (size_t i = 0; i < h.keys.size() * 64; ++i) {
            h.flux.push_back(std::sin(double(i)) * 1e-9);
            h.flux_prev.push_back(std::cos(double(i)) / 3);
        }
    }
    c.totals.substeps = 999;
    c.totals.dt_min = 1.0 / 3e4;
    c.totals.dt_max = 2e-4;
    c.totals.cg_iterations = 4321;
    c.totals.cg_max = 17;
    c.totals.active_nodes_max = 5000;
    c.totals.allocated_nodes_max = 8192;
    c.totals.max_speed = 2.5;
    c.totals.retries = 3;
    return c;
}

// a tiny free-falling elastic block: 5x5x5 particles on a 0.025 m lattice, h = 0.05
SimModel small_model() {
    SimModel model;
    model.h = 0.05;
    model.elastic.youngs_modulus = 2000;
    model.elastic.poisson_ratio = 0.35;
    model.elastic.density = 1;
    model.initial_velocity = Vec3(0.3, -0.5, 0.1);
    model.ground = GroundParams{};
    model.ground->height = 0;
    model.time.fps = 96;  // ~24 substeps a frame: quick, yet several per frame
    return model;
}

template <class S = double>
SimStateOf<S> small_state(const SimModel& model) {
    std::vector<Vec3> X;
    std::vector<Real> V0;
    const double spacing = 0.025;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j)
            for (int k = 0; k < 5; ++k) {
                X.push_back(Vec3(i, j + 2, k) * spacing);
                V0.push_back(spacing * spacing * spacing);
            }
    return make_initial_state<S>(model, X, V0);
}

}  // namespace

TEST(SimCheckpoint, FileNames) {
    EXPECT_EQ(checkpoint_path("out/sim", 7).string(), "out/sim/checkpoint.0007.bin");
    const fs::path dir = temp_dir("names");
    for (int f : {12, 3, 100}) std::ofstream(checkpoint_path(dir, f)) << "x";
    std::ofstream(dir / "checkpoint.0005.bin.tmp") << "half-written";
    std::ofstream(dir / "particles.0004.vdb") << "not a checkpoint";
    EXPECT_EQ(list_checkpoint_frames(dir), (std::vector<int>{3, 12, 100}));
    fs::remove_all(dir);
}

TEST(SimCheckpoint, RoundTripIsBitwise) {
    const fs::path dir = temp_dir("roundtrip");
    for (const bool has_moisture : {false, true}) {
        for (const bool has_plasticity : {false, true}) {
            const SimCheckpoint saved = sample_checkpoint(has_moisture, has_plasticity);
            const fs::path file = checkpoint_path(dir, saved.frame);
            write_sim_checkpoint(file, saved);
            const SimCheckpoint read = read_sim_checkpoint(file);
            EXPECT_EQ(read.frame, saved.frame);
            EXPECT_EQ(read.slice_hash, saved.slice_hash);
            EXPECT_EQ(read.threads, saved.threads);
            expect_same_state(saved.state, read.state);
            EXPECT_EQ(read.state.theta.empty(), !has_moisture);
            EXPECT_EQ(read.state.alpha.empty(), !has_plasticity);
            EXPECT_EQ(read.totals.substeps, saved.totals.substeps);
            EXPECT_EQ(read.totals.dt_min, saved.totals.dt_min);
            EXPECT_EQ(read.totals.dt_max, saved.totals.dt_max);
            EXPECT_EQ(read.totals.cg_iterations, saved.totals.cg_iterations);
            EXPECT_EQ(read.totals.cg_max, saved.totals.cg_max);
            EXPECT_EQ(read.totals.active_nodes_max, saved.totals.active_nodes_max);
            EXPECT_EQ(read.totals.allocated_nodes_max, saved.totals.allocated_nodes_max);
            EXPECT_EQ(read.totals.max_speed, saved.totals.max_speed);
            EXPECT_EQ(read.totals.retries, saved.totals.retries);
            EXPECT_FALSE(fs::exists(file.string() + ".tmp"));
        }
    }
    fs::remove_all(dir);
}

// random bit patterns (NaNs, denormals and infinities included) in each of an array's bytes
template <class T>
void fill_random_bits(std::vector<T>& values, size_t n, std::mt19937_64& rng) {
    values.resize(n);
    for (size_t i = 0; i < n; ++i) {
        unsigned char* bytes = reinterpret_cast<unsigned char*>(&values[i]);
        for (size_t b = 0; b < sizeof(T); ++b) bytes[b] = static_cast<unsigned char>(rng());
    }
}

// the state's particle arrays by name, as raw bytes
std::map<std::string, std::string> array_bytes(const SimState& s) {
    std::map<std::string, std::string> out;
    s.for_each_array([&](const char* name, const auto& array, ArrayPresence) {
        out[name].assign(reinterpret_cast<const char*>(array.data()),
                         array.size() * sizeof(array[0]));
    });
    return out;
}

TEST(SimCheckpoint, EveryTableArrayRoundTripsBitForBit) {
    // driven by MC_SIM_STATE_ARRAYS, so an array added to the table is covered without editing this
    // test
    const fs::path dir = temp_dir("table");
    for (const bool is_optional_empty : {false, true}) {
        std::mt19937_64 rng(is_optional_empty ? 7 : 11);
        SimCheckpoint saved = sample_checkpoint(true, true);
        const size_t n = 37;
        size_t arrays = 0;
        saved.state.for_each_array([&](const char*, auto& array, ArrayPresence presence) {
            ++arrays;
            if (presence == ArrayPresence::Optional && is_optional_empty)
                array.clear();
            else
                fill_random_bits(array, n, rng);
        });
        ASSERT_GE(arrays, 13u);
        const fs::path file = checkpoint_path(dir, saved.frame);
        write_sim_checkpoint(file, saved);
        const SimCheckpoint read = read_sim_checkpoint(file);
        const auto expected = array_bytes(saved.state), actual = array_bytes(read.state);
        ASSERT_EQ(expected.size(), arrays);
        for (const auto& [name, bytes] : expected) {
            ASSERT_TRUE(actual.count(name)) << name;
            EXPECT_EQ(actual.at(name).size(), bytes.size()) << name;
            EXPECT_TRUE(actual.at(name) == bytes) << name << " differs after the round trip";
        }
        expect_same_state(saved.state, read.state);
    }
    fs::remove_all(dir);
}

TEST(SimCheckpoint, AFloatStateRoundTripsBitwiseAndOnlyIntoAFloatRun) {
    const fs::path dir = temp_dir("float");
    const SimCheckpointOf<float> saved = sample_checkpoint<float>(true, true);
    const fs::path file = checkpoint_path(dir, saved.frame);
    write_sim_checkpoint(file, saved);
    expect_same_state(saved.state, read_sim_checkpoint<float>(file).state);
    // a float state is not a double run's, nor a double state a float run's
    try {
        read_sim_checkpoint<double>(file);
        ADD_FAILURE() << "a double run read a float checkpoint";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("precision = \"float\""), std::string::npos)
            << e.what();
    }
    const fs::path double_file = checkpoint_path(dir, 43);
    write_sim_checkpoint(double_file, sample_checkpoint<double>(true, true));
    EXPECT_THROW(read_sim_checkpoint<float>(double_file), InputError);

    // a float checkpoint whose arrays hold a value no float has (a damaged or forged file that
    // passes its checksum) is refused by array and index, not rounded
    Checkpoint raw = read_checkpoint(double_file);
    raw.meta_string["precision"] = "float";
    write_checkpoint(double_file, raw);
    try {
        read_sim_checkpoint<float>(double_file);
        ADD_FAILURE() << "a double value was read into a float state";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(": x[0] = "), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

TEST(SimCheckpoint, SavesEveryStateField) {
    // SimState's size changes when a field is added; the checkpoint must then save it too
    // (sim_checkpoint.cpp), or a resumed run silently diverges. Update this number with it.
    constexpr size_t kVectors = 14, kVec3s = 2;
    constexpr size_t kExpected = 2 * sizeof(double) + sizeof(int64_t) +
                                 kVectors * sizeof(std::vector<Real>) + kVec3s * sizeof(Vec3) +
                                 sizeof(MoistureFluxHistory) + sizeof(Scratch<SimWorkspace>);
    EXPECT_EQ(sizeof(SimState), kExpected)
        << "SimState gained or lost a field: update sim_checkpoint.cpp";
}

TEST(SimCheckpoint, CorruptionAndTruncationAreRefused) {
    const fs::path dir = temp_dir("corrupt");
    const fs::path file = checkpoint_path(dir, 1);
    write_sim_checkpoint(file, sample_checkpoint(true, true));
    const auto size = fs::file_size(file);

    // one flipped bit in the middle of the particle data
    const fs::path flipped = dir / "flipped.bin";
    fs::copy_file(file, flipped);
    {
        std::fstream f(flipped, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(std::streamoff(size / 2));
        char byte = 0;
        f.read(&byte, 1);
        byte ^= 0x10;
        f.seekp(std::streamoff(size / 2));
        f.write(&byte, 1);
    }
    try {
        read_sim_checkpoint(flipped);
        ADD_FAILURE() << "a corrupt checkpoint was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("flipped.bin"), std::string::npos) << e.what();
    }

    // a file cut short (a killed writer that bypassed the atomic rename)
    const fs::path cut = dir / "cut.bin";
    fs::copy_file(file, cut);
    fs::resize_file(cut, size - 100);
    EXPECT_THROW(read_sim_checkpoint(cut), InputError);
    EXPECT_THROW(read_sim_checkpoint(dir / "missing.bin"), InputError);
    fs::remove_all(dir);
}

// the stepping logic is thread-agnostic: one thread keeps these quick on a loaded machine
class SimFrameStepper : public ::testing::Test {
protected:
    void SetUp() override { set_thread_count(1); }
    void TearDown() override { set_thread_count(0); }
};

TEST_F(SimFrameStepper, FramesEndExactlyOnTheFrameTime) {
    const SimModel model = small_model();
    SimState state = small_state(model);
    SimTotals totals;
    RetryingStepper stepper;
    for (int frame = 1; frame <= 3; ++frame) {
        const int substeps = advance_frame(model, state, frame, stepper, totals);
        EXPECT_GE(substeps, 1);
        EXPECT_EQ(state.time, double(frame) / model.time.fps) << "frame " << frame;
    }
    EXPECT_EQ(state.step_count, totals.substeps);
    EXPECT_LE(totals.dt_max, stable_dt(model, small_state(model)) * (1 + 1e-12));
    EXPECT_GT(totals.dt_min, 0);
}

TEST_F(SimFrameStepper, FixedStepSplitsTheRemainderInsteadOfASliver) {
    SimModel model = small_model();
    // a frame of 2.5 stable steps: dt, then 0.75 dt twice (dt half the elastic bound, so the
    // physics stays stable and only the stepping logic is under test)
    model.time.fps = 1.0 / (2.5 * 0.5 * elastic_dt_bound(model));
    const double frame_length = 1.0 / model.time.fps;
    model.time.dt_fixed = frame_length / 2.5;
    SimState state = small_state(model);
    SimTotals totals;
    RetryingStepper stepper;
    EXPECT_EQ(advance_frame(model, state, 1, stepper, totals), 3);
    EXPECT_EQ(totals.dt_max, model.time.dt_fixed);
    EXPECT_NEAR(totals.dt_min, 0.75 * model.time.dt_fixed, 1e-12 * frame_length);
    EXPECT_EQ(state.time, frame_length);
}

TEST_F(SimFrameStepper, CollapsedStepNamesFrameAndParticle) {
    const SimModel model = small_model();
    SimState state = small_state(model);
    SimTotals totals;
    // one particle so fast that the velocity bound on dt is ~1e-302 s
    size_t slot = 0;
    while (state.id[slot] != 17) ++slot;
    state.v[slot] = Vec3(0, 1e300, 0);
    try {
        RetryingStepper stepper;
        advance_frame(model, state, 1, stepper, totals);
        ADD_FAILURE() << "a collapsed time step went unnoticed";
    } catch (const RuntimeError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("frame 1 substep 1"), std::string::npos) << msg;
        EXPECT_NE(msg.find("particle 17"), std::string::npos) << msg;
    }
}

// runs frames 1-3 straight and with a checkpoint after frame 1 read back into a fresh state, with
// a state of precision S
template <class S = double>
void expect_bitwise_resume(const SimModel& model, const fs::path& dir) {
    // uninterrupted: frames 1-3
    SimStateOf<S> straight = small_state<S>(model);
    SimTotals straight_totals;
    RetryingStepperOf<S> straight_stepper;
    for (int frame = 1; frame <= 3; ++frame)
        advance_frame(model, straight, frame, straight_stepper, straight_totals);

    // interrupted after frame 1: saved, read back into a fresh state (no workspace), continued
    SimStateOf<S> first_part = small_state<S>(model);
    SimCheckpointOf<S> saved;
    RetryingStepperOf<S> first_stepper;
    advance_frame(model, first_part, 1, first_stepper, saved.totals);
    saved.frame = 1;
    saved.state = first_part;
    write_sim_checkpoint(checkpoint_path(dir, 1), saved);
    SimCheckpointOf<S> resumed = read_sim_checkpoint<S>(checkpoint_path(dir, 1));
    EXPECT_EQ(resumed.state.workspace, nullptr);
    RetryingStepperOf<S> resumed_stepper;
    for (int frame = 2; frame <= 3; ++frame)
        advance_frame(model, resumed.state, frame, resumed_stepper, resumed.totals);

    EXPECT_GT(straight.step_count, 32);
    expect_same_state(straight, resumed.state);
    EXPECT_EQ(resumed.totals.substeps, straight_totals.substeps);
    EXPECT_EQ(resumed.totals.dt_min, straight_totals.dt_min);
    EXPECT_EQ(resumed.totals.retries, straight_totals.retries);
    fs::remove_all(dir);
}

TEST_F(SimFrameStepper, ResumeFromCheckpointIsBitwiseIdentical) {
    // bitwise determinism is promised per thread count: test the parallel path
    set_thread_count(2);
    for (bool moisture : {false, true}) {
        SCOPED_TRACE(moisture ? "with moisture" : "without moisture");
        SimModel model = small_model();
        // ~12 substeps a frame: 3 frames cross the particle re-sorts (every 16)
        model.time.fps = 192;
        // with moisture the CG's flux history carries from step to step outside the state
        if (moisture) model.moisture = MoistureParams{};
        expect_bitwise_resume(model, temp_dir(moisture ? "resume_moist" : "resume"));
        expect_bitwise_resume<float>(model,
                                     temp_dir(moisture ? "resume_moist_float" : "resume_float"));
    }
}

// a fixed dt 3x the elastic bound (what the shot loader refuses) inverts particles: the failed
// substeps are rolled back and redone at a smaller dt, and the run completes; the retries
// restart with every frame, so a run resumed from a checkpoint takes the same steps
TEST_F(SimFrameStepper, FailedSubstepsAreRetriedAndResumeStaysBitwise) {
    SimModel model = small_model();
    model.time.dt_fixed = 3 * elastic_dt_bound(model);
    model.time.fps = 1 / (20 * model.time.dt_fixed);  // 20 fixed steps a frame

    // without retries the run stops: the case is one that needs them
    SimState plain = small_state(model);
    EXPECT_THROW(for (int i = 0; i < 60; ++i) step(model, plain, stable_dt(model, plain)),
                 RuntimeError);

    SimState state = small_state(model);
    SimTotals totals;
    RetryingStepper stepper;
    for (int frame = 1; frame <= 3; ++frame) {
        advance_frame(model, state, frame, stepper, totals);
        EXPECT_EQ(state.time, double(frame) / model.time.fps) << "frame " << frame;
    }
    EXPECT_GT(totals.retries, 0);
    EXPECT_EQ(totals.retries, stepper.retries());
    EXPECT_LE(totals.dt_min, model.time.dt_fixed / 2);  // halved
    EXPECT_EQ(totals.dt_max, model.time.dt_fixed);      // and grown back
    EXPECT_EQ(state.step_count, totals.substeps);       // rolled-back steps are not counted
    for (size_t p = 0; p < state.size(); ++p) {
        ASSERT_TRUE(state.x[p].allFinite() && state.J[p] > 0) << "particle " << state.id[p];
    }

    expect_bitwise_resume(model, temp_dir("resume_retried"));
}
