#include "pipeline/shot/build.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sim/core/log.h"

namespace mudcrack::spec {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// readers for the filled tree: keys with a default are always there (validate.h)
const json* find_value(const json& tree, const std::string& pointer) {
    const json::json_pointer p(pointer);
    return tree.contains(p) ? &tree.at(p) : nullptr;
}
bool has(const json& tree, const std::string& pointer) { return find_value(tree, pointer) != nullptr; }
Real number(const json& tree, const std::string& pointer) {
    return tree.at(json::json_pointer(pointer)).get<double>();
}
int integer(const json& tree, const std::string& pointer) {
    return static_cast<int>(tree.at(json::json_pointer(pointer)).get<std::int64_t>());
}
bool boolean(const json& tree, const std::string& pointer) {
    return tree.at(json::json_pointer(pointer)).get<bool>();
}
std::string text(const json& tree, const std::string& pointer) {
    return tree.at(json::json_pointer(pointer)).get<std::string>();
}
Vec3 vec3(const json& tree, const std::string& pointer) {
    const json& v = tree.at(json::json_pointer(pointer));
    return Vec3(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

std::string g(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

// a path from the shot, resolved against the shot file's folder, absolute and normalized
fs::path resolve(const std::string& shot_path, const std::string& path) {
    fs::path p(path);
    if (p.is_relative()) p = fs::path(shot_path).parent_path() / p;
    return fs::absolute(p).lexically_normal();
}

// resolves the path at `pointer` in place, and checks the file is there
std::string resolve_existing(json& tree, const std::string& pointer, const std::string& shot_path,
                             Issues& issues) {
    const json::json_pointer p(pointer);
    const std::string given = tree.at(p).get<std::string>();
    const fs::path resolved = resolve(shot_path, given);
    std::error_code ec;
    if (!fs::is_regular_file(resolved, ec))
        issues.add(pointer, value_text(&tree.at(p)),
                   "file not found (looked for " + resolved.string() + ", relative to the shot file)");
    tree[p] = resolved.string();
    return resolved.string();
}

// /reuse names another shot file of this folder by its stem; make links the stages whose slices
// are identical to that shot's outputs (pipeline/shot.mk), so the name must resolve to a file
// other than this one, and that shot must not reuse a third (one level: no chains, no cycles)
void check_reuse(const json& tree, const std::string& shot_path, Issues& issues) {
    const json* reuse = find_value(tree, "/reuse");
    if (!reuse) return;
    const std::string name = reuse->get<std::string>();
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..") {
        issues.add("/reuse", value_text(reuse),
                   "must be the name of another shot in this folder (its file's stem, no \"/\")");
        return;
    }
    const fs::path self = fs::absolute(shot_path).lexically_normal();
    const fs::path other = self.parent_path() / (name + ".json");
    std::error_code ec;
    if (!fs::is_regular_file(other, ec)) {
        issues.add("/reuse", value_text(reuse),
                   "no such shot (looked for " + other.string() + ", in the shot file's folder)");
        return;
    }
    if (fs::equivalent(self, other, ec)) {
        issues.add("/reuse", value_text(reuse), "must name another shot, not this one");
        return;
    }
    std::ifstream in(other, std::ios::binary);
    std::ostringstream text_of_other;
    text_of_other << in.rdbuf();
    // a malformed reused shot is reported when make validates and runs it
    const json root = json::parse(text_of_other.str(), nullptr, /*allow_exceptions=*/false,
                                  /*ignore_comments=*/true);
    if (root.is_object() && root.contains("reuse"))
        issues.add("/reuse", value_text(reuse),
                   "must name a shot that does not set /reuse itself (" + other.string() + " reuses " +
                       value_text(&root["reuse"]) + "; name that shot instead)");
}

bool all_less(const Vec3& a, const Vec3& b) { return (a.array() < b.array()).all(); }

// the /source/<type> section names, in SourceType order (init_params.cpp lives in the CGAL target,
// which this library must not link)
const char* const kSourceKinds[] = {"mesh", "box", "heightfield"};

SourceType source_type(const std::string& name) {
    if (name == "mesh") return SourceType::Mesh;
    if (name == "heightfield") return SourceType::Heightfield;
    return SourceType::Box;
}

ColliderMode collider_mode(const std::string& name) {
    if (name == "slip") return ColliderMode::Slip;
    if (name == "separate") return ColliderMode::Separate;
    return ColliderMode::Sticky;
}

ColorMode color_mode(const std::string& name) {
    if (name == "hardening") return ColorMode::Hardening;
    if (name == "plain") return ColorMode::Plain;
    return ColorMode::Moisture;
}

void build_mesh(json& tree, const std::string& shot_path, MeshSource& mesh, Issues& issues) {
    if (has(tree, "/source/mesh/path"))
        mesh.path = resolve_existing(tree, "/source/mesh/path", shot_path, issues);
    else if (!issues.has("/source/mesh/path"))
        issues.add("/source/mesh/path", "(missing)", "required when /source/type = \"mesh\"");
    mesh.scale = number(tree, "/source/mesh/scale");
    mesh.translate = vec3(tree, "/source/mesh/translate");
    mesh.fit_to_ground = boolean(tree, "/source/mesh/fit_to_ground");
}

void build_box(const json& tree, BoxSource& box, Issues& issues) {
    box.min = vec3(tree, "/source/box/min");
    box.max = vec3(tree, "/source/box/max");
    box.spacing = number(tree, "/source/box/spacing");
    box.lattice = text(tree, "/source/box/lattice") == "jittered" ? Lattice::Jittered : Lattice::Regular;
    box.jitter = number(tree, "/source/box/jitter");
    if (issues.has("/source/box")) return;  // bounds already reported
    if (!all_less(box.min, box.max)) {
        issues.add("/source/box/max", issues.value_of(tree, "/source/box/max"),
                   "must be > /source/box/min = " + issues.value_of(tree, "/source/box/min") +
                       " on every axis",
                   "m");
        return;
    }
    const Real smallest = (box.max - box.min).minCoeff();
    if (box.spacing > smallest)
        issues.add("/source/box/spacing", issues.value_of(tree, "/source/box/spacing"),
                   "must be <= the smallest box extent " + g(smallest) + " (at least one lattice cell)", "m");
}

void build_heightfield(json& tree, const std::string& shot_path, HeightfieldSource& hf, Issues& issues) {
    const json& size = tree.at(json::json_pointer("/source/heightfield/size"));
    hf.size = Vec3(size[0].get<double>(), 0, size[1].get<double>());
    hf.base = number(tree, "/source/heightfield/base");
    hf.amplitude = number(tree, "/source/heightfield/amplitude");
    hf.channel_depth = number(tree, "/source/heightfield/channel_depth");
    hf.channel_width = number(tree, "/source/heightfield/channel_width");
    hf.channel_meander = number(tree, "/source/heightfield/channel_meander");
    hf.image_height = number(tree, "/source/heightfield/image_height");
    hf.spacing = number(tree, "/source/heightfield/spacing");
    if (has(tree, "/source/heightfield/image"))
        hf.image = resolve_existing(tree, "/source/heightfield/image", shot_path, issues);
    // the channel must not cut through the slab's bottom
    if (hf.image.empty() && hf.channel_depth >= hf.base && !issues.has("/source/heightfield"))
        issues.add("/source/heightfield/channel_depth",
                   issues.value_of(tree, "/source/heightfield/channel_depth"),
                   "must be < /source/heightfield/base = " + g(hf.base), "m");
}

void build_plasticity(json& tree, SimModel& model) {
    if (!has(tree, "/plasticity")) return;
    NaccParams nacc;
    nacc.alpha0 = number(tree, "/plasticity/alpha0");
    // Table 1 gives one beta; beta0 and beta1 default to it (physics.md 4.8 T21)
    const Real beta = has(tree, "/plasticity/beta") ? number(tree, "/plasticity/beta") : Real(1);
    nacc.beta0 = has(tree, "/plasticity/beta0") ? number(tree, "/plasticity/beta0") : beta;
    nacc.beta1 = has(tree, "/plasticity/beta1") ? number(tree, "/plasticity/beta1") : beta;
    nacc.xi = number(tree, "/plasticity/xi");
    nacc.M = number(tree, "/plasticity/M");
    nacc.hardening = boolean(tree, "/plasticity/hardening");
    if (has(tree, "/plasticity/damage_strain")) nacc.damage_strain = number(tree, "/plasticity/damage_strain");
    // the shorthand is replaced by what it means, so equal settings give equal slices
    json& section = tree["plasticity"];
    section.erase("beta");
    section["beta0"] = nacc.beta0;
    section["beta1"] = nacc.beta1;
    model.nacc = nacc;
}

void build_moisture(json& tree, SimModel& model, Issues& issues) {
    if (!has(tree, "/moisture")) return;
    MoistureParams m;
    m.eta = number(tree, "/moisture/eta");
    m.k_r = number(tree, "/moisture/k_r");
    m.eps = number(tree, "/moisture/eps");
    m.D = number(tree, "/moisture/D");
    m.lambda = number(tree, "/moisture/lambda");
    m.theta0 = number(tree, "/moisture/theta0");
    m.cg_tolerance = number(tree, "/moisture/cg_tolerance");
    m.cg_max_iterations = integer(tree, "/moisture/cg_max_iterations");
    m.seal_colliders = boolean(tree, "/moisture/seal_colliders");
    m.implicit_robin = boolean(tree, "/moisture/implicit_robin");
    m.evaporation = text(tree, "/moisture/evaporation") == "surface" ? MoistureParams::Evaporation::Surface
                                                                    : MoistureParams::Evaporation::Grid;
    if (m.implicit_robin && m.evaporation == MoistureParams::Evaporation::Surface)
        issues.add("/moisture/implicit_robin", issues.value_of(tree, "/moisture/implicit_robin"),
                   "must be false with /moisture/evaporation = \"surface\" (the surface layer's decay is "
                   "exact; the implicit Robin term belongs to the grid evaporation)");
    m.interval = integer(tree, "/moisture/interval");
    m.max_log_jw_step = number(tree, "/moisture/max_log_jw_step");
    // particles start fully saturated unless told otherwise (paper Section 7.1)
    m.theta_init = has(tree, "/moisture/theta_init") ? number(tree, "/moisture/theta_init") : m.eta;
    tree["moisture"]["theta_init"] = m.theta_init;
    if (!issues.has("/moisture/eta")) {
        const std::string within = "must be in [0, /moisture/eta = " + g(m.eta) + "]";
        if (m.theta_init > m.eta && !issues.has("/moisture/theta_init"))
            issues.add("/moisture/theta_init", issues.value_of(tree, "/moisture/theta_init"), within);
        if (m.theta0 > m.eta && !issues.has("/moisture/theta0"))
            issues.add("/moisture/theta0", issues.value_of(tree, "/moisture/theta0"), within);
    }
    model.moisture = m;
}

void build_time(const json& tree, SimModel& model, Issues& issues) {
    TimeParams& t = model.time;
    t.dt_max = number(tree, "/sim/dt_max");
    t.cfl_velocity = number(tree, "/sim/cfl_velocity");
    t.cfl_elastic = number(tree, "/sim/cfl_elastic");
    t.fps = number(tree, "/frames/fps");
    t.frame_start = integer(tree, "/frames/start");
    t.frame_end = integer(tree, "/frames/end");
    if (t.frame_end < t.frame_start && !issues.has("/frames"))
        issues.add("/frames/end", issues.value_of(tree, "/frames/end"),
                   "must be >= /frames/start = " + std::to_string(t.frame_start));
    if (!has(tree, "/sim/dt")) return;
    t.dt_fixed = number(tree, "/sim/dt");
    // explicit MPM blows up above the elastic wave bound (physics.md 1.7): refuse it at load
    const bool are_inputs_ok = !issues.has("/material") && !issues.has("/sim/h") &&
                               !issues.has("/sim/cfl_elastic");
    const Real bound = elastic_dt_bound(model);
    if (are_inputs_ok && t.dt_fixed > bound) {
        const ElasticParams& e = model.elastic;
        issues.add("/sim/dt", issues.value_of(tree, "/sim/dt"),
                   "exceeds the elastic bound C_E h / c_p = " + g(bound) + " s (C_E=" + g(t.cfl_elastic) +
                       ", h=" + g(model.h) + " m, E=" + g(e.youngs_modulus) + " Pa, nu=" +
                       g(e.poisson_ratio) + ", rho=" + g(e.density) + " kg/m^3, c_p=" +
                       g(e.wave_speed()) + " m/s); lower /sim/dt or omit it for adaptive steps");
    }
}

void build_colliders(const json& tree, SimModel& model, Issues& issues) {
    if (has(tree, "/colliders/ground")) {
        GroundParams ground;
        ground.height = number(tree, "/colliders/ground/height");
        ground.mode = collider_mode(text(tree, "/colliders/ground/mode"));
        ground.friction = number(tree, "/colliders/ground/friction");
        model.ground = ground;
    }
    if (has(tree, "/colliders/domain")) {
        DomainParams& d = model.domain;
        d.is_auto = false;
        d.min = vec3(tree, "/colliders/domain/min");
        d.max = vec3(tree, "/colliders/domain/max");
        d.padding = integer(tree, "/colliders/domain/padding");
        if (!issues.has("/colliders/domain") && !all_less(d.min, d.max))
            issues.add("/colliders/domain/max", issues.value_of(tree, "/colliders/domain/max"),
                       "must be > /colliders/domain/min = " + issues.value_of(tree, "/colliders/domain/min") +
                           " on every axis",
                       "m");
    }
}

}  // namespace

std::string build_reuse(const json& tree, const std::string& shot_path, Issues& issues) {
    check_reuse(tree, shot_path, issues);
    const json* reuse = find_value(tree, "/reuse");
    return reuse ? reuse->get<std::string>() : std::string();
}

InitParams build_init(json& tree, const std::string& shot_path, Issues& issues) {
    InitParams init;
    const bool has_type = has(tree, "/source/type");
    init.type = has_type ? source_type(text(tree, "/source/type")) : SourceType::Box;
    init.edge_length = number(tree, "/init/edge_length");
    init.seed = static_cast<unsigned>(tree.at(json::json_pointer("/init/seed")).get<std::int64_t>());
    if (has(tree, "/init/strength_field")) {
        StrengthFieldParams field;
        field.correlation_length = number(tree, "/init/strength_field/correlation_length");
        field.weibull_modulus = number(tree, "/init/strength_field/weibull_modulus");
        init.strength_field = field;
        if (!has(tree, "/plasticity"))
            issues.add("/init/strength_field", "(set)",
                       "needs /plasticity: the field multiplies the NACC yield pressure p0, which pure "
                       "elasticity does not have");
    }
    if (!has_type) return init;  // already reported; which source settings apply is unknown
    switch (init.type) {
        case SourceType::Mesh: build_mesh(tree, shot_path, init.mesh, issues); break;
        case SourceType::Box: build_box(tree, init.box, issues); break;
        case SourceType::Heightfield: build_heightfield(tree, shot_path, init.heightfield, issues); break;
    }
    // only the selected source's settings matter downstream
    json& source = tree["source"];
    for (const char* kind : kSourceKinds)
        if (kSourceKinds[static_cast<int>(init.type)] != std::string(kind)) source.erase(kind);
    return init;
}

SimModel build_sim(json& tree, Issues& issues) {
    SimModel model;
    model.h = number(tree, "/sim/h");
    model.gravity = vec3(tree, "/sim/gravity");
    model.initial_velocity = vec3(tree, "/source/initial_velocity");
    model.checkpoint_every = integer(tree, "/sim/checkpoint_every");
    model.elastic.density = number(tree, "/material/density");
    model.elastic.youngs_modulus = number(tree, "/material/youngs_modulus");
    model.elastic.poisson_ratio = number(tree, "/material/poisson_ratio");
    build_plasticity(tree, model);
    build_moisture(tree, model, issues);
    build_time(tree, model, issues);
    build_colliders(tree, model, issues);
    return model;
}

std::optional<SurfaceParams> build_surface(const json& tree) {
    if (!has(tree, "/surfacing")) return std::nullopt;
    SurfaceParams s;
    s.mode = text(tree, "/surfacing/mode") == "wang2019" ? SurfaceMode::Wang2019 : SurfaceMode::Ours;
    s.zeta = number(tree, "/surfacing/zeta");
    s.length_consistent = boolean(tree, "/surfacing/length_consistent");
    s.cracks = boolean(tree, "/surfacing/cracks");
    s.format = text(tree, "/surfacing/format");
    s.min_fragment_particles = integer(tree, "/surfacing/min_fragment_particles");
    return s;
}

std::optional<RenderParams> build_render(const json& tree) {
    if (!has(tree, "/render")) return std::nullopt;
    RenderParams r;
    const json& resolution = tree.at(json::json_pointer("/render/resolution"));
    r.width = static_cast<int>(resolution[0].get<std::int64_t>());
    r.height = static_cast<int>(resolution[1].get<std::int64_t>());
    r.color_mode = color_mode(text(tree, "/render/color_mode"));
    r.camera.is_auto = !has(tree, "/render/camera");
    if (!r.camera.is_auto) {
        r.camera.position = vec3(tree, "/render/camera/position");
        r.camera.target = vec3(tree, "/render/camera/target");
        r.camera.fov_deg = number(tree, "/render/camera/fov");
    }
    r.samples = integer(tree, "/render/samples");
    r.turntable = has(tree, "/render/turntable");
    if (r.turntable) {
        r.turntable_views = integer(tree, "/render/turntable/views");
        r.turntable_frame = integer(tree, "/render/turntable/frame");
    }
    r.albedo = vec3(tree, "/render/albedo");
    r.alpha_range = number(tree, "/render/alpha_range");
    r.fps = number(tree, "/render/fps");
    return r;
}

namespace {

// whether the shot has the physics a cached attribute needs
bool has_cache_physics(CachePhysics physics, const SimModel& sim, const std::optional<SurfaceParams>& surface) {
    switch (physics) {
        case CachePhysics::Always: return true;
        case CachePhysics::Moisture: return sim.moisture.has_value();
        case CachePhysics::Plasticity: return sim.nacc.has_value();
        case CachePhysics::Damage: return sim.nacc.has_value() && sim.nacc->damage_strain > 0;
        case CachePhysics::Surfacing: return surface.has_value();
    }
    return false;
}

const char* cache_physics_text(CachePhysics physics) {
    switch (physics) {
        case CachePhysics::Always: return "";
        case CachePhysics::Moisture: return "/moisture";
        case CachePhysics::Plasticity: return "/plasticity";
        case CachePhysics::Damage: return "/plasticity/damage_strain";
        case CachePhysics::Surfacing: return "/surfacing";
    }
    return "";
}

}  // namespace

CacheAttributes derive_cache(const json& tree, const SimModel& sim, const std::optional<SurfaceParams>& surface,
                             Issues& issues) {
    CacheAttributes cache;
    for (size_t i = 0; i < kCachedAttributeCount; ++i) {
        const CachedAttributeInfo& a = kCachedAttributes[i];
        const bool has_physics = has_cache_physics(a.physics, sim, surface);
        if (a.policy == CachePolicy::ByPhysics) {
            cache[i] = has_physics;
            continue;
        }
        const std::string pointer = std::string("/sim/cache/") + a.shot_key;
        const bool is_requested = has(tree, pointer) && boolean(tree, pointer);
        if (is_requested && !has_physics)
            issues.add(pointer, "true", std::string("the shot has no ") + a.vdb_name + " to cache: needs " +
                                            cache_physics_text(a.physics));
        cache[i] = is_requested && has_physics;
    }
    return cache;
}

void check_across(const json& tree, const InitParams& init, const SimModel& sim,
                  const std::optional<RenderParams>& render, Issues& issues) {
    const DomainParams& d = sim.domain;
    const bool is_domain_ok = !d.is_auto && !issues.has("/colliders/domain");
    if (is_domain_ok && has(tree, "/source/type") && init.type == SourceType::Box &&
        !issues.has("/source/box")) {
        if (!(init.box.min.array() >= d.min.array()).all())
            issues.add("/source/box/min", issues.value_of(tree, "/source/box/min"),
                       "must be >= /colliders/domain/min = " +
                           issues.value_of(tree, "/colliders/domain/min") +
                           " on every axis (the box must lie inside the domain)",
                       "m");
        if (!(init.box.max.array() <= d.max.array()).all())
            issues.add("/source/box/max", issues.value_of(tree, "/source/box/max"),
                       "must be <= /colliders/domain/max = " +
                           issues.value_of(tree, "/colliders/domain/max") +
                           " on every axis (the box must lie inside the domain)",
                       "m");
    }
    if (is_domain_ok && sim.ground && !issues.has("/colliders/ground") &&
        !(sim.ground->height >= d.min.y() && sim.ground->height < d.max.y()))
        issues.add("/colliders/ground/height", issues.value_of(tree, "/colliders/ground/height"),
                   "must be in [" + g(d.min.y()) + ", " + g(d.max.y()) + ") (the domain's y range)", "m");
    if (render && render->turntable && !issues.has("/render/turntable/frame") && !issues.has("/frames")) {
        const int f = render->turntable_frame;
        if (f != -1 && (f < sim.time.frame_start || f > sim.time.frame_end))
            issues.add("/render/turntable/frame", issues.value_of(tree, "/render/turntable/frame"),
                       "must be -1 (the last frame) or a frame in [" + std::to_string(sim.time.frame_start) +
                           ", " + std::to_string(sim.time.frame_end) + "]");
    }
}

void warn_doubtful(const SimModel& sim, const std::optional<SurfaceParams>& surface,
                   const std::string& shot_path) {
    if (!surface) return;
    // an intact region at uniform Jw has edge ratio Jw^(1/3); Eq. 14's threshold falls as Jw zeta,
    // so fully dried intact soil (Jw = 1 - eta) breaks unless zeta >= (1 - eta)^(-2/3)
    const bool is_jw_scaled =
        sim.moisture && surface->mode == SurfaceMode::Ours && !surface->length_consistent;
    const Real eta = sim.moisture ? sim.moisture->eta : 0;
    const Real bound = is_jw_scaled ? std::pow(1 - eta, -2.0 / 3.0) : 1.0;
    if (surface->zeta >= bound) return;
    const std::string why = is_jw_scaled
        ? "(1 - eta)^(-2/3) = " + g(bound) + " for /moisture/eta = " + g(eta) +
              ": intact soil that dries fully will crack everywhere (physics.md 5.5)"
        : "1: intact material breaks at rest";
    log::warn("zeta-below-bound",
              shot_path + ": /surfacing/zeta = " + g(surface->zeta) + " is below " + why);
}

}  // namespace mudcrack::spec
