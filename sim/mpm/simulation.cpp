// The MPM driver: initial state, time step, the consolidated step of docs/physics.md §7, cache
// views.
#include "sim/mpm/simulation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

#include "sim/core/check.h"
#include "sim/core/error.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"
#include "sim/moisture/pore.h"
#include "sim/mpm/cached_values.h"
#include "sim/mpm/transfer.h"
#include "sim/mpm/workspace.h"

namespace mudcrack {

namespace {

// the state's arrays are physically reordered by grid block every this many steps; in between
// the step reads them through the bin order (they stay nearly sorted)
constexpr int64_t kResortInterval = 16;
// auto domain: free cells kept below the lowest particle (or the ground) inside the wall band
constexpr int kAutoDomainCellsBelow = 3;
// auto domain: fraction of the particles' extent added above and around them
constexpr Real kAutoDomainMargin = 0.5;

// reorders an array of float- or double-component elements (a number, Vec3, Mat3) so slot i
// takes slot order[i], one component at a time through an n-Real buffer (a double holds either
// exactly)
template <class T>
void permute_components(std::vector<T>& a, const std::vector<int32_t>& order,
                        std::vector<Real>& buf) {
    if (a.empty()) return;
    using Component = typename PackedNumbers<T>::Scalar;
    static_assert(std::is_floating_point_v<Component>, "element must be made of numbers");
    constexpr int kComp = static_cast<int>(PackedNumbers<T>::kCount);
    Component* data = reinterpret_cast<Component*>(a.data());
    const int64_t n = static_cast<int64_t>(a.size());
    for (int k = 0; k < kComp; ++k) {
        parallel_for(n,
                     [&](int64_t i) { buf[i] = data[static_cast<int64_t>(order[i]) * kComp + k]; });
        parallel_for(n, [&](int64_t i) { data[i * kComp + k] = buf[i]; });
    }
}

// reorders a slot-index array (id) through the same Real buffer: int32 values are exact in a double
void permute_components(std::vector<int32_t>& a, const std::vector<int32_t>& order,
                        std::vector<Real>& buf) {
    const int64_t n = static_cast<int64_t>(a.size());
    parallel_for(n, [&](int64_t i) { buf[i] = static_cast<Real>(a[order[i]]); });
    parallel_for(n, [&](int64_t i) { a[i] = static_cast<int32_t>(buf[i]); });
}

template <class S>
void permute_state(SimStateOf<S>& s, const std::vector<int32_t>& order, std::vector<Real>& buf) {
    buf.resize(s.size());
    s.for_each_array(
        [&](const char*, auto& array, ArrayPresence) { permute_components(array, order, buf); });
}

bool is_identity(const std::vector<int32_t>& order) {
    for (size_t i = 0; i < order.size(); ++i)
        if (order[i] != static_cast<int32_t>(i)) return false;
    return true;
}

// splitmix64's output function: a number in [0, 1) from x, every bit of x stirred into it
Real splitmix64_unit(uint64_t x) {
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    x ^= x >> 31;
    return static_cast<Real>(x >> 11) * 0x1.0p-53;
}

constexpr uint64_t kGoldenGamma = 0x9E3779B97F4A7C15ull;  // splitmix64's increment

// The grid's offset in cells, each axis in [0, 1), for the steps from shift_index * interval on
// (splitmix64 of the index: a pure function of the step count, so a resumed run moves its grid
// as the uninterrupted run did).
Vec3 grid_shift_cells(uint64_t shift_index) {
    Vec3 u;
    uint64_t z = shift_index * 3;
    for (int d = 0; d < 3; ++d) u[d] = splitmix64_unit(z += kGoldenGamma);
    return u;
}

}  // namespace

// Golden: 4 psi_j = 2 pi frac((j + 1) g) is the golden rotation. Random: splitmix64's sequence from
// index 8.48e18 on (kTurnStream is that index times the increment), which the shift's indices
// (3 j, from 0 up) never reach, so a shot that both shifts and turns its grid does not turn it by
// its shifts.
Real grid_turn_angle(SimModel::TurnAngles angles, uint64_t turn_index) {
    if (angles == SimModel::TurnAngles::Golden) {
        constexpr Real kGoldenFraction = 0.6180339887498948482;  // (sqrt 5 - 1) / 2
        const Real turns = static_cast<Real>(turn_index + 1) * kGoldenFraction;
        return kPi / 2 * (turns - std::floor(turns));
    }
    constexpr uint64_t kTurnStream = 0xD1B54A32D192ED03ull;
    return 2 * kPi * splitmix64_unit(kTurnStream + turn_index * kGoldenGamma);
}

namespace {

// the rotation by `angle` about the vertical (y) axis: x toward -z for a positive angle
Mat3 rotation_about_vertical(Real angle) {
    const Real c = std::cos(angle), s = std::sin(angle);
    Mat3 r;
    r << c, 0, s, 0, 1, 0, -s, 0, c;
    return r;
}

// The angle of the grid a state with `step_count` steps is held in: the grid of its last step,
// and the world's (0) before the first.
Real state_turn_angle(const SimModel& model, int64_t step_count) {
    if (model.grid_turn_interval <= 0 || step_count == 0) return 0;
    return grid_turn_angle(
        model.grid_turn_angles,
        static_cast<uint64_t>(step_count - 1) / static_cast<uint64_t>(model.grid_turn_interval));
}

// Carries the state's directional arrays by `turn` about the vertical through `centre`: positions
// and velocities turn, the APIC matrix as a spatial tensor (R C R^T), Fe on its spatial side
// (R Fe: the current configuration turns, the rest and plastic ones do not). Every scalar (J,
// alpha, theta, the damage) is frame-indifferent.
template <class S>
void turn_state(SimStateOf<S>& s, const Mat3& turn, const Vec3& centre) {
    const Mat3 turn_t = turn.transpose();
    parallel_for(static_cast<int64_t>(s.size()), [&](int64_t p) {
        const Vec3 x = s.x[p].template cast<Real>();
        s.x[p] = (turn * (x - centre) + centre).template cast<S>();
        s.v[p] = (turn * s.v[p].template cast<Real>()).template cast<S>();
        s.C[p] = (turn * s.C[p].template cast<Real>() * turn_t).template cast<S>();
        s.Fe[p] = (turn * s.Fe[p].template cast<Real>()).template cast<S>();
    });
}

// The grid for the state's next step. A moving grid (/sim/grid_shift) starts u h below the domain
// and ends (1 - u) h above it, one cell more per axis: it covers the domain whatever u is, and
// its wall band only moves outward.
template <class S>
SimWorkspace& ensure_workspace(const SimModel& model, SimStateOf<S>& state) {
    SimWorkspace& ws = state.workspace.get_or_create();
    if (model.grid_shift_interval > 0) {
        Vec3 u = grid_shift_cells(static_cast<uint64_t>(state.step_count) /
                                  static_cast<uint64_t>(model.grid_shift_interval));
        // over a ground, the grid keeps its height: the nodes at and below the ground plane are
        // what holds the soil (a sticky ground glues the cells they reach), and a grid moved up
        // and down lets go of the bottom layer and takes it again, period after period (the
        // demo lifted 10 % of its footprint off a sticky ground, against 0.8 % on a fixed grid)
        if (model.ground) u.y() = 0;
        ws.grid.geo = mpm::make_grid_geometry(state.domain_min - model.h * u,
                                              state.domain_max + model.h * (Vec3::Ones() - u),
                                              model.h, model.domain.padding);
    } else {
        ws.grid.geo = mpm::make_grid_geometry(state.domain_min, state.domain_max, model.h,
                                              model.domain.padding);
    }
    const int nt = std::max(1, thread_count());
    ws.windows.resize(nt);
    for (auto& w : ws.windows) w.resize(mpm::kWindowNodes * 8);
    return ws;
}

// bins the particles and, every kResortInterval steps and when forced (at t = 0 and at a grid
// turn), reorders the arrays by block (and the stress cache with them, when it is current)
template <class S>
void bin_and_sort(SimStateOf<S>& state, SimWorkspace& ws, bool force_sort, bool tau_is_current) {
    mpm::bin_particles(ws.grid, state.x, state.id);
    if ((force_sort || state.step_count % kResortInterval == 0) && !is_identity(ws.grid.order)) {
        permute_state(state, ws.grid.order, ws.permute_buffer);
        if (tau_is_current) permute_components(ws.tau, ws.grid.order, ws.permute_buffer);
        for (size_t i = 0; i < ws.grid.order.size(); ++i)
            ws.grid.order[i] = static_cast<int32_t>(i);
    }
}

constexpr Real kMaxCellsPerStep = 2;  // velocity CFL hard limit [cells/step]

template <class S>
std::string describe_non_finite(const SimStateOf<S>& s, size_t p, int64_t substep) {
    auto finite3 = [](const auto& m) { return m.allFinite(); };
    const char* what = nullptr;
    if (!finite3(s.x[p]))
        what = "non-finite position";
    else if (!finite3(s.v[p]))
        what = "non-finite velocity";
    else if (!finite3(s.Fe[p]))
        what = "non-finite elastic deformation gradient Fe";
    else if (!std::isfinite(s.J[p]))
        what = "non-finite volume ratio J";
    else if (!(s.J[p] > 0))
        what = "an inverted volume, J <= 0 (the step is unstable)";
    else if (!(s.Fe[p].template cast<Real>().determinant() > 0))
        what = "an inverted elastic deformation gradient, det Fe <= 0 (the step is unstable)";
    else if (!s.alpha.empty() && !std::isfinite(s.alpha[p]))
        what = "non-finite hardening state alpha";
    else if (!s.theta.empty() && !std::isfinite(s.theta[p]))
        what = "non-finite water content theta";
    if (!what) return {};
    std::ostringstream os;
    os << "substep " << substep << ": particle " << s.id[p] << " has " << what
       << " (theta=" << (s.theta.empty() ? std::string("n/a") : std::to_string(s.theta[p]))
       << ", J=" << s.J[p]
       << ", alpha=" << (s.alpha.empty() ? std::string("n/a") : std::to_string(s.alpha[p]))
       << ", |v|=" << s.v[p].norm() << ")";
    return os.str();
}

// the smallest particle id with a non-finite state, described; empty if all are finite
template <class S>
std::string find_non_finite(const SimStateOf<S>& s, int64_t substep) {
    size_t best = s.size();
    for (size_t p = 0; p < s.size(); ++p) {
        if (best < s.size() && s.id[p] >= s.id[best]) continue;
        if (!describe_non_finite(s, p, substep).empty()) best = p;
    }
    return best < s.size() ? describe_non_finite(s, best, substep) : std::string();
}

// the initial particles' checks: sizes agree, positions and volumes finite, strengths > 0
void check_initial_particles(const SimModel& model, const std::vector<Vec3>& X,
                             const std::vector<Real>& V0, const std::vector<Real>& strength) {
    const size_t n = X.size();
    if (n == 0)
        throw InputError(
            "initial particles: the particle set is empty: need at least one particle");
    if (V0.size() != n) {
        std::ostringstream os;
        os << "initial particles: " << V0.size() << " rest volumes for " << n
           << " positions: must match";
        throw InputError(os.str());
    }
    // the shot spec refuses a bad /sim/h with the file, key and value; here it is a precondition
    MC_CHECK(model.h > 0 && std::isfinite(model.h));
    if (!strength.empty()) {
        if (!model.nacc)
            throw InputError("initial particles: a strength field needs plasticity (/plasticity)");
        if (strength.size() != n) {
            std::ostringstream os;
            os << "initial particles: " << strength.size() << " strength values for " << n
               << " positions: must match";
            throw InputError(os.str());
        }
        for (size_t p = 0; p < n; ++p)
            if (!(strength[p] > 0) || !std::isfinite(strength[p])) {
                std::ostringstream os;
                os << "initial particles: particle " << p << " has strength " << strength[p]
                   << ": need a finite p0 multiplier > 0";
                throw InputError(os.str());
            }
    }
    for (size_t p = 0; p < n; ++p) {
        if (!X[p].allFinite() || !(V0[p] > 0) || !std::isfinite(V0[p])) {
            std::ostringstream os;
            os << "initial particles: particle " << p << " has position (" << X[p].transpose()
               << ") and volume0 " << V0[p] << ": need a finite position and a finite volume > 0";
            throw InputError(os.str());
        }
    }
}

// the simulation box: given, or derived once from the particle bounds X
template <class S>
void set_domain(const SimModel& model, const std::vector<Vec3>& X, SimStateOf<S>& s) {
    Vec3 lo = X[0], hi = X[0];
    for (const Vec3& x : X) {
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
    }
    const Real h = model.h;
    const int pad = model.domain.padding;
    if (model.domain.is_auto) {
        // a turned grid's domain turns with it about its centre: around the footprint's centre,
        // it holds the disc the footprint sweeps, a square in x and z whatever the angle
        if (model.grid_turn_interval > 0) {
            const Real cx = (lo.x() + hi.x()) / 2, cz = (lo.z() + hi.z()) / 2;
            Real r2 = 0;
            for (const Vec3& x : X)
                r2 = std::max(r2, (x.x() - cx) * (x.x() - cx) + (x.z() - cz) * (x.z() - cz));
            const Real r = std::sqrt(r2);
            lo.x() = cx - r, hi.x() = cx + r;
            lo.z() = cz - r, hi.z() = cz + r;
        }
        const Vec3 extent = hi - lo;
        for (int d = 0; d < 3; ++d) {
            const Real margin =
                std::max(kAutoDomainMargin * extent[d], Real(kAutoDomainCellsBelow) * h) +
                (pad + 1) * h;
            s.domain_min[d] = lo[d] - margin;
            s.domain_max[d] = hi[d] + margin;
            // a free body: whole cells on both sides of a node at the particles' centre. On a
            // grid not symmetric about them, opposite faces reach different nodes (a face on a
            // node spreads mass one cell further than a face between two), so they evaporate
            // and shrink unalike and the body drifts (4 mm in 4 s of drying in a TD's shot)
            if (!model.ground) {
                const Real centre = (lo[d] + hi[d]) / 2;
                const Real cells = std::ceil((centre - s.domain_min[d]) / h);
                s.domain_min[d] = centre - cells * h;
                s.domain_max[d] = centre + cells * h;
            }
        }
        // with a ground: below, a few free cells under the ground or the lowest particle
        if (model.ground)
            s.domain_min.y() =
                std::min(lo.y(), model.ground->height) - (kAutoDomainCellsBelow + pad + 1) * h;
    } else {
        s.domain_min = model.domain.min;
        s.domain_max = model.domain.max;
        const Vec3 inner_lo = s.domain_min + Vec3::Constant(h),
                   inner_hi = s.domain_max - Vec3::Constant(h);
        if (!((lo.array() >= inner_lo.array()).all() && (hi.array() <= inner_hi.array()).all())) {
            std::ostringstream os;
            os << "domain [" << s.domain_min.transpose() << "] - [" << s.domain_max.transpose()
               << "]: the particles span [" << lo.transpose() << "] - [" << hi.transpose()
               << "]: must lie at least one cell (h = " << h << ") inside the domain";
            throw InputError(os.str());
        }
    }
}

}  // namespace

template <class S>
SimStateOf<S> make_initial_state(const SimModel& model, const std::vector<Vec3>& X,
                                 const std::vector<Real>& V0, const std::vector<Real>& strength) {
    check_initial_particles(model, X, V0, strength);
    const size_t n = X.size();

    using StateMat3 = typename SimStateOf<S>::StateMat3;
    SimStateOf<S> s;
    s.id.resize(n);
    for (size_t p = 0; p < n; ++p) s.id[p] = static_cast<int32_t>(p);
    s.x.resize(n);
    for (size_t p = 0; p < n; ++p) s.x[p] = X[p].template cast<S>();
    s.v.assign(n, model.initial_velocity.template cast<S>());
    s.C.assign(n, StateMat3::Zero());
    s.Fe.assign(n, StateMat3::Identity());
    s.J.assign(n, 1);
    if (model.nacc) s.alpha.assign(n, model.nacc->alpha0);
    s.strength = strength;
    if (model.nacc && model.nacc->damage_strain > 0) s.damage.assign(n, 0);
    s.V0 = V0;
    s.mass.resize(n);
    if (model.moisture) {
        const MoistureParams& mp = *model.moisture;
        const Real theta = mp.initial_theta();
        const Real sat = saturation_of(theta, mp.eta);
        s.theta.assign(n, theta);
        s.Jw.assign(n, pore_jw(sat, mp.eta));
        for (size_t p = 0; p < n; ++p)
            s.mass[p] = moist_mass(V0[p], model.elastic.density, sat, mp);
    } else {
        for (size_t p = 0; p < n; ++p) s.mass[p] = V0[p] * model.elastic.density;
    }

    set_domain(model, X, s);

    // arrays sorted by grid block from the start
    SimWorkspace& ws = ensure_workspace(model, s);
    bin_and_sort(s, ws, true, false);
    return s;
}

template <class S>
void set_moisture_field(const SimModel& model, SimStateOf<S>& state,
                        const std::function<Real(const Vec3&)>& theta_of_x) {
    MC_CHECK(model.moisture.has_value());
    const MoistureParams& mp = *model.moisture;
    for (size_t p = 0; p < state.size(); ++p) {
        state.theta[p] = std::clamp(theta_of_x(state.x[p].template cast<Real>()), Real(0), mp.eta);
        const Real sat = saturation_of(state.theta[p], mp.eta);
        state.Jw[p] = pore_jw(sat, mp.eta);
        state.mass[p] = moist_mass(state.V0[p], model.elastic.density, sat, mp);
    }
}

template <class S>
Real stable_dt(const SimModel& model, const SimStateOf<S>& state) {
    if (model.time.dt_fixed > 0) return model.time.dt_fixed;
    Real dt = model.time.dt_max;
    // elastic wave bound; with moisture the lightest (dry) particles set the wave speed
    Real rho = model.elastic.density;
    if (model.moisture) rho = std::min(rho, model.elastic.density * (1 - model.moisture->eta));
    const Real c_p = std::sqrt((model.elastic.lambda() + 2 * model.elastic.mu()) / rho);
    if (c_p > 0) dt = std::min(dt, model.time.cfl_elastic * model.h / c_p);
    // velocity bound
    const Real max_v2 = parallel_reduce(
        static_cast<int64_t>(state.size()), Real(0),
        [&](int64_t p) { return state.v[p].template cast<Real>().squaredNorm(); },
        [](Real a, Real b) { return std::max(a, b); });
    if (max_v2 > 0) dt = std::min(dt, model.time.cfl_velocity * model.h / std::sqrt(max_v2));
    return dt;
}

template <class S>
StepStats step(const SimModel& model, SimStateOf<S>& state, Real dt) {
    const int64_t substep = state.step_count + 1;
    if (!(dt > 0) || !std::isfinite(dt)) {
        std::ostringstream os;
        os << "substep " << substep << ": time step dt = " << dt << ": must be finite and > 0";
        throw RuntimeError(os.str());
    }
    SimWorkspace& ws = ensure_workspace(model, state);
    StepStats stats;
    // a turned grid: at the start of each period the state moves into the frame of the period's
    // grid (and its stress cache, computed in the last grid's frame, is stale)
    const int64_t turn = model.grid_turn_interval, shift = model.grid_shift_interval;
    const bool grid_turns_now = turn > 0 && state.step_count % turn == 0;
    const bool grid_shifts_now = shift > 0 && state.step_count % shift == 0;
    if (grid_turns_now) {
        const GridFrame held = state_grid_frame(model, state);
        const Mat3 next = rotation_about_vertical(grid_turn_angle(
            model.grid_turn_angles, static_cast<uint64_t>(state.step_count / turn)));
        turn_state(state, next * held.rotation.transpose(), held.centre);
    }
    // the moisture CG's warm start extrapolates fluxes at fixed nodes: none survive a move
    if (grid_turns_now || grid_shifts_now) state.moisture_flux.clear();

    // the stress cache is the last step's (and so Fe's) only if that step was this state's last
    // and the state has not turned since; it stays marked stale until this step has succeeded
    const bool tau_is_current =
        !grid_turns_now && ws.tau_step == state.step_count && ws.tau.size() == state.size();
    ws.tau_step = -1;

    // 1. bin particles into grid blocks (and every few steps reorder their arrays). A turn
    // reorders them at once: the last grid's block order is scattered across the turned grid's
    // blocks, and every step until the next reorder would gather through it. Measured on the
    // demo's Mesh_3 puddle turned every 5 steps (frames 1-12, 2 threads, 2026-11-30): P2G and
    // G2P took 96 and 172 ns per particle-step, 55 and 111 with the reorder, which adds 14 to
    // the binning.
    WallTimer phase;
    bin_and_sort(state, ws, grid_turns_now, tau_is_current);
    stats.seconds.bin = phase.seconds();

    // which parts of the moisture model run this step
    const bool has_pores = model.moisture && model.moisture->eta > 0;
    // A solve every k-th step takes the time stepped since the last one, this step's included:
    // the moisture's clock keeps the steps' own, however dt varies (a frame's shortened last
    // steps, a retry's smaller ones). With k = 1 that is dt, to the bit.
    const int interval = has_pores ? std::max(1, model.moisture->interval) : 1;
    const bool solve_moisture_now = has_pores && (state.step_count + 1) % interval == 0;
    const double moisture_dt = state.moisture_lag + dt;

    // 1. P2G (with the moisture fields on solve steps)
    phase.reset();
    MoistureGrid* mg = nullptr;
    if (solve_moisture_now) {
        mg = &ws.moisture;
        begin_moisture_p2g(*mg, ws.grid);
    }
    if (!tau_is_current) mpm::kirchhoff_stresses(model, state, ws.tau);
    mpm::particle_to_grid(state, ws.tau.data(), ws.grid, mg, dt, ws.windows);
    stats.seconds.p2g = phase.seconds();

    // 2. grid velocity update, colliders and walls
    phase.reset();
    mpm::update_grid_velocity(model, ws.grid, dt);
    stats.seconds.grid = phase.seconds();

    // 3. implicit moisture diffusion with evaporation over moisture_dt; the evaporation as the
    // shot's ramp has it where that time starts (this step's start when k = 1)
    MoistureParams drying;
    if (solve_moisture_now) {
        drying = *model.moisture;
        drying.lambda = drying.lambda_at(state.time - state.moisture_lag);
        phase.reset();
        MoistureSeal seal;
        seal.seal_colliders = model.moisture->seal_colliders;
        seal.has_ground = model.ground.has_value();
        if (seal.has_ground) seal.ground_height = model.ground->height;
        const MoistureParticlesOf<S> mp{state.x.data(), state.V0.data(), state.J.data(),
                                        state.theta.data()};
        const MoistureSolveStats ms = solve_moisture(drying, seal, ws.grid, mp, moisture_dt, *mg,
                                                     state.moisture_flux, ws.windows);
        stats.cg_iterations = ms.iterations;
        stats.cg_residual = ms.residual;
        stats.seconds.moisture = phase.seconds();
    }

    // 4-8. G2P, kinematics, pore update, return mapping, advection, finite-ness
    phase.reset();
    mpm::MoistureUpdate moisture_update;
    if (interval > 1) {
        // a state from before the array (a checkpoint, a state built by hand) owes no rate
        if (state.theta_rate.size() != state.size()) state.theta_rate.assign(state.size(), 0);
        moisture_update.theta_rate = state.theta_rate.data();
    }
    if (mg) {
        moisture_update.dtheta = mg->x.data();
        moisture_update.dt = moisture_dt;
        moisture_update.lambda = drying.lambda;
        if (drying.evaporation == MoistureParams::Evaporation::Surface && drying.lambda > 0)
            moisture_update.evaporating = mg->particle_is_boundary.data();
    }
    const mpm::G2PResult g2p = mpm::grid_to_particle(model, state, ws.grid, moisture_update,
                                                     has_pores, dt, ws.windows, ws.tau.data());
    stats.seconds.g2p = phase.seconds();
    state.time += dt;
    state.step_count = substep;
    if (has_pores) state.moisture_lag = solve_moisture_now ? 0 : moisture_dt;
    if (g2p.bad_slot >= 0) {
        std::string msg = find_non_finite(state, substep);
        if (msg.empty()) {
            std::ostringstream os;
            os << "substep " << substep << ": particle " << state.id[g2p.bad_slot]
               << " has a non-finite state sum (overflow)";
            msg = os.str();
        }
        throw RuntimeError(msg);
    }
    // a particle crossing more than kMaxCellsPerStep cells in one step has left the regime
    // where the quadratic kernel transfers momentum consistently: stop before it diverges
    if (g2p.max_speed * dt > kMaxCellsPerStep * model.h) {
        std::ostringstream os;
        os << "substep " << substep << ": max |v| = " << g2p.max_speed << " m/s moves particles "
           << g2p.max_speed * dt / model.h << " cells in one step of dt = " << dt
           << " s (h = " << model.h
           << " m): the time step is unstable; lower /sim/dt or /sim/cfl_velocity";
        throw RuntimeError(os.str());
    }

    stats.active_nodes = 0;
    const int64_t n_nodes = static_cast<int64_t>(ws.grid.n_blocks()) * mpm::kBlockNodes;
    for (int64_t i = 0; i < n_nodes; ++i)
        stats.active_nodes += ws.grid.nodes[i * mpm::kNodeFields] > 0;
    stats.allocated_nodes = n_nodes;
    stats.max_speed = g2p.max_speed;
    ws.tau_step = state.step_count;  // the step succeeded: tau is the new Fe's
    return stats;
}

template <class S>
GridFrame state_grid_frame(const SimModel& model, const SimStateOf<S>& state) {
    GridFrame frame;
    frame.rotation = rotation_about_vertical(state_turn_angle(model, state.step_count));
    frame.centre = (state.domain_min + state.domain_max) / 2;
    return frame;
}

template <class S>
ParticleFrame state_to_frame(const SimModel& model, const SimStateOf<S>& state,
                             const CacheAttributes& attrs) {
    const GridFrame frame = state_grid_frame(model, state);
    const bool is_turned = frame.rotation != Mat3::Identity();
    const size_t n = state.size();
    ParticleFrame f;
    f.time = state.time;
    f.P.resize(n);
#define MC_RESIZE_CACHED(T, member, key, vdb, physics, policy, doc) \
    if (attrs.key) f.member.resize(n);
    MC_CACHED_ATTRIBUTES(MC_RESIZE_CACHED)
#undef MC_RESIZE_CACHED
    for (size_t p = 0; p < n; ++p) {
        const int32_t id = state.id[p];
        MC_CHECK(id >= 0 && static_cast<size_t>(id) < n);
        f.P[id] = state.x[p].template cast<float>();
#define MC_FILL_CACHED(T, member, key, vdb, physics, policy, doc) \
    if (attrs.key) f.member[id] = cached_value::member(model, state, p);
        MC_CACHED_ATTRIBUTES(MC_FILL_CACHED)
#undef MC_FILL_CACHED
        // a turned grid's state, back in the world's frame: the position, and the cached
        // attributes with a direction (the velocity, and Fe on its spatial side)
        if (is_turned) {
            f.P[id] = frame.world_point(state.x[p].template cast<Real>()).template cast<float>();
            if (attrs.velocity)
                f.v[id] =
                    frame.world_vector(state.v[p].template cast<Real>()).template cast<float>();
            if (attrs.Fe)
                f.Fe[id] = (frame.rotation.transpose() * state.Fe[p].template cast<Real>())
                               .template cast<float>();
        }
    }
    return f;
}

template <class S>
int64_t state_memory_bytes(const SimStateOf<S>& s) {
    int64_t total = 0;
    s.for_each_array(
        [&](const char*, const auto& array, ArrayPresence) { total += capacity_bytes(array); });
    total += s.moisture_flux.memory_bytes();
    if (s.workspace) total += s.workspace->memory_bytes();
    return total;
}

std::string float_state_range_problem(const SimModel& model, const Vec3& domain_min,
                                      const Vec3& domain_max) {
    const Real reach = std::max(domain_min.cwiseAbs().maxCoeff(), domain_max.cwiseAbs().maxCoeff());
    const float r = static_cast<float>(reach);
    const Real spacing = Real(std::nextafter(r, std::numeric_limits<float>::infinity()) - r);
    if (spacing <= kFloatSpacingPerCell * model.h) return {};
    std::ostringstream os;
    os << "the simulation box reaches " << reach << " m from the origin, where a float's spacing ("
       << spacing << " m) is over 2^-15 of the grid cell h = " << model.h
       << " m: keep \"double\", or place the scene nearer the origin";
    return os.str();
}

// the two precisions a state keeps its directional arrays in (SimStateOf)
#define MC_INSTANTIATE_FOR_STATE(S)                                                                \
    template SimStateOf<S> make_initial_state(const SimModel&, const std::vector<Vec3>&,           \
                                              const std::vector<Real>&, const std::vector<Real>&); \
    template void set_moisture_field(const SimModel&, SimStateOf<S>&,                              \
                                     const std::function<Real(const Vec3&)>&);                     \
    template Real stable_dt(const SimModel&, const SimStateOf<S>&);                                \
    template StepStats step(const SimModel&, SimStateOf<S>&, Real);                                \
    template GridFrame state_grid_frame(const SimModel&, const SimStateOf<S>&);                    \
    template ParticleFrame state_to_frame(const SimModel&, const SimStateOf<S>&,                   \
                                          const CacheAttributes&);                                 \
    template int64_t state_memory_bytes(const SimStateOf<S>&);
MC_INSTANTIATE_FOR_STATE(double)
MC_INSTANTIATE_FOR_STATE(float)
#undef MC_INSTANTIATE_FOR_STATE

}  // namespace mudcrack
