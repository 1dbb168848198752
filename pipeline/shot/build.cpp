#include "pipeline/shot/build.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <variant>

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
bool has(const json& tree, const std::string& pointer) {
    return find_value(tree, pointer) != nullptr;
}
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

void read_into(const json& tree, const std::string& pointer, Real& out) {
    out = number(tree, pointer);
}
void read_into(const json& tree, const std::string& pointer, int& out) {
    out = integer(tree, pointer);
}
void read_into(const json& tree, const std::string& pointer, bool& out) {
    out = boolean(tree, pointer);
}
void read_into(const json& tree, const std::string& pointer, std::string& out) {
    out = text(tree, pointer);
}
void read_into(const json& tree, const std::string& pointer, Vec3& out) {
    out = vec3(tree, pointer);
}

// one member of a typed params struct and its key inside the struct's shot section
template <class S>
struct Field {
    const char* key;
    std::variant<Real S::*, int S::*, bool S::*, std::string S::*, Vec3 S::*> member;
};

// copies each key of `section` into its member of `out`; the keys must be in the filled tree
// (keys with a default always are), so optional keys stay with their own has() test
template <class S>
void read_fields(const json& tree, const std::string& section, S& out,
                 std::initializer_list<Field<S>> fields) {
    for (const Field<S>& f : fields) {
        const std::string pointer = section + "/" + f.key;
        std::visit([&](auto member) { read_into(tree, pointer, out.*member); }, f.member);
    }
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
        issues.add(
            pointer, value_text(&tree.at(p)),
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
                   "must name a shot that does not set /reuse itself (" + other.string() +
                       " reuses " + value_text(&root["reuse"]) + "; name that shot instead)");
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

void build_mesh(json& tree, const std::string& shot_path, MeshSource& mesh, Issues& issues) {
    if (has(tree, "/source/mesh/path"))
        mesh.path = resolve_existing(tree, "/source/mesh/path", shot_path, issues);
    else if (!issues.has("/source/mesh/path"))
        issues.add("/source/mesh/path", "(missing)", "required when /source/type = \"mesh\"");
    read_fields<MeshSource>(tree, "/source/mesh", mesh,
                            {{"scale", &MeshSource::scale},
                             {"translate", &MeshSource::translate},
                             {"fit_to_ground", &MeshSource::fit_to_ground}});
}

void build_box(const json& tree, BoxSource& box, Issues& issues) {
    read_fields<BoxSource>(tree, "/source/box", box,
                           {{"min", &BoxSource::min},
                            {"max", &BoxSource::max},
                            {"spacing", &BoxSource::spacing},
                            {"jitter", &BoxSource::jitter}});
    const std::string lattice = text(tree, "/source/box/lattice");
    box.lattice = lattice == "jittered" ? Lattice::Jittered
                  : lattice == "mesh"   ? Lattice::Mesh
                                        : Lattice::Regular;
    box.footprint = text(tree, "/source/box/footprint") == "ellipse" ? Footprint::Ellipse
                                                                     : Footprint::Rectangle;
    const bool bounds_reported = issues.has("/source/box");
    if (bounds_reported) return;
    if (!all_less(box.min, box.max)) {
        issues.add("/source/box/max", issues.value_of(tree, "/source/box/max"),
                   "must be > /source/box/min = " + issues.value_of(tree, "/source/box/min") +
                       " on every axis",
                   "m");
        return;
    }
    const Real smallest = (box.max - box.min).minCoeff();
    if (box.lattice != Lattice::Mesh && box.spacing > smallest)
        issues.add(
            "/source/box/spacing", issues.value_of(tree, "/source/box/spacing"),
            "must be <= the smallest box extent " + g(smallest) + " (at least one lattice cell)",
            "m");
}

void build_heightfield(json& tree, const std::string& shot_path, HeightfieldSource& hf,
                       Issues& issues) {
    const json& size = tree.at(json::json_pointer("/source/heightfield/size"));
    hf.size = Vec3(size[0].get<double>(), 0, size[1].get<double>());
    using H = HeightfieldSource;
    read_fields<H>(tree, "/source/heightfield", hf,
                   {{"base", &H::base},
                    {"amplitude", &H::amplitude},
                    {"channel_depth", &H::channel_depth},
                    {"channel_width", &H::channel_width},
                    {"channel_meander", &H::channel_meander},
                    {"image_height", &H::image_height},
                    {"spacing", &H::spacing}});
    hf.lattice = text(tree, "/source/heightfield/lattice") == "mesh" ? HeightfieldLattice::Mesh
                                                                     : HeightfieldLattice::Columns;
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
    read_fields<NaccParams>(tree, "/plasticity", nacc,
                            {{"alpha0", &NaccParams::alpha0},
                             {"xi", &NaccParams::xi},
                             {"M", &NaccParams::M},
                             {"hardening", &NaccParams::hardening}});
    // Table 1 gives one beta; beta0 and beta1 default to it (docs/physics.md §4.8 T21)
    const Real beta = has(tree, "/plasticity/beta") ? number(tree, "/plasticity/beta") : Real(1);
    nacc.beta0 = has(tree, "/plasticity/beta0") ? number(tree, "/plasticity/beta0") : beta;
    nacc.beta1 = has(tree, "/plasticity/beta1") ? number(tree, "/plasticity/beta1") : beta;
    if (has(tree, "/plasticity/damage_strain"))
        nacc.damage_strain = number(tree, "/plasticity/damage_strain");
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
    using M = MoistureParams;
    read_fields<M>(tree, "/moisture", m,
                   {{"eta", &M::eta},
                    {"k_r", &M::k_r},
                    {"eps", &M::eps},
                    {"D", &M::D},
                    {"lambda", &M::lambda},
                    {"theta0", &M::theta0},
                    {"cg_tolerance", &M::cg_tolerance},
                    {"cg_max_iterations", &M::cg_max_iterations},
                    {"seal_colliders", &M::seal_colliders},
                    {"implicit_robin", &M::implicit_robin},
                    {"interval", &M::interval},
                    {"max_log_jw_step", &M::max_log_jw_step}});
    m.evaporation = text(tree, "/moisture/evaporation") == "surface"
                        ? MoistureParams::Evaporation::Surface
                        : MoistureParams::Evaporation::Grid;
    // optional, so the slices of the shots that leave it out (the paper's operator) stay as they
    // were and their caches stay valid
    m.diffusion_operator = has(tree, "/moisture/diffusion_operator") &&
                                   text(tree, "/moisture/diffusion_operator") == "grid"
                               ? MoistureParams::DiffusionOperator::Grid
                               : MoistureParams::DiffusionOperator::Particles;
    if (m.implicit_robin && m.diffusion_operator == MoistureParams::DiffusionOperator::Grid)
        issues.add("/moisture/implicit_robin", issues.value_of(tree, "/moisture/implicit_robin"),
                   "must be false with /moisture/diffusion_operator = \"grid\" (the implicit "
                   "Robin term is a particle sum; the grid operator makes no particle pass)");
    if (m.implicit_robin && m.evaporation == MoistureParams::Evaporation::Surface)
        issues.add(
            "/moisture/implicit_robin", issues.value_of(tree, "/moisture/implicit_robin"),
            "must be false with /moisture/evaporation = \"surface\" (the surface layer's decay is "
            "exact; the implicit Robin term belongs to the grid evaporation)");
    // the ramp's frames as times: frame f ends at f / fps
    if (has(tree, "/moisture/evaporation_ramp") && !issues.has("/moisture/evaporation_ramp") &&
        !issues.has("/frames/fps")) {
        const json& ramp = tree.at(json::json_pointer("/moisture/evaporation_ramp"));
        const Real start = ramp[0].get<double>(), full = ramp[1].get<double>();
        const Real fps = number(tree, "/frames/fps");
        if (!(full > start))
            issues.add("/moisture/evaporation_ramp",
                       issues.value_of(tree, "/moisture/evaporation_ramp"),
                       "must be [start, full] with full > start (the frame by which evaporation "
                       "reaches lambda comes after the one where it begins)");
        m.evaporation_ramp_start = start / fps;
        m.evaporation_ramp_end = full / fps;
    }
    // particles start fully saturated unless told otherwise (MoistureParams::initial_theta); the
    // slice records the value they start at, unclamped so the range check below still sees it
    m.theta_init = has(tree, "/moisture/theta_init") ? number(tree, "/moisture/theta_init")
                                                     : m.initial_theta();
    tree["moisture"]["theta_init"] = m.theta_init;
    if (!issues.has("/moisture/eta")) {
        const std::string within = "must be in [0, /moisture/eta = " + g(m.eta) + "]";
        if (m.theta_init > m.eta && !issues.has("/moisture/theta_init"))
            issues.add("/moisture/theta_init", issues.value_of(tree, "/moisture/theta_init"),
                       within);
        if (m.theta0 > m.eta && !issues.has("/moisture/theta0"))
            issues.add("/moisture/theta0", issues.value_of(tree, "/moisture/theta0"), within);
    }
    model.moisture = m;
}

void build_time(const json& tree, SimModel& model, Issues& issues) {
    TimeParams& t = model.time;
    using T = TimeParams;
    read_fields<T>(tree, "/sim", t,
                   {{"dt_max", &T::dt_max},
                    {"cfl_velocity", &T::cfl_velocity},
                    {"cfl_elastic", &T::cfl_elastic}});
    read_fields<T>(tree, "/frames", t,
                   {{"fps", &T::fps}, {"start", &T::frame_start}, {"end", &T::frame_end}});
    if (t.frame_end < t.frame_start && !issues.has("/frames"))
        issues.add("/frames/end", issues.value_of(tree, "/frames/end"),
                   "must be >= /frames/start = " + std::to_string(t.frame_start));
    if (!has(tree, "/sim/dt")) return;
    t.dt_fixed = number(tree, "/sim/dt");
    // explicit MPM blows up above the elastic wave bound (docs/physics.md §1.7): refuse it at load
    const bool are_inputs_ok =
        !issues.has("/material") && !issues.has("/sim/h") && !issues.has("/sim/cfl_elastic");
    const Real bound = elastic_dt_bound(model);
    if (are_inputs_ok && t.dt_fixed > bound) {
        const ElasticParams& e = model.elastic;
        issues.add("/sim/dt", issues.value_of(tree, "/sim/dt"),
                   "exceeds the elastic bound C_E h / c_p = " + g(bound) +
                       " s (C_E=" + g(t.cfl_elastic) + ", h=" + g(model.h) +
                       " m, E=" + g(e.youngs_modulus) + " Pa, nu=" + g(e.poisson_ratio) +
                       ", rho=" + g(e.density) + " kg/m^3, c_p=" + g(e.wave_speed()) +
                       " m/s); lower /sim/dt or omit it for adaptive steps");
    }
}

void build_colliders(const json& tree, SimModel& model, Issues& issues) {
    if (has(tree, "/colliders/ground")) {
        GroundParams ground;
        read_fields<GroundParams>(
            tree, "/colliders/ground", ground,
            {{"height", &GroundParams::height}, {"friction", &GroundParams::friction}});
        ground.mode = collider_mode(text(tree, "/colliders/ground/mode"));
        model.ground = ground;
    }
    if (has(tree, "/colliders/domain")) {
        DomainParams& d = model.domain;
        d.is_auto = false;
        read_fields<DomainParams>(tree, "/colliders/domain", d,
                                  {{"min", &DomainParams::min},
                                   {"max", &DomainParams::max},
                                   {"padding", &DomainParams::padding}});
        if (!issues.has("/colliders/domain") && !all_less(d.min, d.max))
            issues.add("/colliders/domain/max", issues.value_of(tree, "/colliders/domain/max"),
                       "must be > /colliders/domain/min = " +
                           issues.value_of(tree, "/colliders/domain/min") + " on every axis",
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
    init.seed =
        static_cast<unsigned>(tree.at(json::json_pointer("/init/seed")).get<std::int64_t>());
    if (has(tree, "/init/strength_field")) {
        StrengthFieldParams field;
        field.correlation_length = number(tree, "/init/strength_field/correlation_length");
        field.weibull_modulus = number(tree, "/init/strength_field/weibull_modulus");
        field.azimuths = text(tree, "/init/strength_field/azimuths") == "random"
                             ? ModeAzimuths::Random
                             : ModeAzimuths::Even;
        init.strength_field = field;
        if (!has(tree, "/plasticity"))
            issues.add(
                "/init/strength_field", "(set)",
                "needs /plasticity: the field multiplies the NACC yield pressure p0, which pure "
                "elasticity does not have");
    }
    if (!has_type) return init;  // already reported; which source settings apply is unknown
    switch (init.type) {
        case SourceType::Mesh: build_mesh(tree, shot_path, init.mesh, issues); break;
        case SourceType::Box: build_box(tree, init.box, issues); break;
        case SourceType::Heightfield:
            build_heightfield(tree, shot_path, init.heightfield, issues);
            break;
    }
    // only the selected source's settings matter downstream
    json& source = tree["source"];
    for (const char* kind : kSourceKinds)
        if (kSourceKinds[static_cast<int>(init.type)] != std::string(kind)) source.erase(kind);
    return init;
}

SimModel build_sim(json& tree, Issues& issues) {
    SimModel model;
    read_fields<SimModel>(tree, "/sim", model,
                          {{"h", &SimModel::h},
                           {"gravity", &SimModel::gravity},
                           {"checkpoint_every", &SimModel::checkpoint_every},
                           {"grid_shift", &SimModel::grid_shift_interval},
                           {"grid_turn", &SimModel::grid_turn_interval}});
    model.grid_turn_angles = text(tree, "/sim/grid_turn_angles") == "random"
                                 ? SimModel::TurnAngles::Random
                                 : SimModel::TurnAngles::Golden;
    model.precision =
        text(tree, "/sim/precision") == "float" ? StatePrecision::Float : StatePrecision::Double;
    model.initial_velocity = vec3(tree, "/source/initial_velocity");
    read_fields<ElasticParams>(tree, "/material", model.elastic,
                               {{"density", &ElasticParams::density},
                                {"youngs_modulus", &ElasticParams::youngs_modulus},
                                {"poisson_ratio", &ElasticParams::poisson_ratio}});
    build_plasticity(tree, model);
    build_moisture(tree, model, issues);
    build_time(tree, model, issues);
    build_colliders(tree, model, issues);
    return model;
}

std::optional<SurfaceParams> build_surface(const json& tree, Issues& issues) {
    if (!has(tree, "/surfacing")) return std::nullopt;
    SurfaceParams s;
    s.mode = *parse_surface_mode(text(tree, "/surfacing/mode"));  // the spec admits only mode names
    using S = SurfaceParams;
    read_fields<S>(tree, "/surfacing", s,
                   {{"zeta", &S::zeta},
                    {"length_consistent", &S::length_consistent},
                    {"cracks", &S::cracks},
                    {"format", &S::format},
                    {"min_fragment_particles", &S::min_fragment_particles},
                    {"min_piece_size", &S::min_piece_size},
                    {"debris_gap", &S::debris_gap},
                    {"close_gaps", &S::close_gaps},
                    {"open_speed", &S::open_speed},
                    {"wall_smoothing", &S::wall_smoothing}});
    s.debris =
        text(tree, "/surfacing/debris") == "points" ? DebrisOutput::Points : DebrisOutput::None;
    if (debris_needs_plates(s))
        issues.add(
            "/surfacing/debris", issues.value_of(tree, "/surfacing/debris"),
            "needs /surfacing/mode = \"plates\" (only the plates mode tells debris from the pieces)");
    return s;
}

std::optional<RenderParams> build_render(const json& tree) {
    if (!has(tree, "/render")) return std::nullopt;
    RenderParams r;
    const json& resolution = tree.at(json::json_pointer("/render/resolution"));
    r.width = static_cast<int>(resolution[0].get<std::int64_t>());
    r.height = static_cast<int>(resolution[1].get<std::int64_t>());
    r.color_mode = parse_color_mode(text(tree, "/render/color_mode")).value_or(ColorMode::Moisture);
    r.camera.is_auto = !has(tree, "/render/camera");
    if (!r.camera.is_auto) {
        using C = CameraParams;
        read_fields<C>(tree, "/render/camera", r.camera,
                       {{"position", &C::position}, {"target", &C::target}, {"fov", &C::fov_deg}});
    }
    using R = RenderParams;
    read_fields<R>(tree, "/render", r,
                   {{"samples", &R::samples},
                    {"albedo", &R::albedo},
                    {"alpha_range", &R::alpha_range},
                    {"fps", &R::fps}});
    r.turntable = has(tree, "/render/turntable");
    if (r.turntable)
        read_fields<R>(tree, "/render/turntable", r,
                       {{"views", &R::turntable_views}, {"frame", &R::turntable_frame}});
    return r;
}

namespace {

// whether the shot has the physics a cached attribute needs
bool has_cache_physics(CachePhysics physics, const SimModel& sim,
                       const std::optional<SurfaceParams>& surface) {
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

CacheAttributes derive_cache(const json& tree, const SimModel& sim,
                             const std::optional<SurfaceParams>& surface, Issues& issues) {
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
            issues.add(pointer, "true",
                       std::string("the shot has no ") + a.vdb_name + " to cache: needs " +
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
                   "must be in [" + g(d.min.y()) + ", " + g(d.max.y()) + ") (the domain's y range)",
                   "m");
    // a turned grid turns the walls with it about the vertical, and would need gravity turned too
    if (sim.grid_turn_interval > 0 && !issues.has("/sim/grid_turn")) {
        if (!d.is_auto)
            issues.add("/sim/grid_turn", issues.value_of(tree, "/sim/grid_turn"),
                       "needs the domain derived from the particles (the domain's walls turn "
                       "with the grid): leave /colliders/domain out");
        if (sim.gravity.x() != 0 || sim.gravity.z() != 0)
            issues.add("/sim/grid_turn", issues.value_of(tree, "/sim/grid_turn"),
                       "needs a vertical /sim/gravity (the grid turns about the vertical), not " +
                           issues.value_of(tree, "/sim/gravity"));
    }
    if (render && render->turntable && !issues.has("/render/turntable/frame") &&
        !issues.has("/frames")) {
        const int f = render->turntable_frame;
        if (f != -1 && (f < sim.time.frame_start || f > sim.time.frame_end))
            issues.add("/render/turntable/frame", issues.value_of(tree, "/render/turntable/frame"),
                       "must be -1 (the last frame) or a frame in [" +
                           std::to_string(sim.time.frame_start) + ", " +
                           std::to_string(sim.time.frame_end) + "]");
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
    const std::string why =
        is_jw_scaled
            ? "(1 - eta)^(-2/3) = " + g(bound) + " for /moisture/eta = " + g(eta) +
                  ": intact soil that dries fully will crack everywhere (docs/physics.md §5.5)"
            : "1: intact material breaks at rest";
    log::warn("zeta-below-bound",
              shot_path + ": /surfacing/zeta = " + g(surface->zeta) + " is below " + why);
}

}  // namespace mudcrack::spec
