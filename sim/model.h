#pragma once
/// The immutable simulation model (MuJoCo's mjModel): everything mc-sim needs from the shot,
/// already validated, in SI units. Built by pipeline/shot; the sim never sees JSON. A section the
/// shot leaves out is std::nullopt here and is never computed or allocated.
#include <algorithm>
#include <optional>
#include <string>

#include "sim/core/particle_attributes.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Neo-Hookean solid (Tu et al. 2023 Eq. 4-5).
struct ElasticParams {
    Real density = 1;            // rho_s, solid density [kg/m^3]
    Real youngs_modulus = 2000;  // E [Pa]
    Real poisson_ratio = 0.35;   // nu [-]
    Real mu() const { return youngs_modulus / (2 * (1 + poisson_ratio)); }
    Real lambda() const {
        return youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio));
    }
    /// 3D bulk modulus kappa = lambda + 2/3 mu (docs/physics.md §1.6).
    Real kappa() const { return lambda() + Real(2) / 3 * mu(); }
    /// P-wave speed sqrt((lambda + 2 mu)/rho) [m/s], for the elastic time-step bound.
    Real wave_speed() const;
};

/// Non-associated Cam-Clay (Wolper et al. 2019; Tu et al. 2023 Eq. 7-9, 12).
struct NaccParams {
    Real alpha0 = 0;        // initial hardening state (ziran's logJp) [-]
    Real beta0 = 1;         // cohesion when dry (s = 0) [-]
    Real beta1 = 1;         // cohesion when saturated (s = 1) [-]
    Real xi = 1;            // hardening factor in p0 = kappa sinh(xi max(-alpha, 0)) [-]
    Real M = 1.87;          // critical-state slope (friction) [-]
    bool hardening = true;  // update alpha in the return mapping
    /// Tensile damage (docs/physics.md §6.2): the softening returns' alpha increments,
    /// divided by this, add to a particle's damage d in [0, 1], and its cohesion is beta (1 - d).
    /// 0: no damage (no array, no cost).
    Real damage_strain = 0;
};

/// Pore water (Tu et al. 2023 Sections 4.1, 5.2; docs/physics.md §3-4).
struct MoistureParams {
    Real eta = 0.5;            // porosity: theta in [0, eta], Jw = 1 - eta (1 - s) [-]
    Real k_r = 1;              // rho_s / rho_w [-]
    Real eps = 0.5;            // saturation hardening rate, alpha += eps log(Jw ratio) [-]
    Real D = 0.02;             // diffusivity [m^2/s]
    Real lambda = 0.1;         // evaporation coefficient [m/s]
    Real theta0 = 0;           // ambient moisture [-]
    Real theta_init = -1;      // initial moisture; < 0 means eta (fully saturated) [-]
    Real cg_tolerance = 1e-6;  // relative residual [-]
    int cg_max_iterations = 50;
    bool seal_colliders = true;   // faces against the ground/walls do not evaporate
    bool implicit_robin = false;  // evaporation term in the matrix instead of the rhs
    /// Grid: the paper's r term scattered from the particles whose stencil touches a surface node.
    /// Surface: the particles of the exposed layer lose water themselves, exactly (an exponential
    /// decay towards theta0), and the CG carries only diffusion (docs/physics.md §6.3).
    enum class Evaporation { Grid, Surface } evaporation = Evaporation::Grid;
    /// How L, the diffusion's stiffness, is discretised (docs/physics.md §4.9). Particles: the
    /// paper's particle quadrature, L_ij = sum_p V_p D grad w_ip . grad w_jp, applied matrix-free
    /// by one gather/scatter pass over the particles per CG iteration. Grid: a finite-volume
    /// Laplacian between face-adjacent nodes, conductance D hm(W_i, W_j) / h^2 (hm the harmonic
    /// mean), applied on the grid alone; the same conservation and zero flux into empty nodes.
    enum class DiffusionOperator {
        Particles,
        Grid
    } diffusion_operator = DiffusionOperator::Particles;
    int interval = 1;             // solve moisture every k-th MPM step (docs/physics.md §4.2)
    Real max_log_jw_step = 1e-3;  // cap on |log(Jw^n/Jw^{n+1})| per step (docs/physics.md §3.2)
    /// When the drying starts (docs/physics.md §6.3): no evaporation until ramp_start, then
    /// lambda rising linearly to its full value at ramp_end; ramp_end <= ramp_start: lambda from
    /// the start [s]
    Real evaporation_ramp_start = 0;
    Real evaporation_ramp_end = 0;
    /// The evaporation coefficient at time t: lambda scaled by the ramp [m/s]
    Real lambda_at(Real t) const {
        if (!(evaporation_ramp_end > evaporation_ramp_start)) return lambda;
        const Real ramp =
            (t - evaporation_ramp_start) / (evaporation_ramp_end - evaporation_ramp_start);
        return lambda * std::clamp(ramp, Real(0), Real(1));
    }
    /// The particles' starting moisture: theta_init, or eta (fully saturated, paper Section 7.1)
    /// when theta_init < 0; clamped to [0, eta] (min, then max: no precondition on eta, which the
    /// shot loader reads before it reports a bad one).
    Real initial_theta() const {
        return std::max(Real(0), std::min(theta_init < 0 ? eta : theta_init, eta));
    }
};

enum class ColliderMode { Sticky, Slip, Separate };

/// A horizontal ground plane y = height with outward normal +y.
struct GroundParams {
    Real height = 0;  // [m]
    ColliderMode mode = ColliderMode::Sticky;
    Real friction = 0;  // Coulomb coefficient (slip/separate) [-]
};

/// Axis-aligned simulation box: nodes within `padding` cells of a wall lose their outward
/// velocity (separate behaviour). Particles never leave it.
struct DomainParams {
    bool is_auto = true;            // derive from the particles' bounds (see sim/mpm) when unset
    Vec3 min = Vec3::Constant(-1);  // [m]
    Vec3 max = Vec3::Constant(1);   // [m]
    int padding = 3;                // [cells]
};

struct TimeParams {
    Real dt_max = 1e-3;  // [s]
    // > 0 forces this dt (refused at load if above the elastic bound) [s]
    Real dt_fixed = 0;
    Real cfl_velocity = 0.6;  // C_v: dt <= C_v h / max|v|
    Real cfl_elastic = 0.5;   // C_E: dt <= C_E h / c_p
    Real fps = 24;            // frames per second
    int frame_start = 1;      // first frame (1-based)
    int frame_end = 24;       // last frame, inclusive
};

/// The precision of a state's directional arrays (/sim/precision).
enum class StatePrecision { Double, Float };

struct SimModel {
    Real h = 0.05;                         // grid spacing [m]
    Vec3 gravity = Vec3(0, -9.81, 0);      // [m/s^2]
    Vec3 initial_velocity = Vec3::Zero();  // of every particle at t = 0 [m/s]
    ElasticParams elastic;
    std::optional<NaccParams> nacc;          // nullopt: pure elasticity
    std::optional<MoistureParams> moisture;  // nullopt: no theta arrays, no moisture grid, no CG
    std::optional<GroundParams> ground;
    DomainParams domain;
    TimeParams time;
    int checkpoint_every = 10;  // frames between full-precision checkpoints (0: off)
    // every this many steps the background grid moves by a fraction of a cell (0: a fixed grid;
    // sim/mpm/simulation.cpp, docs/physics.md §6.4)
    int grid_shift_interval = 0;
    // every this many steps the background grid turns to a new angle about the vertical
    // (0: a grid along the world's axes; sim/mpm/simulation.cpp, docs/physics.md §6.5). Needs an
    // auto domain and a vertical gravity (the shot loader refuses the others).
    int grid_turn_interval = 0;
    // how the turned grid's angles are drawn (/sim/grid_turn_angles; docs/physics.md §6.5):
    // Golden, the golden-ratio sequence of quarter turns, leaves every run of a few turns without
    // a preferred pair of directions; Random, uniform draws, can prefer one for a hundred steps
    enum class TurnAngles { Golden, Random } grid_turn_angles = TurnAngles::Golden;
    // what the state keeps its directional arrays (x, v, C, Fe) in between steps: SimState or
    // SimStateFloat (sim/mpm/simulation.h); the step computes in double either way
    StatePrecision precision = StatePrecision::Double;
    CacheAttributes cache;
};

/// The elastic time-step bound C_E h / c_p [s].
Real elastic_dt_bound(const SimModel& model);

/// The smallest stable time step a run accepts, as a fraction of the frame length 1/fps: a step
/// this much smaller than the frame would take over a billion substeps per frame. mc-sim stops a
/// run whose step collapses below it; the shot loader refuses a shot whose step starts below it.
constexpr double kCollapsedDtFraction = 1e-9;

}  // namespace mudcrack
