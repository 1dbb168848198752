// The stability matrix: stiff and extreme cases run with a step budget and a wall-time limit.
// Each case either completes, is refused with an InputError, or stops with a RuntimeError; a
// non-finite state that nothing reported, a hang or a crash is a failure of the product.
#include "tools/report/stability.h"

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>

#include "pipeline/shot/shot.h"
#include "sim/core/error.h"
#include "sim/core/tet_mesh.h"
#include "sim/mpm/simulation.h"
#include "sim/mpm/step_retry.h"
#include "tools/report/energy.h"
#include "tools/report/format.h"
#include "tools/report/scenes.h"

extern char** environ;

namespace mudcrack::report {

namespace {

constexpr Real kGravity = 9.81;

// what a case runs: a model and particles, or a shot text that must pass the shot loader first
struct CaseSetup {
    SimModel model;
    ParticleBlock particles;
    std::string shot_json;  // non-empty: parse_shot(shot_json) runs first, as mc-sim would
};

// the common scene: a 0.2 m cube of 2x2x2 particles per cell, 0.05 m above a sticky ground,
// under gravity, elastic E = 1e4 Pa, nu = 0.3, rho = 1000 kg/m^3
CaseSetup base_scene(Scale scale) {
    const Real h = scale == Scale::Full ? 0.025 : 0.05;
    CaseSetup c;
    c.model = bare_model(h, 1e4, 0.3, 1000);
    c.model.gravity = Vec3(0, -kGravity, 0);
    c.model.ground = GroundParams{};
    const int n = static_cast<int>(std::lround(0.2 / (h / 2)));
    c.particles = lattice_block(Vec3(0, 0.05, 0), Vec3i(n, n, n), h / 2);
    return c;
}

NaccParams soil_nacc() {
    NaccParams p;
    p.alpha0 = std::log(0.99);
    p.M = 1.85;
    p.beta0 = p.beta1 = 2;
    p.xi = 3;
    return p;
}

// drying soil on the ground: NACC plus moisture with evaporation
CaseSetup drying_scene(Scale scale, Real eta) {
    CaseSetup c = base_scene(scale);
    c.model.nacc = soil_nacc();
    c.model.moisture = MoistureParams{};
    c.model.moisture->eta = eta;
    c.model.moisture->D = 0.02;
    c.model.moisture->lambda = 0.5;
    return c;
}

// a fixed dt below the elastic bound and D such that D dt / h^2 = ratio
CaseSetup diffusion_number_scene(Scale scale, Real ratio) {
    CaseSetup c = drying_scene(scale, 0.5);
    SimModel dry = c.model;
    dry.elastic.density *= 1 - c.model.moisture->eta;
    c.model.time.dt_fixed = 0.5 * elastic_dt_bound(dry);
    c.model.moisture->D = ratio * c.model.h * c.model.h / c.model.time.dt_fixed;
    return c;
}

// a block thrown at a wall of a fixed domain box, no gravity and no ground
CaseSetup wall_impact_scene(Scale scale, const Vec3& velocity, bool with_nacc) {
    CaseSetup c = base_scene(scale);
    c.model.gravity = Vec3::Zero();
    c.model.ground.reset();
    if (with_nacc) c.model.nacc = soil_nacc();
    c.model.initial_velocity = velocity;
    c.model.domain.is_auto = false;
    c.model.domain.min = Vec3(-0.4, -0.4, -0.4);
    c.model.domain.max = Vec3(0.6, 0.6, 0.6);
    return c;
}

// four particles at the corners of a tet, with their rest volumes from the tet (a quarter each,
// as particle_rest_volumes gives mc-init's particles), appended to the block's particles
void append_tet(ParticleBlock& b, const std::array<Vec3, 4>& corners) {
    TetMesh mesh;
    mesh.X.assign(corners.begin(), corners.end());
    mesh.tets.push_back({0, 1, 2, 3});
    const std::vector<Real> volumes = particle_rest_volumes(mesh);
    for (int k = 0; k < 4; ++k) {
        b.X.push_back(corners[k]);
        b.V0.push_back(volumes[k]);
    }
}

// the degenerate-tet cases: one tet from init, on top of the base block or alone
struct DegenerateTet {
    const char* name;
    const char* description;
    bool keeps_block;
    std::array<Vec3, 4> corners;
};
const DegenerateTet kDegenerateTets[] = {
    {"tet_flat",
     "block plus a flat (coplanar) tet from init: zero rest volumes",
     true,
     {Vec3(0.05, 0.3, 0.05), Vec3(0.1, 0.3, 0.05), Vec3(0.05, 0.3, 0.1), Vec3(0.1, 0.3, 0.1)}},
    {"tet_needle",
     "block plus a needle tet (0.1 m long, 1e-6 m wide) on its top",
     true,
     {Vec3(0.1, 0.26, 0.1), Vec3(0.1, 0.36, 0.1), Vec3(0.100001, 0.3, 0.1),
      Vec3(0.1, 0.3, 0.100001)}},
    {"tet_sliver_alone",
     "a lone sliver tet (rest volume ~1e-20 m^3) falling onto the ground",
     false,
     {Vec3(0.1, 0.1, 0.1), Vec3(0.13, 0.1, 0.1), Vec3(0.1, 0.13, 0.1),
      Vec3(0.115, 0.115, 0.1 + 1e-16)}},
};

// the shot of the "dt past the elastic bound" case: dt twice the bound, through the shot loader
std::string dt_past_bound_shot() {
    SimModel m;
    m.h = 0.02;
    m.elastic.youngs_modulus = 1e4;
    m.elastic.poisson_ratio = 0.3;
    m.elastic.density = 1000;
    const Real dt = 2 * elastic_dt_bound(m);
    return format(R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"youngs_modulus": 1e4, "poisson_ratio": 0.3, "density": 1000},
        "sim": {"h": 0.02, "dt": %.6g}})",
                  dt);
}

// a case's setup: the base scene, or a drying one at porosity eta, with one change
using SetupChange = std::function<void(CaseSetup&)>;
std::function<CaseSetup(Scale)> on_base(SetupChange change) {
    return [change](Scale s) {
        CaseSetup c = base_scene(s);
        change(c);
        return c;
    };
}
std::function<CaseSetup(Scale)> on_drying(Real eta, SetupChange change) {
    return [eta, change](Scale s) {
        CaseSetup c = drying_scene(s, eta);
        change(c);
        return c;
    };
}

struct CaseEntry {
    StabilityCase info;
    std::function<CaseSetup(Scale)> setup;
};

const std::vector<CaseEntry>& case_table() {
    static const std::vector<CaseEntry> table = [] {
        std::vector<CaseEntry> t;
        auto add = [&](std::string name, std::string group, std::string desc,
                       std::function<CaseSetup(Scale)> fn) {
            t.push_back({{std::move(name), std::move(group), std::move(desc)}, std::move(fn)});
        };
        for (Real E : {1e2, 1e4, 1e6, 1e8})
            add(format("E_%.0e", E), "stiffness",
                format(
                    "elastic block dropped on a sticky ground, E = %.0e Pa, nu = 0.3, adaptive dt",
                    E),
                on_base([E](CaseSetup& c) { c.model.elastic.youngs_modulus = E; }));
        for (Real nu : {0.45, 0.49, 0.499})
            add(format("nu_%g", nu), "incompressibility",
                format("elastic block dropped, E = 1e4 Pa, nu = %g", nu),
                on_base([nu](CaseSetup& c) { c.model.elastic.poisson_ratio = nu; }));
        add("nacc_nu_0.499", "incompressibility", "NACC soil block dropped, nu = 0.499",
            on_base([](CaseSetup& c) {
                c.model.elastic.poisson_ratio = 0.499;
                c.model.nacc = soil_nacc();
            }));
        for (Real eta : {0.0, 0.5, 0.9, 0.95})
            add(format("eta_%g", eta), "porosity",
                format("NACC soil drying on the ground, eta = %g, lambda = 0.5 m/s", eta),
                [eta](Scale s) { return drying_scene(s, eta); });
        add("sinh_overflow_alpha0", "hardening",
            "NACC with xi = 1000, alpha0 = -1: xi*alpha = 1000, sinh overflows",
            on_base([](CaseSetup& c) {
                c.model.nacc = soil_nacc();
                c.model.nacc->xi = 1000;
                c.model.nacc->alpha0 = -1;
            }));
        add("sinh_overflow_drying", "hardening",
            "drying drives alpha down: eps = 50, eta = 0.95, xi = 10, lambda = 50 m/s (xi*|alpha| -> 1500)",
            on_drying(0.95, [](CaseSetup& c) {
                c.model.nacc->xi = 10;
                c.model.moisture->eps = 50;
                c.model.moisture->lambda = 50;
                c.model.moisture->max_log_jw_step = 0;  // no cap: the whole jump at once
            }));
        add("evaporation_one_step", "evaporation",
            "lambda = 1e4 m/s: the surface layer dries completely in one step",
            on_drying(0.5, [](CaseSetup& c) { c.model.moisture->lambda = 1e4; }));
        add("evaporation_one_step_uncapped", "evaporation",
            "lambda = 1e4 m/s with no cap on the per-step pore change (max_log_jw_step = 0)",
            on_drying(0.5, [](CaseSetup& c) {
                c.model.moisture->lambda = 1e4;
                c.model.moisture->max_log_jw_step = 0;
            }));
        for (Real r : {1e2, 1e4})
            add(format("D_dt_h2_%.0e", r), "diffusion number",
                format("drying soil with D dt/h^2 = %.0e at a fixed dt = half the elastic bound",
                       r),
                [r](Scale s) { return diffusion_number_scene(s, r); });
        for (Real r : {1e2, 1e4})
            add(format("D_dt_h2_%.0e_grid_operator", r), "diffusion number",
                format("drying soil with D dt/h^2 = %.0e at a fixed dt = half the elastic bound, "
                       "the grid operator (docs/physics.md §4.9)",
                       r),
                [r](Scale s) {
                    CaseSetup c = diffusion_number_scene(s, r);
                    c.model.moisture->diffusion_operator = MoistureParams::DiffusionOperator::Grid;
                    return c;
                });
        add("dt_past_bound_shot", "time step",
            "shot with /sim/dt = 2x the elastic bound, through the shot loader",
            on_base([](CaseSetup& c) { c.shot_json = dt_past_bound_shot(); }));
        add("dt_past_bound_forced", "time step",
            "dt = 3x the elastic bound forced in-process (bypasses the shot check)",
            on_base([](CaseSetup& c) { c.model.time.dt_fixed = 3 * elastic_dt_bound(c.model); }));
        add("wall_impact_20", "impacts", "elastic block thrown at 20 m/s into a domain wall",
            [](Scale s) { return wall_impact_scene(s, Vec3(20, 0, 0), false); });
        add("wall_impact_200", "impacts",
            "NACC block thrown at (200, -100, 50) m/s into the domain corner",
            [](Scale s) { return wall_impact_scene(s, Vec3(200, -100, 50), true); });
        add("ground_impact_50", "impacts", "NACC block falling at 50 m/s onto the sticky ground",
            on_base([](CaseSetup& c) {
                c.model.nacc = soil_nacc();
                c.model.initial_velocity = Vec3(0, -50, 0);
            }));
        for (const DegenerateTet& d : kDegenerateTets)
            add(d.name, "degenerate tets", d.description, on_base([d](CaseSetup& c) {
                    if (!d.keeps_block) c.particles = {};
                    append_tet(c.particles, d.corners);
                }));
        return t;
    }();
    return table;
}

// any non-finite value in the state; what the sim's own check must have reported
template <class S>
bool has_non_finite(const SimStateOf<S>& s) {
    for (size_t p = 0; p < s.size(); ++p) {
        if (!s.x[p].allFinite() || !s.v[p].allFinite() || !s.Fe[p].allFinite() ||
            !s.C[p].allFinite() || !std::isfinite(s.J[p]) || !std::isfinite(s.mass[p]))
            return true;
        if (!s.theta.empty() && (!std::isfinite(s.theta[p]) || !std::isfinite(s.Jw[p])))
            return true;
        if (!s.alpha.empty() && !std::isfinite(s.alpha[p])) return true;
    }
    return false;
}

std::string one_line(std::string s) {
    std::replace(s.begin(), s.end(), '\n', ' ');
    std::replace(s.begin(), s.end(), '\t', ' ');
    return s;
}

}  // namespace

const char* outcome_name(Outcome outcome) {
    switch (outcome) {
        case Outcome::Completed: return "completed";
        case Outcome::Refused: return "refused";
        case Outcome::StoppedWithError: return "stopped with error";
        case Outcome::SilentNaN: return "FAILURE: silent NaN";
        case Outcome::Hang: return "FAILURE: hang";
        case Outcome::Crashed: return "FAILURE: crash";
        case Outcome::Diverged: return "completed, diverged";
    }
    return "?";
}

StabilityLimits stability_limits(Scale scale) {
    StabilityLimits l;
    if (scale == Scale::Full) {
        l.max_steps = 400;
        l.max_wall_s = 120;
    } else {
        l.max_steps = 60;
        l.max_wall_s = 20;
    }
    return l;
}

std::vector<StabilityCase> stability_cases() {
    std::vector<StabilityCase> out;
    for (const CaseEntry& e : case_table()) {
        out.push_back(e.info);
        out.push_back(
            {e.info.name + kFloatCaseSuffix, e.info.group, e.info.description + " (float state)"});
    }
    return out;
}

namespace {

// what the accepted steps of a stability case add up to; a rollback returns to the tally of its
// rollback point
struct Tally {
    int64_t steps = 0;
    Real max_speed = 0;
    Real e_scale = 0, e_max = 0, e_last = 0;  // energy: largest |total| seen, largest, last
};

template <class S>
void sample_energy(const SimModel& model, const SimStateOf<S>& s, Tally& tally) {
    tally.e_last = state_energy(model, s).total();
    tally.e_max = std::max(tally.e_max, tally.e_last);
    tally.e_scale = std::max(tally.e_scale, std::abs(tally.e_last));
}

// steps the case until the step limit, the wall-time limit, a non-finite state or an error;
// failed substeps are retried as in mc-sim (sim/mpm/step_retry.h), from the state at t = 0.
// Sets r's outcome and message.
template <class S>
void step_case(const SimModel& model, SimStateOf<S>& s, const StabilityLimits& limits,
               const WallClock& clock, Tally& tally, RetryingStepperOf<S>& stepper,
               StabilityResult& r) {
    stepper.restart(s);
    Tally at_rollback_point = tally;
    r.outcome = Outcome::Completed;
    try {
        while (tally.steps < limits.max_steps) {
            if (clock.seconds() > limits.max_wall_s) {
                r.outcome = Outcome::Hang;
                r.message = format("exceeded %.0f s of wall time after %lld steps",
                                   limits.max_wall_s, static_cast<long long>(tally.steps));
                break;
            }
            const StepAttempt a =
                stepper.attempt(model, s, stable_dt(model, s) * stepper.dt_scale());
            if (!a.is_accepted) {
                tally = at_rollback_point;
                continue;
            }
            ++tally.steps;
            if (has_non_finite(s)) {
                r.outcome = Outcome::SilentNaN;
                r.message = format("non-finite state after step %lld and no error",
                                   static_cast<long long>(tally.steps));
                break;
            }
            tally.max_speed = std::max(tally.max_speed, a.stats.max_speed);
            if (tally.steps % 5 == 0 || tally.steps == limits.max_steps)
                sample_energy(model, s, tally);
            if (a.is_rollback_point) at_rollback_point = tally;
        }
    } catch (const RuntimeError& e) {
        r.outcome = Outcome::StoppedWithError;
        r.message = one_line(e.what());
    } catch (const InputError& e) {
        r.outcome = Outcome::StoppedWithError;
        r.message = one_line(std::string("input error while stepping: ") + e.what());
    } catch (const std::exception& e) {
        r.outcome = Outcome::Crashed;
        r.message = one_line(std::string("unexpected exception: ") + e.what());
    }
}

}  // namespace

namespace {

// the case from its initial state on, with a state of precision S; r holds its name
template <class S>
StabilityResult run_case_in(CaseSetup& c, const StabilityLimits& limits, const WallClock& clock,
                            StabilityResult r) {
    // refusals at load: the shot loader, then the initial state
    std::optional<SimStateOf<S>> state;
    try {
        if (!c.shot_json.empty()) {
            const StatePrecision precision = c.model.precision;
            c.model = parse_shot(c.shot_json, "stability_case.json").sim;
            c.model.precision = precision;
        }
        state.emplace(make_initial_state<S>(c.model, c.particles.X, c.particles.V0));
    } catch (const InputError& e) {
        r.outcome = Outcome::Refused;
        r.message = one_line(e.what());
        r.wall_s = clock.seconds();
        return r;
    }
    SimStateOf<S>& s = *state;

    // the steps, with the energy sampled along the way
    Tally tally;
    const Real e0 = state_energy(c.model, s).total();  // gravity from the ground, so >= 0
    tally.e_scale = std::abs(e0);
    tally.e_max = tally.e_last = e0;
    for (const auto& v : s.v) tally.max_speed = std::max<Real>(tally.max_speed, v.norm());
    RetryingStepperOf<S> stepper;
    step_case(c.model, s, limits, clock, tally, stepper, r);
    r.steps = tally.steps;
    r.retries = stepper.retries();
    r.max_speed = tally.max_speed;
    // an error without a message is not a clear error
    if (r.outcome == Outcome::StoppedWithError && r.message.empty()) {
        r.outcome = Outcome::Crashed;
        r.message = "a RuntimeError with an empty message";
    }
    r.sim_time = s.time;
    if (r.outcome == Outcome::Completed) sample_energy(c.model, s, tally);
    const Real denom = tally.e_scale > 0 ? tally.e_scale : Real(1);
    const bool is_energy_finite =
        std::isfinite(tally.e_last) && std::isfinite(tally.e_max) && std::isfinite(denom);
    const Real inf = std::numeric_limits<Real>::infinity();
    r.energy_drift = is_energy_finite ? (tally.e_last - e0) / denom : inf;
    r.energy_growth = is_energy_finite ? (tally.e_max - e0) / denom : inf;
    if (r.outcome == Outcome::Completed && !(r.energy_growth <= kDivergedEnergyGrowth)) {
        r.outcome = Outcome::Diverged;
        int inverted = 0;
        for (const auto& Fe : s.Fe) inverted += !(Fe.template cast<Real>().determinant() > 0);
        r.message =
            is_energy_finite
                ? format("energy grew to %.3g x its scale with no error", r.energy_growth)
                : format("elastic energy not finite: %d particles with det Fe <= 0, no error",
                         inverted);
    }
    r.wall_s = clock.seconds();
    return r;
}

}  // namespace

StabilityResult run_stability_case(const std::string& name, Scale scale,
                                   const StabilityLimits& limits) {
    // "<case>/float": the case with a float state
    const std::string suffix = kFloatCaseSuffix;
    const bool in_float = name.size() > suffix.size() &&
                          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
    const std::string base = in_float ? name.substr(0, name.size() - suffix.size()) : name;
    const auto& table = case_table();
    const auto it = std::find_if(table.begin(), table.end(),
                                 [&](const CaseEntry& e) { return e.info.name == base; });
    if (it == table.end())
        throw InputError("--case " + name + ": no such stability case (see --list-cases)");
    const WallClock clock;
    StabilityResult r;
    r.name = name;
    CaseSetup c = it->setup(scale);
    c.model.precision = in_float ? StatePrecision::Float : StatePrecision::Double;
    return with_state_precision(
        c.model.precision, [&](auto s) { return run_case_in<decltype(s)>(c, limits, clock, r); });
}

std::string serialize_result(const StabilityResult& r) {
    return format("%s%s\t%d\t%lld\t%lld\t%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t%s", result_line_tag(),
                  r.name.c_str(), static_cast<int>(r.outcome), static_cast<long long>(r.steps),
                  static_cast<long long>(r.retries), r.sim_time, r.max_speed, r.energy_drift,
                  r.energy_growth, r.wall_s, one_line(r.message).c_str());
}

bool parse_result(const std::string& line, StabilityResult& r) {
    const std::string tag = result_line_tag();
    if (line.compare(0, tag.size(), tag) != 0) return false;
    std::vector<std::string> f;
    std::stringstream ss(line.substr(tag.size()));
    std::string field;
    while (f.size() < 9 && std::getline(ss, field, '\t')) f.push_back(field);
    if (f.size() < 9) return false;
    std::getline(ss, r.message);
    try {
        r.name = f[0];
        const int outcome = std::stoi(f[1]);
        if (outcome < 0 || outcome > static_cast<int>(Outcome::Diverged)) return false;
        r.outcome = static_cast<Outcome>(outcome);
        r.steps = std::stoll(f[2]);
        r.retries = std::stoll(f[3]);
        r.sim_time = std::stod(f[4]);
        r.max_speed = std::stod(f[5]);
        r.energy_drift = std::stod(f[6]);
        r.energy_growth = std::stod(f[7]);
        r.wall_s = std::stod(f[8]);
    } catch (const std::exception&) {
        return false;
    }
    return true;
}

StabilityResult run_stability_case_isolated(const std::string& exe, const std::string& name,
                                            Scale scale, const StabilityLimits& limits,
                                            int threads) {
    StabilityResult r;
    r.name = name;
    const WallClock clock;
    int fds[2];
    if (pipe(fds) != 0)
        throw RuntimeError("stability case " + name + ": pipe() failed: " + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
    const std::string threads_arg = std::to_string(threads);
    std::vector<std::string> args = {exe, "--case", name, "--threads", threads_arg};
    if (scale == Scale::Reduced) args.push_back("--quick");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    if (rc != 0) {
        close(fds[0]);
        throw RuntimeError("stability case " + name + ": cannot run " + exe + ": " +
                           std::strerror(rc));
    }

    // read the child's output until it closes the pipe or the time is up
    const double limit = limits.max_wall_s + 30;  // grace: start-up and the last step
    std::string output;
    bool is_timed_out = false;
    char buf[4096];
    while (true) {
        const double left = limit - clock.seconds();
        if (left <= 0) {
            is_timed_out = true;
            break;
        }
        pollfd pfd{fds[0], POLLIN, 0};
        const int ready = poll(&pfd, 1, static_cast<int>(std::min(left, 1.0) * 1000) + 1);
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) continue;
        const ssize_t n = read(fds[0], buf, sizeof buf);
        if (n <= 0) break;
        output.append(buf, static_cast<size_t>(n));
    }
    close(fds[0]);
    if (is_timed_out) kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    r.wall_s = clock.seconds();

    // the result line, else the last line the child printed as the reason
    std::string last_line;
    std::stringstream lines(output);
    for (std::string line; std::getline(lines, line);) {
        if (parse_result(line, r)) {
            r.wall_s = clock.seconds();
            return r;
        }
        if (!line.empty()) last_line = line;
    }
    if (is_timed_out) {
        r.outcome = Outcome::Hang;
        r.message = format("killed after %.0f s without a result", limit);
    } else {
        r.outcome = Outcome::Crashed;
        r.message = WIFSIGNALED(status) ? format("died by signal %d (%s)", WTERMSIG(status),
                                                 strsignal(WTERMSIG(status)))
                                        : format("exited %d without a result", WEXITSTATUS(status));
        if (!last_line.empty()) r.message += ": " + one_line(last_line);
    }
    return r;
}

}  // namespace mudcrack::report
