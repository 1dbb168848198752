// Physical plausibility at load (build.h, check_plausible): values each inside their own range
// that together would stop a stage deep in its run, refused before any work with the key named.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "pipeline/init/lattice.h"
#include "pipeline/shot/build.h"

namespace mudcrack::spec {
namespace {

using nlohmann::json;

// OpenVDB's transforms refuse a voxel whose volume is within 1e-15 of zero ("ArithmeticError"):
// h = 1e-5 m is one; caches are written with voxels of h, the surfacing's grids finer still
constexpr Real kMinCellSize = 1e-4;  // [m]
// the MPM grid keys its 4^3-node blocks with 32 bits (sim/grid/sparse_grid.h)
constexpr double kMaxGridBlocks = 4.0e9;
// memory per particle of a step: the state, the workspace with its grid, the retry path's copy of
// the state (docs/measurements.md: 550 to 645 bytes), with room for the caches
constexpr double kBytesPerParticle = 1024;
// llvmpipe (OSMesa) allocates at most 1 GiB per render buffer (Mesa's LP_MAX_TEXTURE_SIZE); the
// multisampled colour buffer is the largest: 4 bytes x samples per pixel
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
constexpr double kMaxRenderBufferBytes = kGiB;
// a film frame [s]: a step too small for it is the step's fault, not the frame rate's
constexpr Real kUsualFrameLength = 1.0 / 24;

std::string g(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

// the time step a shot starts with, the largest of its terms that limits it, and that term's key
struct StepBound {
    Real dt = 0;
    std::string pointer, why;
};

StepBound smallest_step(const json& tree, const SimModel& sim, const Issues& issues) {
    const TimeParams& t = sim.time;
    if (t.dt_fixed > 0) return {t.dt_fixed, "/sim/dt", "the fixed step /sim/dt"};
    StepBound b{t.dt_max, "/sim/dt_max", "the largest step /sim/dt_max"};
    // the elastic bound with the lightest (dry) soil, as stable_dt computes it
    ElasticParams dry = sim.elastic;
    if (sim.moisture) dry.density = std::min(dry.density, dry.density * (1 - sim.moisture->eta));
    const Real elastic = t.cfl_elastic * sim.h / dry.wave_speed();
    if (!(elastic >= b.dt)) {
        // the value further from a soil's (about 1000 kg/m^3, 1 MPa) leads the message
        const bool is_density = std::abs(std::log10(sim.elastic.density / 1e3)) >
                                std::abs(std::log10(sim.elastic.youngs_modulus / 1e6));
        const std::string other = is_density ? "/material/youngs_modulus" : "/material/density";
        b = {elastic, is_density ? "/material/density" : "/material/youngs_modulus",
             "the elastic bound C_E h / c_p (c_p = " + g(dry.wave_speed()) + " m/s, with " + other +
                 " = " + issues.value_of(tree, other) + ")"};
    }
    // the speed it starts with, plus what gravity adds over one frame
    const Real v0 = sim.initial_velocity.norm(), fall = sim.gravity.norm() / t.fps;
    const Real velocity = t.cfl_velocity * sim.h / (v0 + fall);
    if (!(velocity >= b.dt)) {
        const bool is_gravity = fall > v0;
        b = {velocity, is_gravity ? "/sim/gravity" : "/source/initial_velocity",
             "the velocity bound C_v h / |v| (|v| = " + g(v0 + fall) + " m/s" +
                 (is_gravity ? " after falling for one frame" : "") + ")"};
    }
    return b;
}

// a step below the floor would never finish a frame (mc-sim would stop on its first substep)
void check_time_step(const json& tree, const SimModel& sim, Issues& issues) {
    if (issues.has("/material") || issues.has("/sim") || issues.has("/frames") ||
        issues.has("/source/initial_velocity"))
        return;
    const Real frame = 1 / sim.time.fps;
    const Real floor = kCollapsedDtFraction * frame;
    const StepBound b = smallest_step(tree, sim, issues);
    if (b.dt >= floor && std::isfinite(b.dt)) return;
    const std::string floor_text =
        "the floor " + g(kCollapsedDtFraction) + " x the frame length 1 / fps = " + g(floor) +
        " s: a frame would take more than " + g(1 / kCollapsedDtFraction) + " substeps";
    // the largest step allowed is below the floor while it would do for frames of a usual
    // length: the frames are too long
    const Real largest = sim.time.dt_fixed > 0 ? sim.time.dt_fixed : sim.time.dt_max;
    if (largest < floor && largest >= kCollapsedDtFraction * kUsualFrameLength) {
        issues.add("/frames/fps", issues.value_of(tree, "/frames/fps"),
                   "frames of " + g(frame) + " s: the largest time step " + g(largest) +
                       " s is below " + floor_text +
                       "; expected frames per second of simulated time (e.g. 24)");
        return;
    }
    issues.add(
        b.pointer, issues.value_of(tree, b.pointer),
        "gives a stable time step of " + g(b.dt) + " s (" + b.why + "), below " + floor_text);
}

// what the sim grid spans: the explicit domain, else the source's extent (a mesh's is unknown here)
bool grid_extent(const InitParams& init, const SimModel& sim, Vec3& extent) {
    if (!sim.domain.is_auto) {
        extent = sim.domain.max - sim.domain.min;
        return true;
    }
    if (init.type == SourceType::Box) {
        extent = init.box.max - init.box.min;
        return true;
    }
    if (init.type == SourceType::Heightfield) {
        const HeightfieldSource& hf = init.heightfield;
        extent = Vec3(hf.size.x(), hf.base + hf.amplitude + hf.image_height, hf.size.z());
        return true;
    }
    return false;
}

void check_cell_size(const json& tree, const InitParams& init, const SimModel& sim,
                     Issues& issues) {
    if (issues.has("/sim/h") || issues.has("/source") || issues.has("/colliders/domain")) return;
    if (sim.h < kMinCellSize) {
        issues.add("/sim/h", issues.value_of(tree, "/sim/h"),
                   "must be >= " + g(kMinCellSize) +
                       " (OpenVDB, which holds the caches, refuses voxels this small)",
                   "m");
        return;
    }
    Vec3 extent;
    if (!grid_extent(init, sim, extent)) return;
    double blocks = 1;
    for (int d = 0; d < 3; ++d)
        blocks *= std::ceil((extent[d] / sim.h + 2 * sim.domain.padding) / 4) + 2;
    if (blocks >= kMaxGridBlocks)
        issues.add("/sim/h", issues.value_of(tree, "/sim/h"),
                   "a grid over the domain's " + g(extent.x()) + " x " + g(extent.y()) + " x " +
                       g(extent.z()) + " m needs " + g(blocks) +
                       " blocks of 4^3 cells: must be < " + g(kMaxGridBlocks) +
                       "; raise /sim/h or shrink the domain",
                   "m");
}

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? double(pages) * double(page) : 0;
}

// the particle count a lattice source gives, against the machine's memory
void check_particle_memory(const json& tree, const InitParams& init, Issues& issues) {
    if (issues.has("/source")) return;
    double count = 0;
    std::string pointer;
    if (init.type == SourceType::Box) {
        const Vec3 cells = (init.box.max - init.box.min) / init.box.spacing;
        count =
            (std::round(cells.x()) + 1) * (std::round(cells.y()) + 1) * (std::round(cells.z()) + 1);
        pointer = "/source/box/spacing";
    } else if (init.type == SourceType::Heightfield) {
        const HeightfieldSource& hf = init.heightfield;
        const Real height = hf.base + hf.amplitude + hf.image_height;
        count = (hf.size.x() / hf.spacing + 1) * (hf.size.z() / hf.spacing + 1) *
                (height / hf.spacing + 1);
        pointer = "/source/heightfield/spacing";
    }
    // past kMaxInitParticles mc-init refuses the count itself, naming it whole
    const double memory = physical_memory_bytes();
    if (count == 0 || count > kMaxInitParticles || memory == 0 ||
        count * kBytesPerParticle <= memory)
        return;
    issues.add(pointer, issues.value_of(tree, pointer),
               "makes about " + g(count) + " particles, which need about " +
                   g(count * kBytesPerParticle / kGiB) + " GiB (" + g(kBytesPerParticle) +
                   " bytes each) on a machine with " + g(memory / kGiB) + " GiB; raise the spacing",
               "m");
}

void check_render_buffer(const json& tree, const std::optional<RenderParams>& render,
                         Issues& issues) {
    if (!render || issues.has("/render")) return;
    // llvmpipe pads each side to its 64-pixel tiles
    const auto padded = [](int pixels) { return std::ceil(pixels / 64.0) * 64.0; };
    const double bytes = 4.0 * padded(render->width) * padded(render->height) * render->samples;
    if (bytes <= kMaxRenderBufferBytes) return;
    issues.add(
        "/render/resolution", issues.value_of(tree, "/render/resolution"),
        "with /render/samples = " + std::to_string(render->samples) +
            ", the multisampled colour buffer needs " + g(bytes / kGiB) +
            " GiB; OSMesa (llvmpipe) allocates at most 1 GiB per buffer: lower "
            "the resolution or the samples (width x height x samples <= 268435456, each side padded to "
            "64 pixels)");
}

// a camera placed by hand, as the renderer sees it: in single precision, looking somewhere
void check_camera(const json& tree, const std::optional<RenderParams>& render, Issues& issues) {
    if (!render || render->camera.is_auto || issues.has("/render/camera")) return;
    const CameraParams& camera = render->camera;
    for (const auto& [pointer, point] : {std::pair{"/render/camera/position", camera.position},
                                         std::pair{"/render/camera/target", camera.target}}) {
        if (point.cast<float>().allFinite()) continue;
        issues.add(pointer, issues.value_of(tree, pointer),
                   "beyond the renderer's single precision: expected coordinates below 3.4e+38",
                   "m");
        return;
    }
    // the view direction of a camera on its target is undefined: every pixel would show nothing
    if (!((camera.target.cast<float>() - camera.position.cast<float>()).norm() > 0))
        issues.add(
            "/render/camera/position", issues.value_of(tree, "/render/camera/position"),
            "is on /render/camera/target = " + issues.value_of(tree, "/render/camera/target") +
                ": the camera would look nowhere; expected a position away from the target",
            "m");
}

}  // namespace

void check_plausible(const json& tree, const InitParams& init, const SimModel& sim,
                     const std::optional<RenderParams>& render, Issues& issues) {
    check_cell_size(tree, init, sim, issues);  // first: a time step with a bad h blames h
    check_time_step(tree, sim, issues);
    check_particle_memory(tree, init, issues);
    check_render_buffer(tree, render, issues);
    check_camera(tree, render, issues);
}

}  // namespace mudcrack::spec
