#include "pipeline/stages/sim/sim_stage.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/io/checksum.h"
#include "pipeline/io/manifest.h"
#include "pipeline/io/points_io.h"
#include "pipeline/shot/measured_body.h"
#include "pipeline/stages/sim/sim_checkpoint.h"
#include "pipeline/stages/sim/sim_frame_stepper.h"
#include "pipeline/stages/sim/sim_progress.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"
#include "sim/mpm/simulation.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

constexpr int kCheckpointsKept = 2;  // the newest two: one may be mid-write when a run is killed

/// The rest state mc-init produced.
struct InitParticles {
    std::vector<Vec3> X;         // rest positions [m], index = particle id
    std::vector<Real> V0;        // rest volumes [m^3]
    std::vector<Real> strength;  // p0 multipliers of a heterogeneous soil, else empty
    nlohmann::json manifest;
};

// read DIR/init/ and check that it was made from this shot's init slice
InitParticles read_init(const fs::path& init_dir, const Shot& shot) {
    InitParticles init;
    init.manifest = read_current_manifest(init_dir, shot.slice_hash(Stage::Init));

    const fs::path particles_file = init_dir / "particles.vdb";
    RecordedChecksums(init.manifest, init_dir / "manifest.json").verify(particles_file);
    const PointCloud cloud = read_points(particles_file);
    const std::vector<float>* volume0 = cloud.find_float("volume0");
    if (!volume0)
        throw InputError(particles_file.string() +
                         ": no volume0 attribute: expected the rest volume "
                         "of every particle (re-run mc-init)");
    if (volume0->size() != cloud.P.size() || cloud.id.size() != cloud.P.size())
        throw InputError(particles_file.string() + ": " + std::to_string(cloud.P.size()) +
                         " positions but " + std::to_string(cloud.id.size()) + " ids and " +
                         std::to_string(volume0->size()) + " volume0 values: expected one each");
    if (cloud.P.empty()) throw InputError(particles_file.string() + ": no particles");
    for (size_t i = 0; i < cloud.id.size(); ++i) {
        if (cloud.id[i] != int32_t(i))
            throw InputError(particles_file.string() + ": particle ids are not 0.." +
                             std::to_string(cloud.P.size() - 1) + " (slot " + std::to_string(i) +
                             " has id " + std::to_string(cloud.id[i]) + ")");
        if (!((*volume0)[i] > 0))
            throw InputError(particles_file.string() + ": particle " + std::to_string(i) +
                             " has volume0 = " + std::to_string((*volume0)[i]) + ": expected > 0");
    }
    init.X.reserve(cloud.P.size());
    init.V0.reserve(cloud.P.size());
    for (size_t i = 0; i < cloud.P.size(); ++i) {
        init.X.push_back(cloud.P[i].cast<Real>());
        init.V0.push_back((*volume0)[i]);
    }
    // the heterogeneous strength is the shot's (/init/strength_field, in the init slice checked
    // above); make_initial_state checks its values
    if (shot.init.strength_field && shot.sim.nacc) {
        const std::vector<float>* strength = cloud.find_float("strength");
        if (!strength || strength->size() != cloud.P.size())
            throw InputError(particles_file.string() +
                             ": no strength attribute with one value per particle, "
                             "but the shot sets /init/strength_field: re-run mc-init");
        init.strength.assign(strength->begin(), strength->end());
    }
    return init;
}

// a point [x, y, z] a manifest's object holds at `key`, or nullopt
std::optional<Vec3> manifest_point(const json& object, const char* key) {
    if (!object.is_object() || !object.contains(key)) return std::nullopt;
    const json& value = object[key];
    if (!value.is_array() || value.size() != 3) return std::nullopt;
    Vec3 p;
    for (int d = 0; d < 3; ++d) {
        if (!value[d].is_number()) return std::nullopt;
        p[d] = value[d].get<double>();
    }
    return p;
}

// a mesh body's bounds, which the loader cannot know, as mc-init recorded them: the ground is not
// in the init slice, so one edited since mc-init ran is checked here, as the loader checks a box's
void check_mesh_body(const Shot& shot, const fs::path& init_dir, const json& init_manifest) {
    if (shot.init.type != SourceType::Mesh || !init_manifest.contains("mesh_bounds")) return;
    const json& bounds = init_manifest["mesh_bounds"];
    const std::optional<Vec3> lo = manifest_point(bounds, "min"),
                              hi = manifest_point(bounds, "max");
    const fs::path manifest = init_dir / "manifest.json";
    if (!lo || !hi)
        throw InputError(manifest.string() + ": damaged: /mesh_bounds = " + bounds.dump() +
                         ": expected {\"min\": [x, y, z], \"max\": [x, y, z]}: re-run mc-init");
    MeasuredBody body = placed_mesh_body(shot.init.mesh.path, *lo, *hi);
    body.what += " (" + manifest.string() + ")";
    check_measured_body(shot, body);
}

// the frame number in a file name "<stem>.<digits>.<ext>", or -1
int frame_of(const fs::path& file, const std::string& stem, const std::string& ext) {
    static const std::regex pattern(R"(^([A-Za-z_]+)\.(\d+)\.([a-z]+)$)");
    std::smatch m;
    const std::string name = file.filename().string();
    if (!std::regex_match(name, m, pattern) || m[1] != stem || m[3] != ext) return -1;
    return std::stoi(m[2]);
}

void remove_file(const fs::path& file) {
    std::error_code ec;
    fs::remove(file, ec);
    if (ec) throw RuntimeError(file.string() + ": cannot remove: " + ec.message());
}

// remove this stage's own files in DIR/sim/: frame caches and checkpoints after frame
// `keep_through` (all of them for -1), half-written temporaries, and the manifest
void clear_sim_dir(const fs::path& sim_dir, int keep_through) {
    for (const fs::directory_entry& entry : fs::directory_iterator(sim_dir)) {
        const fs::path& file = entry.path();
        const int cache_frame = frame_of(file, "particles", "vdb");
        const int checkpoint_frame = frame_of(file, "checkpoint", "bin");
        if (file.extension() == ".tmp" || file.filename() == "manifest.json" ||
            cache_frame > keep_through || checkpoint_frame > keep_through)
            remove_file(file);
    }
}

// what a failed run leaves for --resume, appended to its one-line error
std::string kept_frames_note(int first, int kept, const fs::path& sim_dir) {
    return (kept >= first ? "; frames " + std::to_string(first) + "-" + std::to_string(kept) +
                                " are kept in " + sim_dir.string()
                          : std::string()) +
           " (no manifest written)";
}

// a frame cache a resume may keep: the bytes whose checksum the checkpoint recorded (a cache
// damaged since, missing, or not recorded is not kept: the frames from it on are simulated again)
bool is_intact_frame(const fs::path& file, int frame,
                     const std::map<int, std::string>& cache_crc32) {
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) return false;
    std::string problem;
    const auto recorded = cache_crc32.find(frame);
    if (recorded == cache_crc32.end()) {
        problem = file.string() + ": no checksum recorded for it";
    } else {
        try {
            const std::string found = file_crc32(file);
            if (found == recorded->second) return true;
            problem = file.string() + ": damaged: its CRC-32 is " + found +
                      ", the checkpoint records " + recorded->second;
        } catch (const InputError& e) {
            problem = e.what();
        }
    }
    log::warn("bad frame cache", problem + ": the checkpoints after it are not used");
    return false;
}

// the newest checkpoint that is intact, made from this shot's sim slice, for these particles,
// not past the last frame, and whose in-range frames are all on disk
template <class S>
std::optional<SimCheckpointOf<S>> find_resume_checkpoint(const fs::path& sim_dir, const Shot& shot,
                                                         size_t n_particles, int first, int last) {
    std::vector<int> frames = list_checkpoint_frames(sim_dir);
    std::reverse(frames.begin(), frames.end());
    for (const int c : frames) {
        const fs::path file = checkpoint_path(sim_dir, c);
        if (c > last) {
            log::info(file.string() + ": past the last frame " + std::to_string(last) +
                      ", not used");
            continue;
        }
        SimCheckpointOf<S> checkpoint;
        try {
            checkpoint = read_sim_checkpoint<S>(file);
        } catch (const InputError& e) {
            log::warn("bad checkpoint", std::string(e.what()) + ": skipped");
            continue;
        }
        if (checkpoint.slice_hash != shot.slice_hash(Stage::Sim)) {
            log::warn("stale checkpoint", file.string() +
                                              ": written for another version of the shot's "
                                              "sim settings: skipped");
            continue;
        }
        if (checkpoint.state.size() != n_particles || checkpoint.frame != c) {
            log::warn("bad checkpoint",
                      file.string() + ": holds " + std::to_string(checkpoint.state.size()) +
                          " particles at frame " + std::to_string(checkpoint.frame) +
                          ", expected " + std::to_string(n_particles) + " at frame " +
                          std::to_string(c) + ": skipped");
            continue;
        }
        bool has_frames = true;
        for (int f = first; f <= c && has_frames; ++f)
            has_frames = is_intact_frame(frame_path(sim_dir, "particles", f, "vdb"), f,
                                         checkpoint.cache_crc32);
        if (!has_frames) {
            log::info(file.string() + ": some frames before it are missing or damaged, not used");
            continue;
        }
        if (checkpoint.threads != thread_count())
            log::warn("checkpoint threads",
                      file.string() + ": written with " + std::to_string(checkpoint.threads) +
                          " threads, resuming with " + std::to_string(thread_count()) +
                          ": caches will not be bitwise identical to an uninterrupted run");
        return checkpoint;
    }
    return std::nullopt;
}

// keep only the newest kCheckpointsKept checkpoints
void prune_checkpoints(const fs::path& sim_dir) {
    const std::vector<int> frames = list_checkpoint_frames(sim_dir);
    for (size_t i = 0; i + kCheckpointsKept < frames.size(); ++i)
        remove_file(checkpoint_path(sim_dir, frames[i]));
}

std::vector<std::string> attribute_names(const PointCloud& cloud) {
    std::vector<std::string> names = {"P", "id"};
    for (const auto& [name, values] : cloud.vec3s) names.push_back(name);
    for (const auto& [name, values] : cloud.floats) names.push_back(name);
    for (const auto& [name, values] : cloud.mat3s) names.push_back(name);
    return names;
}

// the manifest's records of frames first..last's caches, with the checksums every reader verifies
json cache_records(const fs::path& sim_dir, int first, int last,
                   const std::map<int, std::string>& cache_crc32) {
    json records = json::array();
    for (int f = first; f <= last; ++f)
        records.push_back({{"frame", f},
                           {"file", frame_path(sim_dir, "particles", f, "vdb").filename().string()},
                           {"crc32", cache_crc32.at(f)}});
    return records;
}

// the frames a run writes: --frames, within the shot's, or the shot's (the loader checked
// 1 <= /frames/start <= /frames/end)
std::pair<int, int> frames_to_write(const Shot& shot, const StageOptions& options) {
    const TimeParams& time = shot.sim.time;
    const FrameRange frames = frames_to_process(options, {time.frame_start, time.frame_end},
                                                shot.path + " (/frames/start, /frames/end)");
    return {frames.first, frames.last};
}

// what a run carries from frame to frame, and what its manifest reports
template <class S>
struct SimRun {
    SimStateOf<S> state;
    SimTotals totals;
    std::map<int, std::string> cache_crc32;  // of the frame caches on disk, by frame
    int done_frame = 0;                      // the state is at the end of this frame
    bool resumed = false;                    // the state came from a checkpoint (--resume)
    int64_t substeps_before = 0;             // totals.substeps when this run started
    int64_t retries_before = 0;              // totals.retries when this run started
    double step_seconds = 0;                 // in advance_frame only: the rate's denominator
    StepPhaseSeconds phase_seconds;          // this run's accepted steps, by phase (wall)
    int64_t state_bytes = 0;                 // the state and stepper's largest footprint
    std::vector<std::string> cached_attributes;
};

// a float state's range (sim/mpm/simulation.h): refused by the shot's key, before any output
template <class S>
void check_state_precision(const Shot& shot, const SimStateOf<S>& state) {
    if constexpr (std::is_same_v<S, float>) {
        const std::string problem =
            float_state_range_problem(shot.sim, state.domain_min, state.domain_max);
        if (!problem.empty())
            throw InputError(shot.path + ": /sim/precision = \"float\": " + problem);
    }
}

// the starting state: a checkpoint (--resume) or the rest state at t = 0 (end of "frame 0");
// clears what a run must not leave behind
template <class S>
SimRun<S> start_run(const Shot& shot, const SimStageOptions& sim_options, const InitParticles& init,
                    const fs::path& sim_dir, int first, int last) {
    std::optional<SimCheckpointOf<S>> resumed;
    if (sim_options.resume) {
        resumed = find_resume_checkpoint<S>(sim_dir, shot, init.X.size(), first, last);
        if (!resumed)
            log::info("--resume: no usable checkpoint in " + sim_dir.string() +
                      ", starting from t = 0");
    }
    SimRun<S> run;
    if (resumed) {
        run.state = std::move(resumed->state);
        run.totals = resumed->totals;
        run.cache_crc32 = std::move(resumed->cache_crc32);
        run.done_frame = resumed->frame;
        run.resumed = true;
        log::info("resuming from " + checkpoint_path(sim_dir, run.done_frame).string());
    } else {
        run.state = make_initial_state<S>(shot.sim, init.X, init.V0, init.strength);
    }
    check_state_precision(shot, run.state);
    std::error_code ec;
    fs::create_directories(sim_dir, ec);
    if (ec) throw RuntimeError(sim_dir.string() + ": cannot create: " + ec.message());
    // the old manifest goes first, so make sees an incomplete stage until this run succeeds;
    // stale frames and checkpoints (after the resumed one) and half-written temporaries too
    clear_sim_dir(sim_dir, run.resumed ? run.done_frame : -1);
    run.substeps_before = run.totals.substeps;
    run.retries_before = run.totals.retries;
    run.state_bytes = state_memory_bytes(run.state);
    return run;
}

// the frame's cache; a failure (a full disk) keeps what is done for --resume
template <class S>
void write_frame_cache(const SimModel& model, SimRun<S>& run, const fs::path& sim_dir, int frame,
                       int frame_substeps, int first, SimProgress& progress) {
    ParticleFrame particles = state_to_frame(model, run.state, model.cache);
    particles.frame = frame;
    particles.time = run.state.time;
    particles.substeps = frame_substeps;
    const PointCloud cloud = frame_to_points(particles);  // with the cache's metadata
    try {
        const fs::path cache = frame_path(sim_dir, "particles", frame, "vdb");
        write_points(cache, cloud, model.h);
        run.cache_crc32[frame] = file_crc32(cache);
    } catch (const RuntimeError& e) {
        progress.finish();
        throw RuntimeError(std::string(e.what()) + kept_frames_note(first, frame - 1, sim_dir));
    }
    if (run.cached_attributes.empty()) run.cached_attributes = attribute_names(cloud);
}

// a full-precision checkpoint of the state at the end of `frame`, then the oldest pruned
template <class S>
void write_frame_checkpoint(const Shot& shot, SimRun<S>& run, const fs::path& sim_dir, int frame,
                            int first, SimProgress& progress) {
    SimCheckpointOf<S> checkpoint;
    checkpoint.frame = frame;
    checkpoint.slice_hash = shot.slice_hash(Stage::Sim);
    checkpoint.threads = thread_count();
    checkpoint.totals = run.totals;
    checkpoint.cache_crc32 = run.cache_crc32;
    // lend the state to the checkpoint instead of copying it (it can be GBs)
    checkpoint.state = std::move(run.state);
    try {
        write_sim_checkpoint(checkpoint_path(sim_dir, frame), checkpoint);
    } catch (const RuntimeError& e) {
        progress.finish();
        throw RuntimeError(std::string(e.what()) + kept_frames_note(first, frame, sim_dir));
    }
    run.state = std::move(checkpoint.state);
    prune_checkpoints(sim_dir);
}

// frames done_frame + 1 .. last: substeps, caches (from `first` on) and checkpoints
template <class S>
void simulate_frames(const Shot& shot, const SimStageOptions& sim_options, SimRun<S>& run,
                     const fs::path& sim_dir, int first, int last, bool verbose) {
    const SimModel& model = shot.sim;
    SimStateOf<S>& state = run.state;
    SimProgress progress(int64_t(state.size()), first, last, state.time,
                         frame_end_time(model, last), verbose, stderr, is_terminal(stderr));
    WallTimer step_timer;
    RetryingStepperOf<S> stepper;
    for (int frame = run.done_frame + 1; frame <= last; ++frame) {
        if (frame == sim_options.inject_nan_at_frame) {
            const auto slot = std::find(state.id.begin(), state.id.end(), 0) - state.id.begin();
            state.v[size_t(slot)].setConstant(std::numeric_limits<S>::quiet_NaN());
        }

        // substep to the frame's end
        int frame_substeps = 0;
        try {
            step_timer.reset();
            frame_substeps = advance_frame(
                model, state, frame, stepper, run.totals,
                [&](int k) {
                    progress.substep(frame, k, state.time,
                                     run.totals.substeps - run.substeps_before,
                                     run.step_seconds + step_timer.seconds());
                },
                [&](const StepPhaseSeconds& seconds) { run.phase_seconds += seconds; });
            run.step_seconds += step_timer.seconds();
        } catch (const RuntimeError& e) {
            progress.finish();
            throw RuntimeError(std::string(e.what()) + kept_frames_note(first, frame - 1, sim_dir));
        }
        run.state_bytes =
            std::max(run.state_bytes, state_memory_bytes(state) + stepper.memory_bytes());

        // the frame's cache (frames before the requested range are simulated, not written)
        if (frame >= first)
            write_frame_cache(model, run, sim_dir, frame, frame_substeps, first, progress);

        // a checkpoint every checkpoint_every frames (by absolute frame number, so a resumed run
        // checkpoints the same frames as an uninterrupted one)
        if (model.checkpoint_every > 0 && frame % model.checkpoint_every == 0)
            write_frame_checkpoint(shot, run, sim_dir, frame, first, progress);
        progress.frame_done(frame, frame_substeps, state.time,
                            run.totals.substeps - run.substeps_before, run.step_seconds);
    }
    progress.finish();
}

// the run's particle-steps per second of stepping
template <class S>
double step_rate(const SimRun<S>& run) {
    const int64_t run_substeps = run.totals.substeps - run.substeps_before;
    return run.step_seconds > 0 ? double(run_substeps) * double(run.state.size()) / run.step_seconds
                                : 0;
}

template <class S>
json sim_manifest(const Shot& shot, const fs::path& out, const InitParticles& init,
                  const SimRun<S>& run, int first, int last, double wall_seconds) {
    const SimModel& model = shot.sim;
    const SimTotals& totals = run.totals;
    const fs::path sim_dir = out / "sim";
    const size_t n = init.X.size();
    const double cg_mean =
        totals.substeps > 0 ? double(totals.cg_iterations) / double(totals.substeps) : 0;
    json m = make_manifest("sim", shot.path, shot.slice_hash(Stage::Sim));
    m["inputs"] = {
        {"init",
         {{"dir", (out / "init").string()}, {"slice_hash", manifest_slice_hash(init.manifest)}}}};
    m["frames"] = {
        {"first", first}, {"last", last}, {"count", last - first + 1}, {"fps", model.time.fps}};
    m["particles"] = n;
    m["threads"] = thread_count();
    m["precision"] = state_precision_name<S>();
    m["resumed_from_frame"] = run.resumed ? json(run.done_frame) : json(nullptr);
    m["wall_seconds"] = wall_seconds;
    m["step_loop_seconds"] = run.step_seconds;
    // where the accepted steps' wall time went (StepPhaseSeconds; a step redone after a rollback
    // counts each time it was accepted); the rest of step_loop_seconds is the stable dt, the
    // rollback copies and the attempts that failed their checks
    const StepPhaseSeconds& ph = run.phase_seconds;
    m["step_phase_seconds"] = {{"bin", ph.bin},
                               {"p2g", ph.p2g},
                               {"grid", ph.grid},
                               {"moisture", ph.moisture},
                               {"g2p", ph.g2p}};
    m["substeps_this_run"] = totals.substeps - run.substeps_before;
    m["particle_steps_per_second"] = step_rate(run);
    m["substeps"] = totals.substeps;
    m["dt"] = {{"min", totals.dt_min}, {"max", totals.dt_max}};
    m["max_speed"] = totals.max_speed;
    m["retries"] = totals.retries;
    m["grid_nodes"] = {{"active_max", totals.active_nodes_max},
                       {"allocated_max", totals.allocated_nodes_max}};
    m["moisture"] = model.moisture.has_value();
    m["cg_iterations"] = {
        {"mean_per_substep", cg_mean}, {"max", totals.cg_max}, {"total", totals.cg_iterations}};
    m["peak_memory_bytes"] = peak_rss_bytes();
    m["state_bytes"] = run.state_bytes;
    m["bytes_per_particle"] = double(run.state_bytes) / double(n);
    m["allocated"] = {{"moisture_grid", model.moisture.has_value()},
                      {"theta", !run.state.theta.empty()},
                      {"Jw", !run.state.Jw.empty()},
                      {"plasticity", !run.state.alpha.empty()}};
    m["cached_attributes"] = run.cached_attributes;
    m["caches"] = cache_records(sim_dir, first, last, run.cache_crc32);
    m["checkpoint_every"] = model.checkpoint_every;
    std::vector<std::string> checkpoints;
    for (const int c : list_checkpoint_frames(sim_dir))
        checkpoints.push_back(checkpoint_path(sim_dir, c).filename().string());
    m["checkpoints"] = checkpoints;
    return m;
}

// the stage with a state of precision S (/sim/precision)
template <class S>
int run_sim_stage_in(const Shot& shot, const StageOptions& options,
                     const SimStageOptions& sim_options) {
    WallTimer wall;
    const SimModel& model = shot.sim;
    const fs::path out(options.out);
    const fs::path sim_dir = out / "sim";

    // the frames to write, the rest state, the starting state
    const std::pair<int, int> frames = frames_to_write(shot, options);
    const int first = frames.first, last = frames.second;
    // the testing aid's frame, like --frames: one this run simulates, else it would never fire
    if (const int k = sim_options.inject_nan_at_frame; k != 0 && (k < first || k > last))
        throw UsageError(
            "--inject-nan-at-frame " + std::to_string(k) + ": outside the frames " +
            std::to_string(first) + "-" + std::to_string(last) + " this run simulates (" +
            (options.frame_range.is_set() ? "--frames " + options.frames + " of " : std::string()) +
            shot.path + " (/frames/start, /frames/end))");
    const InitParticles init = read_init(out / "init", shot);
    check_mesh_body(shot, out / "init", init.manifest);
    SimRun<S> run = start_run<S>(shot, sim_options, init, sim_dir, first, last);

    // the frames, then the manifest, last
    simulate_frames(shot, sim_options, run, sim_dir, first, last, !options.quiet);
    if (run.cached_attributes.empty())  // resumed past the last frame: name what the caches hold
        run.cached_attributes =
            attribute_names(frame_to_points(state_to_frame(model, run.state, model.cache)));
    write_manifest(sim_dir, sim_manifest(shot, out, init, run, first, last, wall.seconds()));

    const size_t n = init.X.size();
    char line[240];
    std::snprintf(
        line, sizeof line,
        "frames %d-%d: %lld substeps, %lld retried, %.3g M particle-steps/s, %.0f bytes/particle",
        first, last, (long long)(run.totals.substeps - run.substeps_before),
        (long long)(run.totals.retries - run.retries_before), step_rate(run) * 1e-6,
        double(run.state_bytes) / double(n));
    log::info(line);
    return 0;
}

}  // namespace

int run_sim_stage(const Shot& shot, const StageOptions& options,
                  const SimStageOptions& sim_options) {
    return with_state_precision(shot.sim.precision, [&](auto s) {
        return run_sim_stage_in<decltype(s)>(shot, options, sim_options);
    });
}

}  // namespace mudcrack
