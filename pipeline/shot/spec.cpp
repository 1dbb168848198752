// The shot spec table: every key's doc lives here, next to the code that reads it
// (docs/architecture.md §4). Ranges and defaults follow Tu et al. 2023 Table 1 and docs/physics.md
// §1.7, §4.7 and §5.5.
#include "pipeline/shot/spec.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "render/render_params.h"
#include "sim/core/particle_attributes.h"
#include "surfacing/surface_params.h"

namespace mudcrack::spec {
namespace {

using nlohmann::json;

// a fluent builder so each table row reads as one line of documentation
class Key {
public:
    Key(const char* pointer, KeyType type) {
        m_spec.pointer = pointer;
        m_spec.type = type;
        m_spec.presence = Presence::Default;
    }
    Key& def(json value) {
        m_spec.presence = Presence::Default;
        m_spec.default_value = std::move(value);
        return *this;
    }
    Key& required() { return presence(Presence::Required); }
    Key& derived() { return presence(Presence::Derived); }
    Key& optional() { return presence(Presence::Optional); }
    Key& gt(double v) { return bound(m_spec.min, v, true); }
    Key& ge(double v) { return bound(m_spec.min, v, false); }
    Key& lt(double v) { return bound(m_spec.max, v, true); }
    Key& le(double v) { return bound(m_spec.max, v, false); }
    Key& choices(std::vector<std::string> c) {
        m_spec.choices = std::move(c);
        return *this;
    }
    Key& refuse(const char* value, const char* why) {
        m_spec.refused.emplace_back(value, why);
        return *this;
    }
    Key& units(const char* u) {
        m_spec.units = u;
        return *this;
    }
    Key& doc(const char* d) {
        m_spec.doc = d;
        return *this;
    }
    operator KeySpec() const { return m_spec; }  // NOLINT: the builder's purpose

private:
    Key& bound(std::optional<Bound>& end, double v, bool is_exclusive) {
        end = Bound{v, is_exclusive};
        return *this;
    }
    Key& presence(Presence p) {
        m_spec.presence = p;
        return *this;
    }
    KeySpec m_spec;
};

using T = KeyType;

json vec(double a, double b, double c) { return json::array({a, b, c}); }

// @note A data table, one row per shot key (docs/architecture.md §4), so longer than a page.
std::vector<KeySpec> build_fixed_table() {
    // clang-format off
    return {
    // --- format and identity
    Key("/mudcrack", T::Integer).required().units("").doc("shot format major version; this build reads 1"),
    Key("/name", T::String).derived().units("").doc("shot name for logs and manifests; default: the file's stem"),
    Key("/reuse", T::String).optional().units("")
        .doc("another shot in this folder (its file's stem, e.g. \"fig8_c\"): take the stages whose slices are "
             "identical from its outputs (pipeline/shot.mk); that shot may not set /reuse itself; in no slice"),

    // --- source: what mc-init builds the particles from
    Key("/source", T::Section).required().doc("what mc-init fills with particles"),
    Key("/source/type", T::Enum).required().choices({"mesh", "box", "heightfield"}).units("")
        .doc("source kind; its settings live in /source/<type>"),
    Key("/source/initial_velocity", T::Vec3).def(vec(0, 0, 0)).units("m/s")
        .doc("velocity of every particle at t = 0"),
    Key("/source/mesh", T::Section).def(json::object()).doc("closed triangle mesh, tetrahedralized by CGAL Mesh_3 (used when type = mesh)"),
    Key("/source/mesh/path", T::Path).optional().units("")
        .doc("OBJ/PLY/STL/OFF/glTF file relative to the shot file; required when type = mesh"),
    Key("/source/mesh/scale", T::Number).def(1.0).gt(0).units("-").doc("uniform scale applied after loading"),
    Key("/source/mesh/translate", T::Vec3).def(vec(0, 0, 0)).units("m").doc("translation applied after scaling"),
    Key("/source/mesh/fit_to_ground", T::Bool).def(true).units("")
        .doc("move the mesh so its lowest point sits on y = 0 (after translate)"),
    Key("/source/box", T::Section).def(json::object()).doc("box slab on a lattice, 6 tets per cell (used when type = box)"),
    Key("/source/box/min", T::Vec3).def(vec(-0.5, 0, -0.5)).units("m").doc("lower corner"),
    Key("/source/box/max", T::Vec3).def(vec(0.5, 0.1, 0.5)).units("m").doc("upper corner; > min on every axis"),
    Key("/source/box/spacing", T::Number).def(0.025).gt(0).units("m")
        .doc("lattice spacing; particles = prod(round(extent/spacing) + 1) (lattice regular or jittered, footprint rectangle)"),
    Key("/source/box/lattice", T::Enum).def("regular").choices({"regular", "jittered", "mesh"}).units("")
        .doc("regular lattice, interior points jittered, or mesh: CGAL Mesh_3 tets of the box at /init/edge_length, no axis-aligned rows"),
    Key("/source/box/jitter", T::Number).def(0.25).ge(0).lt(0.5).units("spacing")
        .doc("jitter amplitude of interior points (lattice = jittered)"),
    Key("/source/box/footprint", T::Enum).def("rectangle").choices({"rectangle", "ellipse"}).units("")
        .doc("the body's extent in x and z: the whole rectangle, or the ellipse inscribed in it (a round puddle on a square box), its rim on the ellipse; with lattice mesh, Mesh_3 fills the elliptic cylinder"),
    Key("/source/heightfield", T::Section).def(json::object())
        .doc("terrain slab with a carved meandering channel, or a PNG heightmap (used when type = heightfield)"),
    Key("/source/heightfield/size", T::Vec2).def(json::array({4.0, 4.0})).gt(0).units("m")
        .doc("x and z extent"),
    Key("/source/heightfield/base", T::Number).def(0.3).gt(0).units("m").doc("thickness at the banks"),
    Key("/source/heightfield/amplitude", T::Number).def(0.05).ge(0).units("m").doc("bank undulation amplitude"),
    Key("/source/heightfield/channel_depth", T::Number).def(0.15).ge(0).units("m")
        .doc("depth of the carved channel; < base"),
    Key("/source/heightfield/channel_width", T::Number).def(0.8).gt(0).units("m").doc("channel width"),
    Key("/source/heightfield/channel_meander", T::Number).def(0.5).ge(0).units("m")
        .doc("lateral meander amplitude of the channel"),
    Key("/source/heightfield/image", T::Path).optional().units("")
        .doc("grayscale PNG heightmap relative to the shot file; overrides the formula"),
    Key("/source/heightfield/image_height", T::Number).def(0.3).gt(0).units("m").doc("height of a white pixel"),
    Key("/source/heightfield/spacing", T::Number).def(0.05).gt(0).units("m")
        .doc("column spacing: the lattice's, or the top's samples when lattice = mesh"),
    Key("/source/heightfield/lattice", T::Enum).def("columns").choices({"columns", "mesh"}).units("")
        .doc("columns: a lattice of columns spread from bottom to top; mesh: CGAL Mesh_3 tets of the terrain's surface at /init/edge_length, no axis-aligned rows"),

    // --- init: tetrahedralization
    Key("/init", T::Section).def(json::object()).doc("tetrahedral initialization (mc-init)"),
    Key("/init/edge_length", T::Number).def(0.0).ge(0).units("m")
        .doc("target tet edge length for CGAL Mesh_3; 0 = derived from /sim/h by mc-init"),
    Key("/init/seed", T::Integer).def(1).ge(0).le(4294967295.0).units("").doc("jitter, mesher and strength-field seed"),
    Key("/init/strength_field", T::Section).optional()
        .doc("heterogeneous soil: a seeded random field of multipliers on the NACC yield pressure p0, "
             "cached as the particles' \"strength\" (docs/physics.md §6.1); needs "
             "/plasticity; omit for uniform soil"),
    Key("/init/strength_field/correlation_length", T::Number).def(0.05).gt(0).units("m")
        .doc("l of the field's covariance exp(-r^2 / (2 l^2)): the size of weak and strong patches"),
    Key("/init/strength_field/weibull_modulus", T::Number).def(4.0).ge(0.5).le(100).units("-")
        .doc("Weibull modulus m of the multipliers (mean 1): smaller is more varied (m = 4: cv 0.28)"),
    Key("/init/strength_field/azimuths", T::Enum).def("even").choices({"even", "random"}).units("")
        .doc("how the field's 256 plane waves share out the horizontal directions: even (one per "
             "stratum of the circle: no pair of directions preferred) or random (independent: the "
             "sum prefers one pair by chance, which a large slab's cracks can follow; shots measured "
             "before 2026-11-30 keep it; docs/physics.md §6.1)"),

    // --- material: neo-Hookean solid (Tu et al. 2023 Eq. 4-5; Table 1 (rho_s, E, nu))
    Key("/material", T::Section).required().doc("elastic solid (Eq. 4-5)"),
    Key("/material/density", T::Number).def(1.0).gt(0).units("kg/m^3").doc("rho_s, solid density (Table 1: 1 or 2)"),
    Key("/material/youngs_modulus", T::Number).def(2000.0).gt(0).units("Pa").doc("E, Young's modulus (Table 1: 1K-2K)"),
    Key("/material/poisson_ratio", T::Number).def(0.35).gt(-1).lt(0.5).units("-").doc("nu, Poisson's ratio (Table 1: 0.35)"),

    // --- plasticity: NACC (Wolper et al. 2019; Tu et al. 2023 Eq. 7-9, 12)
    Key("/plasticity", T::Section).optional().doc("NACC plasticity (Eq. 7-9); omit for pure elasticity"),
    Key("/plasticity/alpha0", T::Number).def(0.0).units("-").doc("initial hardening state alpha_0 = log J_p (Table 1: 0 to -0.05)"),
    Key("/plasticity/beta", T::Number).optional().ge(0).units("-")
        .doc("shorthand: sets both beta0 and beta1 (Table 1's single beta)"),
    Key("/plasticity/beta0", T::Number).derived().ge(0).units("-").doc("cohesion when dry (s = 0); default: beta, else 1"),
    Key("/plasticity/beta1", T::Number).derived().ge(0).units("-").doc("cohesion when saturated (s = 1); default: beta, else 1"),
    Key("/plasticity/xi", T::Number).def(1.0).ge(0).units("-").doc("hardening factor in p0 = kappa sinh(xi max(-alpha, 0)) (Table 1: 0.5-1)"),
    Key("/plasticity/M", T::Number).def(1.87).gt(0).units("-").doc("critical-state slope, friction (Table 1: 1.87-2.43)"),
    Key("/plasticity/hardening", T::Bool).def(true).units("").doc("update alpha in the return mapping"),
    Key("/plasticity/damage_strain", T::Number).optional().gt(0).units("-")
        .doc("permanent tensile damage: the softening a particle's tension and dry-side returns add to "
             "alpha, summed, removes its cohesion beta linearly and for good once it reaches this "
             "(docs/physics.md §6.2); omit for none"),

    // --- moisture: pore water (Tu et al. 2023 Sections 4.1, 5.2; docs/physics.md §3-4)
    Key("/moisture", T::Section).optional().doc("pore water, shrinkage and drying (Sections 4.1, 5.2); omit for none"),
    Key("/moisture/eta", T::Number).def(0.5).ge(0).lt(1).units("-").doc("porosity: theta in [0, eta], Jw = 1 - eta (1 - s) (Table 1: 0.4-0.5)"),
    Key("/moisture/k_r", T::Number).def(1.0).gt(0).units("-").doc("rho_s / rho_w (Table 1: 1 or 2)"),
    Key("/moisture/eps", T::Number).def(0.5).ge(0).units("-").doc("saturation hardening rate epsilon (Table 1: 0.2-1)"),
    Key("/moisture/D", T::Number).def(0.02).ge(0).units("m^2/s").doc("moisture diffusivity (docs/physics.md §4.7: 0.01-0.05)"),
    Key("/moisture/lambda", T::Number).def(0.1).ge(0).units("m/s").doc("evaporation coefficient (docs/physics.md §4.7: 0.05-0.2)"),
    Key("/moisture/theta0", T::Number).def(0.0).ge(0).lt(1).units("-").doc("ambient moisture; <= eta"),
    Key("/moisture/theta_init", T::Number).derived().ge(0).lt(1).units("-")
        .doc("initial moisture in [0, eta]; default: eta (fully saturated, Section 7.1)"),
    Key("/moisture/cg_tolerance", T::Number).def(1e-6).gt(0).lt(1).units("-").doc("CG relative residual"),
    Key("/moisture/cg_max_iterations", T::Integer).def(50).ge(1).units("").doc("CG iteration cap per solve"),
    Key("/moisture/seal_colliders", T::Bool).def(true).units("").doc("faces against the ground and walls do not evaporate"),
    Key("/moisture/implicit_robin", T::Bool).def(false).units("").doc("evaporation term in the matrix instead of the rhs (evaporation = grid)"),
    Key("/moisture/evaporation", T::Enum).def("grid").choices({"grid", "surface"}).units("")
        .doc("grid: the paper's r term, from particles whose stencil touches a surface node (a drying "
             "front about 2 cells deep); surface: the exposed particle layer loses water itself, so a "
             "crust can be one particle layer thin when D is small (docs/physics.md §6.3)"),
    Key("/moisture/diffusion_operator", T::Enum).optional().choices({"particles", "grid"}).units("")
        .doc("particles (when omitted): the paper's particle-quadrature L, one pass over the particles "
             "per CG iteration; grid: a finite-volume Laplacian between face-adjacent grid nodes, no "
             "particle pass (docs/physics.md §4.9); grid needs implicit_robin false"),
    Key("/moisture/evaporation_ramp", T::Vec2).optional().ge(0).units("frames")
        .doc("[start, full]: when the drying begins, in the shot's own frames: no evaporation until "
             "the end of frame start, then lambda rising linearly to its full value at the end of "
             "frame full; full > start (docs/physics.md §6.3); omit: lambda from the first step"),
    Key("/moisture/interval", T::Integer).def(1).ge(1).units("steps").doc("solve moisture every k-th MPM step over the time since the last solve, each solve's theta increment applied over the k steps from it"),
    Key("/moisture/max_log_jw_step", T::Number).def(1e-3).gt(0).units("-")
        .doc("cap on |log(Jw^n / Jw^n+1)| per step (docs/physics.md §3.2)"),

    // --- sim: grid and time stepping (docs/physics.md §1.7)
    Key("/sim", T::Section).def(json::object()).doc("MPM grid and time stepping"),
    Key("/sim/h", T::Number).def(0.05).gt(0).units("m").doc("grid cell size (Table 1 'Grid Res.': 0.02-0.2)"),
    Key("/sim/dt_max", T::Number).def(1e-3).gt(0).units("s").doc("largest step; adaptive steps obey both CFL bounds (Table 1: 1e-3)"),
    Key("/sim/dt", T::Number).optional().gt(0).units("s")
        .doc("fixed step; refused if above C_E h / c_p; a substep failing its checks is redone at halves of it, "
             "growing back to it; omit for adaptive steps"),
    Key("/sim/cfl_velocity", T::Number).def(0.6).gt(0).le(1).units("-").doc("C_v: dt <= C_v h / max|v|"),
    Key("/sim/cfl_elastic", T::Number).def(0.5).gt(0).le(1).units("-").doc("C_E: dt <= C_E h / c_p, c_p = sqrt((lambda + 2 mu) / rho)"),
    Key("/sim/gravity", T::Vec3).def(vec(0, -9.81, 0)).units("m/s^2").doc("gravitational acceleration (y is up)"),
    Key("/sim/grid_shift", T::Integer).def(0).ge(0).units("steps")
        .doc("every k steps the grid moves by a random fraction of a cell on each axis, so no crack or "
             "plastic band stays locked to its axes; 0 = a fixed grid (docs/physics.md §6.4)"),
    Key("/sim/grid_turn", T::Integer).def(0).ge(0).units("steps")
        .doc("every k steps the grid turns to a new angle about the vertical (/sim/grid_turn_angles), so "
             "no crack follows its axes; needs an auto domain and a vertical gravity; 0 = a grid along "
             "the world's axes (docs/physics.md §6.5)"),
    Key("/sim/grid_turn_angles", T::Enum).def("golden").choices({"golden", "random"}).units("")
        .doc("how the turned grid's angles follow each other: golden (quarter turns by the golden "
             "ratio: every run of a few turns spreads evenly, so no pair of directions is favoured "
             "while a crack opens) or random (independent draws: a run of 20 can favour one pair; "
             "the shots that were measured on it pin it; docs/physics.md §6.5)"),
    Key("/sim/precision", T::Enum).def("double").choices({"double", "float"}).units("")
        .doc("what the particles' positions, velocities, affine velocities and Fe are kept in between steps: "
             "float halves those arrays (a third less memory per particle); the step computes in double "
             "either way, and the scalars stay double (docs/physics.md §7.1)"),
    Key("/sim/checkpoint_every", T::Integer).def(10).ge(0).units("frames").doc("frames between full-precision checkpoints; 0 = off"),

    // --- frames
    Key("/frames", T::Section).def(json::object()).doc("frame range and rate"),
    Key("/frames/start", T::Integer).def(1).ge(1).le(kMaxFrame).units("").doc("first frame (1-based)"),
    Key("/frames/end", T::Integer).def(24).ge(1).le(kMaxFrame).units("")
        .doc("last frame, inclusive; >= start; at most 9999, the last frame a four-digit name.####.ext holds"),
    Key("/frames/fps", T::Number).def(24.0).gt(0).units("1/s").doc("frames per second of simulated time"),

    // --- colliders
    Key("/colliders", T::Section).def(json::object()).doc("boundary conditions"),
    Key("/colliders/ground", T::Section).optional().doc("ground plane y = height; omit for none"),
    Key("/colliders/ground/height", T::Number).def(0.0).units("m").doc("plane height"),
    Key("/colliders/ground/mode", T::Enum).def("sticky").choices({"sticky", "slip", "separate"}).units("")
        .doc("sticky: v = 0; slip: no normal velocity; separate: may lift off"),
    Key("/colliders/ground/friction", T::Number).def(0.0).ge(0).units("-").doc("Coulomb coefficient (slip, separate)"),
    Key("/colliders/domain", T::Section).optional().doc("simulation box; omit to derive it from the particles"),
    Key("/colliders/domain/min", T::Vec3).def(vec(-1, -1, -1)).units("m").doc("lower corner"),
    Key("/colliders/domain/max", T::Vec3).def(vec(1, 1, 1)).units("m").doc("upper corner; > min on every axis"),
    Key("/colliders/domain/padding", T::Integer).def(3).ge(1).units("cells").doc("wall layer that removes outward velocity"),

    // --- surfacing (Tu et al. 2023 Section 6; docs/physics.md §5)
    Key("/surfacing", T::Section).optional().doc("particle-core surfacing (mc-surface); omit for none"),
    Key("/surfacing/mode", T::Enum).def("ours").choices(surface_mode_names()).units("")
        .doc("ours: moisture-aware Eq. 13-14; wang2019: the baseline; plates: clean plates for close-ups (docs/physics.md §5.7)"),
    Key("/surfacing/zeta", T::Number).def(2.0).gt(0).units("-")
        .doc("edge-stretch threshold of Eq. 14 (docs/physics.md §5.5: >= (1-eta)^(-2/3))"),
    Key("/surfacing/length_consistent", T::Bool).def(false).units("")
        .doc("threshold 0.5 (Jw_p^(1/3) + Jw_q^(1/3)) zeta (docs/physics.md §5.5)"),
    Key("/surfacing/cracks", T::Bool).def(true).units("").doc("mesh crack surfaces (false: boundary only)"),
    Key("/surfacing/format", T::Enum).def("glb").choices(mesh_format_names()).units("")
        .refuse("fbx", kFbxRefusal)
        .doc("mesh file format (assimp exporter); not fbx (assimp/assimp#4686)"),
    Key("/surfacing/min_fragment_particles", T::Integer).def(1).ge(1).units("particles")
        .doc("fragments smaller than this are culled as debris"),
    Key("/surfacing/min_piece_size", T::Number).def(2.0).gt(0).units("cells")
        .doc("plates mode: a fragment at least this wide across (in /sim/h) is a plate; the rest joins a plate or is debris"),
    Key("/surfacing/debris_gap", T::Number).def(0.5).gt(0).units("spacings")
        .doc("plates mode: a torn particle whose every path to a plate opened more than this (in particle spacings) is debris"),
    Key("/surfacing/close_gaps", T::Number).def(0.25).ge(0).le(1).units("spacings")
        .doc("plates mode: crack walls whose sides are closer than this (in particle spacings) meet: no hairline gaps"),
    Key("/surfacing/open_speed", T::Number).def(SurfaceParams{}.open_speed).ge(0).le(10).units("spacings/frame")
        .doc("plates mode: how fast a fresh crack cut after its particles parted opens beyond their motion (against pops); 0: at once (no lag, no saw-teeth)"),
    Key("/surfacing/wall_smoothing", T::Integer).def(SurfaceParams{}.wall_smoothing).ge(0).le(100).units("iterations")
        .doc("plates mode: Taubin steps that smooth the crack walls, in rest space and where they are (0: the dual-cell walls)"),
    Key("/surfacing/debris", T::Enum).def("none").choices({"none", "points"}).units("")
        .doc("plates mode: none, or debris.####.ply per frame (position, velocity, radius, id, piece) to instance on"),

    // --- render: the headless preview
    Key("/render", T::Section).optional().doc("preview renderer (mc-render); omit for none"),
    Key("/render/resolution", T::Vec2i).def(json::array({960, 540})).ge(kMinResolution).le(kMaxResolution).units("px").doc("[width, height]"),
    Key("/render/color_mode", T::Enum).def("moisture").choices(color_mode_names()).units("")
        .doc("moisture: wetter is darker; hardening: alpha colormap (Fig. 9); plain: albedo"),
    Key("/render/camera", T::Section).optional().doc("fixed camera; omit to frame the bounds automatically"),
    Key("/render/camera/position", T::Vec3).def(vec(3, 2, 3)).units("m").doc("eye position"),
    Key("/render/camera/target", T::Vec3).def(vec(0, 0, 0)).units("m").doc("look-at point"),
    Key("/render/camera/fov", T::Number).def(35.0).ge(0.01).lt(180).units("deg").doc("vertical field of view (at least 0.01, with room to spare for the renderer's single precision)"),
    Key("/render/samples", T::Integer).def(4).ge(1).le(64).units("").doc("anti-aliasing samples per pixel"),
    Key("/render/turntable", T::Section).optional().doc("orbit around one frame; omit for no turntable"),
    Key("/render/turntable/views", T::Integer).def(36).ge(1).le(3600).units("").doc("views in the orbit"),
    Key("/render/turntable/frame", T::Integer).def(-1).ge(-1).units("")
        .doc("frame to orbit, in [start, end]; -1 = the last frame"),
    Key("/render/albedo", T::Vec3).def(vec(0.55, 0.42, 0.30)).ge(0).le(1).units("").doc("dry soil color, linear RGB"),
    Key("/render/alpha_range", T::Number).def(0.5).gt(0).units("-").doc("hardening colormap spans alpha0 -/+ this"),
    Key("/render/fps", T::Number).def(24.0).ge(0.1).le(1000).units("1/s").doc("movie frame rate (ffmpeg's mp4 writer fails far outside this range)"),
    };
    // clang-format on
}

// /sim/cache/<key>: one Bool per on-request cached attribute (MC_CACHED_ATTRIBUTES), after /sim's
// keys
void add_cache_request_keys(std::vector<KeySpec>& rows) {
    std::vector<KeySpec> keys = {
        Key("/sim/cache", T::Section)
            .optional()
            .doc(
                "extra attributes the frame caches carry (those the shot's physics has but does not cache by "
                "default); omit for the default set (/derived/cache)"),
    };
    for (const CachedAttributeInfo& a : kCachedAttributes) {
        if (a.policy != CachePolicy::OnRequest) continue;
        const std::string pointer = std::string("/sim/cache/") + a.shot_key;
        KeySpec key = Key(pointer.c_str(), T::Bool).def(false).units("");
        key.doc = std::string("cache \"") + a.vdb_name + "\": " + a.doc +
                  "; needs the physics that has it";
        keys.push_back(key);
    }
    const auto frames = std::find_if(rows.begin(), rows.end(),
                                     [](const KeySpec& k) { return k.pointer == "/frames"; });
    rows.insert(frames, keys.begin(), keys.end());
}

std::vector<KeySpec> build_table() {
    std::vector<KeySpec> rows = build_fixed_table();
    add_cache_request_keys(rows);
    return rows;
}

std::string number_text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

}  // namespace

const std::vector<KeySpec>& table() {
    static const std::vector<KeySpec> rows = build_table();
    return rows;
}

const KeySpec* find(const std::string& pointer) {
    static const std::map<std::string, const KeySpec*> index = [] {
        std::map<std::string, const KeySpec*> m;
        for (const KeySpec& k : table()) m[k.pointer] = &k;
        return m;
    }();
    const auto it = index.find(pointer);
    return it == index.end() ? nullptr : it->second;
}

std::string type_text(const KeySpec& key) {
    switch (key.type) {
        case KeyType::Section: return "section";
        case KeyType::Number: return "number";
        case KeyType::Integer: return "integer";
        case KeyType::Bool: return "bool";
        case KeyType::String: return "string";
        case KeyType::Path: return "path";
        case KeyType::Vec3: return "vec3";
        case KeyType::Vec2: return "vec2";
        case KeyType::Vec2i: return "vec2i";
        case KeyType::Enum: {
            std::string s = "enum(";
            for (size_t i = 0; i < key.choices.size(); ++i) s += (i ? "|" : "") + key.choices[i];
            return s + ")";
        }
    }
    return "?";
}

std::string default_text(const KeySpec& key) {
    if (key.type == KeyType::Section) {
        switch (key.presence) {
            case Presence::Required: return "required";
            case Presence::Optional: return "off if omitted";
            default: return "on";
        }
    }
    switch (key.presence) {
        case Presence::Required: return "required";
        case Presence::Derived: return "derived";
        case Presence::Optional: return "(unset)";
        case Presence::Default: break;
    }
    const nlohmann::json& v = key.default_value;
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number_float()) return number_text(v.get<double>());
    if (v.is_array()) {
        std::string s = "[";
        for (size_t i = 0; i < v.size(); ++i)
            s += (i ? ", " : "") +
                 (v[i].is_number_float() ? number_text(v[i].get<double>()) : v[i].dump());
        return s + "]";
    }
    return v.dump();
}

std::string range_text(const KeySpec& key) {
    if (key.min && key.max) {
        return std::string(key.min->is_exclusive ? "(" : "[") + number_text(key.min->value) + ", " +
               number_text(key.max->value) + (key.max->is_exclusive ? ")" : "]");
    }
    if (key.min)
        return std::string(key.min->is_exclusive ? "> " : ">= ") + number_text(key.min->value);
    if (key.max)
        return std::string(key.max->is_exclusive ? "< " : "<= ") + number_text(key.max->value);
    return "";
}

std::string parent_of(const std::string& pointer) {
    const size_t slash = pointer.rfind('/');
    return slash == std::string::npos ? "" : pointer.substr(0, slash);
}

}  // namespace mudcrack::spec
