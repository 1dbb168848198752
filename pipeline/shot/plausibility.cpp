// Physical plausibility at load (build.h, check_plausible): values each inside their own range
// that together would stop a stage deep in its run, refused before any work with the key named.
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <optional>
#include <string>
#include <utility>

#include "pipeline/init/lattice.h"
#include "pipeline/shot/build.h"
#include "pipeline/shot/measured_body.h"

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
// how far below a particle its quadratic B-spline stencil reaches the grid's nodes [cells]
constexpr Real kStencilReach = 1.5;
// the most substeps a frame may start with. The shipped shots start with 42 to 405; 10^4 is 25
// times the most, and still lets a real clay through (E = 1e8 Pa, 2000 kg/m^3, h = 0.01 m: about
// 2,300). Past it a step is seldom what the artist meant (nu = 0.4999999999 makes the demo take
// 6.5 million a frame: months), and the demo's 45,000 particles would take over a minute a frame
constexpr double kMaxSubstepsPerFrame = 1e4;
// a soil's elastic constants, for telling which of the shot's puts its wave speed furthest off
constexpr Real kSoilDensity = 1e3, kSoilYoungsModulus = 1e6, kSoilPoissonRatio = 0.35;  // [SI]

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

// how much stiffer than lambda + 2 mu = E the Poisson ratio makes the soil: without bound toward
// 0.5 (incompressible) and toward -1
Real poisson_stiffening(Real nu) { return (1 - nu) / ((1 + nu) * (1 - 2 * nu)); }

// the material key whose value puts the wave speed furthest from a soil's, by its factor in c_p^2
std::string furthest_material_key(const ElasticParams& e) {
    const std::pair<Real, const char*> factors[] = {
        {std::abs(std::log10(e.density / kSoilDensity)), "/material/density"},
        {std::abs(std::log10(e.youngs_modulus / kSoilYoungsModulus)), "/material/youngs_modulus"},
        {std::abs(std::log10(poisson_stiffening(e.poisson_ratio) /
                             poisson_stiffening(kSoilPoissonRatio))),
         "/material/poisson_ratio"}};
    return std::max_element(std::begin(factors), std::end(factors))->second;
}

// the elastic bound's term of a message: c_p, and the material keys other than `blamed`
std::string elastic_why(const json& tree, const ElasticParams& dry, const std::string& blamed,
                        const Issues& issues) {
    std::string others;
    for (const char* key :
         {"/material/youngs_modulus", "/material/poisson_ratio", "/material/density"}) {
        if (key == blamed) continue;
        others +=
            (others.empty() ? "" : " and ") + std::string(key) + " = " + issues.value_of(tree, key);
    }
    return "the elastic bound C_E h / c_p (c_p = " + g(dry.wave_speed()) + " m/s, with " + others +
           ")";
}

StepBound smallest_step(const json& tree, const SimModel& sim, const Issues& issues) {
    const TimeParams& t = sim.time;
    if (t.dt_fixed > 0) return {t.dt_fixed, "/sim/dt", "the fixed step /sim/dt"};
    StepBound b{t.dt_max, "/sim/dt_max", "the largest step /sim/dt_max"};
    // the elastic bound with the lightest (dry) soil, as stable_dt computes it
    ElasticParams dry = sim.elastic;
    if (sim.moisture) dry.density = std::min(dry.density, dry.density * (1 - sim.moisture->eta));
    const Real elastic = t.cfl_elastic * sim.h / dry.wave_speed();
    if (!(elastic >= b.dt)) {
        const std::string blamed = furthest_material_key(sim.elastic);
        b = {elastic, blamed, elastic_why(tree, dry, blamed, issues)};
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

// a step mc-sim survives but that makes each frame take more than kMaxSubstepsPerFrame substeps:
// hours of simulation with no word (nu = 0.4999999999 gave 1e-8 s steps)
void check_substeps(const json& tree, const SimModel& sim, const StepBound& b, Issues& issues) {
    const Real frame = 1 / sim.time.fps;
    const double substeps = std::ceil(frame / b.dt);
    if (substeps <= kMaxSubstepsPerFrame) return;
    const std::string step = "a stable time step of " + g(b.dt) + " s (" + b.why + ")";
    const std::string bound = "expected at most " + g(kMaxSubstepsPerFrame);
    // the step, with gravity over a frame of a usual length, would do for such frames: the
    // frames are too long
    SimModel usual = sim;
    usual.time.fps = 1 / kUsualFrameLength;
    const StepBound usual_step = smallest_step(tree, usual, issues);
    if (kUsualFrameLength / usual_step.dt <= kMaxSubstepsPerFrame) {
        issues.add("/frames/fps", issues.value_of(tree, "/frames/fps"),
                   "frames of " + g(frame) + " s take " + g(substeps) + " substeps each at " +
                       step + "; " + bound + ": frames per second of simulated time (e.g. 24)");
        return;
    }
    issues.add(b.pointer, issues.value_of(tree, b.pointer),
               "gives " + step + ": " + g(substeps) +
                   " substeps per frame of 1 / fps = " + g(frame) + " s; " + bound);
}

// a step below the floor would never finish a frame (mc-sim would stop on its first substep); one
// above it may still need more substeps a frame than a run should take (check_substeps)
void check_time_step(const json& tree, const SimModel& sim, Issues& issues) {
    if (issues.has("/material") || issues.has("/sim") || issues.has("/frames") ||
        issues.has("/source/initial_velocity"))
        return;
    const Real frame = 1 / sim.time.fps;
    const Real floor = kCollapsedDtFraction * frame;
    const StepBound b = smallest_step(tree, sim, issues);
    if (b.dt >= floor && std::isfinite(b.dt)) return check_substeps(tree, sim, b, issues);
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

// the body a source fills, as far as the loader knows it before mc-init: a box's and a
// heightfield's bounds (a heightfield's top at most base + amplitude, or image_height); a mesh's
// lowest point only, and only when /source/mesh/fit_to_ground puts it at y = 0 (mc-init and mc-sim
// check the rest against the mesh once read: check_measured_body)
struct BodyBounds {
    bool has_extent = false;  // extent and top known
    bool has_bottom = false;
    Vec3 extent = Vec3::Zero();  // [m]
    Real bottom = 0, top = 0;    // lowest and highest y [m]
    std::string where;           // what the bounds come from, for messages
};

BodyBounds body_bounds(const InitParams& init) {
    BodyBounds b;
    if (init.type == SourceType::Box) {
        b = {true,         true, init.box.max - init.box.min, init.box.min.y(), init.box.max.y(),
             "/source/box"};
    } else if (init.type == SourceType::Heightfield) {
        const HeightfieldSource& hf = init.heightfield;
        const Real top = hf.image.empty() ? hf.base + hf.amplitude : hf.image_height;
        b = {true, true, Vec3(hf.size.x(), top, hf.size.z()), 0, top, "/source/heightfield"};
    } else if (init.type == SourceType::Mesh && init.mesh.fit_to_ground) {
        b.has_bottom = true;
        b.where = "/source/mesh/fit_to_ground";
    }
    return b;
}

std::string sides_text(const Vec3& v) {
    return g(v.x()) + " x " + g(v.y()) + " x " + g(v.z()) + " m";
}

// what the sim grid spans: the explicit domain, else the body's extent, down to a ground below it
// (the derived domain reaches the ground; a mesh's extent is unknown here)
bool grid_extent(const InitParams& init, const SimModel& sim, Vec3& extent) {
    if (!sim.domain.is_auto) {
        extent = sim.domain.max - sim.domain.min;
        return true;
    }
    const BodyBounds body = body_bounds(init);
    if (!body.has_extent) return false;
    extent = body.extent;
    if (sim.ground) extent.y() = body.top - std::min(body.bottom, sim.ground->height);
    return true;
}

// a key's value refused, before the file and the value as written are put in front of it
struct Refusal {
    std::string pointer, expectation, units;
};

// the ground plane against the body, where its bounds are known: a ground at or above its top
// buries every particle; one further below its bottom than the body falls in the whole shot, plus
// the 1.5 cells a particle's quadratic B-spline stencil reaches below it, never acts (and, with a
// derived domain, stretches the grid down to it: -1e300 used to hang mc-sim)
std::optional<Refusal> ground_refusal(const BodyBounds& body, const SimModel& sim) {
    const Real height = sim.ground->height;
    if (body.has_extent && !(height < body.top))
        return Refusal{
            "/colliders/ground/height",
            "is at or above the top of the body, y = " + g(body.top) + " (" + body.where +
                "): every particle would start inside the ground; expected a height below " +
                g(body.top) + ", usually the body's bottom y = " + g(body.bottom),
            "m"};
    if (!body.has_bottom) return std::nullopt;
    const Real t = sim.time.frame_end / sim.time.fps;
    const Real fall = sim.initial_velocity.norm() * t + 0.5 * sim.gravity.norm() * t * t;
    const Real lowest = body.bottom - fall - kStencilReach * sim.h;
    if (height >= lowest) return std::nullopt;
    return Refusal{
        "/colliders/ground/height",
        "is " + g(body.bottom - height) + " m below the body's bottom y = " + g(body.bottom) +
            " (" + body.where + "), which moves at most " + g(fall) + " m down in the shot's " +
            g(t) +
            " s (|/source/initial_velocity| t + |/sim/gravity| t^2 / 2): the ground would never act; "
            "expected a height >= " +
            g(lowest) +
            " (that fall and the 1.5 cells a particle reaches "
            "below it), or no /colliders/ground",
        "m"};
}

// a body less than a cell across on a side has no node inside it: its particles share every
// node with the air around them
std::optional<Refusal> cell_size_refusal(const BodyBounds& body, const SimModel& sim) {
    if (!body.has_extent || !(sim.h > body.extent.minCoeff())) return std::nullopt;
    return Refusal{
        "/sim/h",
        "is larger than the body (" + body.where + ": " + sides_text(body.extent) +
            "), which would be less than one cell across: expected at most its thinnest side, " +
            g(body.extent.minCoeff()),
        "m"};
}

void add(const json& tree, const Refusal& r, Issues& issues) {
    issues.add(r.pointer, issues.value_of(tree, r.pointer), r.expectation, r.units);
}

void check_ground(const json& tree, const InitParams& init, const SimModel& sim, Issues& issues) {
    if (!sim.ground || issues.has("/colliders/ground") || issues.has("/source") ||
        issues.has("/sim") || issues.has("/frames"))
        return;
    if (const std::optional<Refusal> r = ground_refusal(body_bounds(init), sim))
        add(tree, *r, issues);
}

void check_cell_size(const json& tree, const InitParams& init, const SimModel& sim,
                     Issues& issues) {
    if (issues.has("/sim/h") || issues.has("/source") || issues.has("/colliders")) return;
    if (sim.h < kMinCellSize) {
        issues.add("/sim/h", issues.value_of(tree, "/sim/h"),
                   "must be >= " + g(kMinCellSize) +
                       " (OpenVDB, which holds the caches, refuses voxels this small)",
                   "m");
        return;
    }
    // a given domain: at least a cell on every axis, and a free cell between its walls
    if (!sim.domain.is_auto) {
        const Vec3 sides = sim.domain.max - sim.domain.min;
        const Real thinnest = sides.minCoeff();
        if (sim.h > thinnest) {
            issues.add("/sim/h", issues.value_of(tree, "/sim/h"),
                       "is larger than the domain (/colliders/domain: " + sides_text(sides) +
                           "): expected at most its thinnest side, " + g(thinnest),
                       "m");
            return;
        }
        const int padding = sim.domain.padding;
        if (2.0 * padding + 1 > thinnest / sim.h) {
            issues.add(
                "/colliders/domain/padding", issues.value_of(tree, "/colliders/domain/padding"),
                "walls of " + std::to_string(padding) + " cells on both sides (at /sim/h = " +
                    g(sim.h) + " m) leave no free cell across the domain's " + g(thinnest) +
                    " m: expected at most " + g(std::floor((thinnest / sim.h - 1) / 2)),
                "cells");
            return;
        }
    }
    if (const std::optional<Refusal> r = cell_size_refusal(body_bounds(init), sim)) {
        add(tree, *r, issues);
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
    if (init.type == SourceType::Box && init.box.lattice != Lattice::Mesh) {
        const Vec3 cells = (init.box.max - init.box.min) / init.box.spacing;
        count =
            (std::round(cells.x()) + 1) * (std::round(cells.y()) + 1) * (std::round(cells.z()) + 1);
        pointer = "/source/box/spacing";
    } else if (init.type == SourceType::Heightfield &&
               init.heightfield.lattice == HeightfieldLattice::Columns) {
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
    check_ground(tree, init, sim, issues);     // first: the grid reaches down to the ground
    check_cell_size(tree, init, sim, issues);  // then: a time step with a bad h blames h
    check_time_step(tree, sim, issues);
    check_particle_memory(tree, init, issues);
    check_render_buffer(tree, render, issues);
    check_camera(tree, render, issues);
}

}  // namespace mudcrack::spec

namespace mudcrack {

namespace {

// a shot's number as its JSON text would show it: the shortest digits that read back the same
std::string number_text(double v) {
    char buf[32];
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

std::string value_text(const Shot& shot, const std::string& pointer) {
    if (pointer == "/sim/h") return number_text(shot.sim.h);
    return number_text(shot.sim.ground->height);
}

}  // namespace

MeasuredBody placed_mesh_body(const std::string& mesh_path, const Vec3& lo, const Vec3& hi) {
    return {lo, hi, mesh_path + " as placed by /source/mesh"};
}

void check_measured_body(const Shot& shot, const MeasuredBody& body) {
    const spec::BodyBounds bounds{true,        true,        body.hi - body.lo,
                                  body.lo.y(), body.hi.y(), body.what};
    spec::Issues issues(shot.path);
    const auto add = [&](const std::optional<spec::Refusal>& r) {
        if (r) issues.add(r->pointer, value_text(shot, r->pointer), r->expectation, r->units);
    };
    // in the loader's order, all at once
    if (shot.sim.ground) add(spec::ground_refusal(bounds, shot.sim));
    add(spec::cell_size_refusal(bounds, shot.sim));
    issues.throw_if_any();
}

}  // namespace mudcrack
