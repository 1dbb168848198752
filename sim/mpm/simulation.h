#pragma once
/// The MPM simulation's state and step (MuJoCo's mjData / mj_step split): SimModel is immutable,
/// SimState holds particles, time and scratch; `step` advances one substep.
/// Tu et al. 2023 Sections 4-5; the consolidated step of docs/physics.md §7.
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "sim/core/particle_frame.h"
#include "sim/core/scratch.h"
#include "sim/core/types.h"
#include "sim/model.h"
#include "sim/moisture/flux_history.h"

namespace mudcrack {

struct SimWorkspace;  // grid and scratch, rebuilt every step; carries nothing from step to step

// SimState's per-particle arrays, (n_particles) each, listed once: the list drives their
// declaration, slot reordering, memory accounting and the checkpoint's save and load (a new
// array changes what a checkpoint holds: bump kSimCheckpointVersion, sim_checkpoint.cpp).
// X(element type, name, presence, doc); presence Always: n elements, Optional: n or none.
// The directional arrays are stored in the state's precision (StateVec3, StateMat3); the scalars
// are always double (see SimStateOf).
#define MC_SIM_STATE_ARRAYS(X)                                                              \
    X(int32_t, id, Always, "particle id per slot")                                          \
    X(StateVec3, x, Always, "position [m]")                                                 \
    X(StateVec3, v, Always, "velocity [m/s]")                                               \
    X(StateMat3, C, Always, "APIC affine velocity [1/s]")                                   \
    X(StateMat3, Fe, Always, "elastic deformation gradient")                                \
    X(Real, J, Always, "det of the total deformation gradient (volume tracking)")           \
    X(Real, alpha, Optional, "NACC hardening state (empty without plasticity)")             \
    X(Real, V0, Always, "rest volume [m^3]")                                                \
    X(Real, mass, Always, "[kg]")                                                           \
    X(Real, theta, Optional, "water content in [0, eta] (moisture only)")                   \
    X(Real, Jw, Optional, "pore determinant 1 - eta (1 - s) (moisture only)")               \
    X(Real, theta_rate, Optional,                                                           \
      "theta's rate from the last moisture solve, applied every step (interval > 1) [1/s]") \
    X(Real, strength, Optional, "p0 multiplier of a heterogeneous soil (empty: uniform)")   \
    X(Real, damage, Optional, "tensile damage in [0, 1], never decreasing (NACC with damage)")

/// Whether a state array may be empty (the model lacks its physics) or always has n elements.
enum class ArrayPresence { Always, Optional };

/// Mutable simulation state. Particle arrays are SoA, (n_particles), periodically reordered by
/// grid block for memory coherence; `id` maps a slot to its particle id (ids are 0..n-1). The
/// step processes particles in (grid block, id) order whatever the slot order, so a state saved
/// and restored in any slot order (e.g. by id) continues bit for bit. Moisture arrays are empty
/// when the model has no moisture section; alpha is empty without plasticity.
///
/// StateReal is the precision the directional arrays (x, v, C, Fe: 24 of a particle's up to 32
/// numbers, 192 of its 256 bytes in double) are kept in between steps: double (SimState), or float
/// (SimStateFloat, a shot's /sim/precision "float"), which holds them in half the memory. The step
/// computes in double either way, and the scalars stay double: J, alpha and theta are running sums
/// of one increment per step, which a float would round to its resolution at the running value
/// every step (docs/physics.md §7.1).
template <class StateReal>
struct SimStateOf {
    using StateVec3 = Eigen::Matrix<StateReal, 3, 1>;
    using StateMat3 = Eigen::Matrix<StateReal, 3, 3>;

    double time = 0;          // simulated time [s]
    int64_t step_count = 0;   // substeps taken since t = 0
    double moisture_lag = 0;  // time stepped since the last moisture solve, which the next solve
                              //   takes (/moisture/interval > 1) [s]; part of the checkpoint
#define MC_STATE_ARRAY_MEMBER(T, name, presence, doc) std::vector<T> name;
    MC_SIM_STATE_ARRAYS(MC_STATE_ARRAY_MEMBER)
#undef MC_STATE_ARRAY_MEMBER
    Vec3 domain_min = Vec3::Zero();     // simulation box, fixed at t = 0 (derived once when the
    Vec3 domain_max = Vec3::Zero();     //   model's domain is auto) [m]; part of the checkpoint
    MoistureFluxHistory moisture_flux;  // the moisture CG's last two solves (its initial guess);
                                        //   part of the checkpoint, so a resumed run is exact
    Scratch<SimWorkspace> workspace;    // a copy gets its own, recreated on demand

    size_t size() const { return x.size(); }

    /// Calls fn(name, array, presence) for each particle array, in MC_SIM_STATE_ARRAYS order.
    template <class Fn>
    void for_each_array(Fn&& fn) {
#define MC_STATE_ARRAY_VISIT(T, name, presence, doc) fn(#name, name, ArrayPresence::presence);
        MC_SIM_STATE_ARRAYS(MC_STATE_ARRAY_VISIT)
#undef MC_STATE_ARRAY_VISIT
    }
    template <class Fn>
    void for_each_array(Fn&& fn) const {
#define MC_STATE_ARRAY_VISIT(T, name, presence, doc) fn(#name, name, ArrayPresence::presence);
        MC_SIM_STATE_ARRAYS(MC_STATE_ARRAY_VISIT)
#undef MC_STATE_ARRAY_VISIT
    }
};

using SimState = SimStateOf<double>;
using SimStateFloat = SimStateOf<float>;

/// Calls fn(S{}) with S the number type `precision` names (double or float), returning its result:
/// the one place a run picks its state's instantiation.
template <class Fn>
decltype(auto) with_state_precision(StatePrecision precision, Fn&& fn) {
    if (precision == StatePrecision::Float) return fn(float{});
    return fn(double{});
}

/// The name /sim/precision, the checkpoints and the report give a state precision S.
template <class S>
constexpr const char* state_precision_name() {
    return std::is_same_v<S, float> ? "float" : "double";
}

/// Where a step's wall time went, phase by phase [s]: each phase from its first parallel loop's
/// start to its last one's end on the calling thread, so on several threads it includes the wait
/// for the slowest worker (what a phase's scaling is judged by). For the benchmarks' per-phase
/// table; the results of a step do not depend on it.
struct StepPhaseSeconds {
    double bin = 0;       // binning, and every few steps the arrays' reorder by block
    double p2g = 0;       // the stresses (when not cached) and the scatter, moisture's fields too
    double grid = 0;      // grid velocities, colliders and walls
    double moisture = 0;  // the moisture solve (0 on steps that do not solve it)
    double g2p = 0;       // gather, kinematics, pores, return map, advection, checks
    double total() const { return bin + p2g + grid + moisture + g2p; }
    StepPhaseSeconds& operator+=(const StepPhaseSeconds& o) {
        bin += o.bin;
        p2g += o.p2g;
        grid += o.grid;
        moisture += o.moisture;
        g2p += o.g2p;
        return *this;
    }
};

/// Counters of one step, for progress lines and the manifest.
struct StepStats {
    StepPhaseSeconds seconds;     // wall time by phase
    int cg_iterations = 0;        // moisture CG iterations (0 without moisture)
    double cg_residual = 0;       // final relative residual
    int64_t active_nodes = 0;     // grid nodes with mass
    int64_t allocated_nodes = 0;  // grid nodes allocated (sparse blocks)
    Real max_speed = 0;           // max |v_p| after the step [m/s]
};

/// The angle about the vertical of the grid that steps [j k, (j + 1) k) are taken on, for a turned
/// grid (/sim/grid_turn k, turn_index j). The grid is the same under a quarter turn, so what it
/// imprints on a crack repeats in 4 psi, and what matters is how the 4 psi_j of the few turns
/// during which a crack opens share out the circle.
/// - Golden: (pi / 2) frac((j + 1) g), g = (sqrt 5 - 1) / 2, in [0, pi / 2). Every run of n
///   consecutive 4 psi_j covers the circle nearly evenly (the three-gap theorem): over any 20 turns
///   of the first 5,000 the mean of exp(4 i psi) is 0.049, and of exp(8 i psi) 0.057.
/// - Random: uniform in [0, 2 pi), one splitmix64 draw per j. Over 20 turns the mean of
///   exp(4 i psi) is 0.19 at the median and up to 0.63 (j from 20 to 40: 0.43, 3 degrees off the
///   world's axes), so the cracks that open within such a run can follow one pair of directions
///   (docs/physics.md §6.5).
Real grid_turn_angle(SimModel::TurnAngles angles, uint64_t turn_index);

/// Where a turned grid (/sim/grid_turn, SimModel::grid_turn_interval = k > 0) holds the state.
/// Its particles' x, v, C and Fe are in the frame of the grid of the state's last step, which is
/// the world turned by an angle about the vertical through the domain's centre; a state that has
/// taken no step is in the world's frame. Everything else (scalars, rest positions, the domain)
/// is the world's. A state whose model does not turn its grid is always in the world's frame.
struct GridFrame {
    Mat3 rotation = Mat3::Identity();  // grid = rotation (world - centre) + centre
    Vec3 centre = Vec3::Zero();        // on the vertical axis of the turn [m]
    Vec3 world_point(const Vec3& x) const { return rotation.transpose() * (x - centre) + centre; }
    Vec3 world_vector(const Vec3& v) const { return rotation.transpose() * v; }
};

/// The frame `state` is held in (see GridFrame). A pure function of the model, the state's step
/// count and its domain, so a run resumed from a checkpoint finds the frame its state was saved
/// in.
template <class S>
GridFrame state_grid_frame(const SimModel& model, const SimStateOf<S>& state);

/// Initial state: particles at rest positions X with rest volumes V0 (from the tet mesh), moving
/// at model.initial_velocity, at theta_init when the model has moisture. `strength` (empty, or
/// one positive p0 multiplier per particle) makes the soil heterogeneous; it needs model.nacc.
template <class S = double>
SimStateOf<S> make_initial_state(const SimModel& model, const std::vector<Vec3>& X,
                                 const std::vector<Real>& V0,
                                 const std::vector<Real>& strength = {});

/// Sets every particle's water content to theta_of_x(x) (clamped to [0, eta]) with the matching
/// pore determinant Jw and mass: a non-uniform initial moisture field (tests, the report).
/// Requires model.moisture.
template <class S>
void set_moisture_field(const SimModel& model, SimStateOf<S>& state,
                        const std::function<Real(const Vec3&)>& theta_of_x);

/// The adaptive time step min(dt_max, C_v h / max|v|, C_E h / c_p), or dt_fixed when set.
template <class S>
Real stable_dt(const SimModel& model, const SimStateOf<S>& state);

/// Advances one substep of length dt. After the step every particle is checked for finite
/// state; a failure throws RuntimeError naming the particle id and its state (theta, J, alpha).
template <class S>
StepStats step(const SimModel& model, SimStateOf<S>& state, Real dt);

/// The cacheable view of the state in particle-id order, with only the requested attributes, in
/// the world's frame.
template <class S>
ParticleFrame state_to_frame(const SimModel& model, const SimStateOf<S>& state,
                             const CacheAttributes& attrs);

/// The coarsest float spacing, as a fraction of the grid cell h, that a float state may have at
/// its domain's farthest coordinate: 2^-15. A float state's positions are rounded to that
/// spacing every step; far from the origin the rounding grows with the distance, and past about
/// this spacing a float run drifts from the double one faster than the double run itself drifts
/// when its start is rounded to float (docs/physics.md §7.1, measured).
constexpr Real kFloatSpacingPerCell = 0x1p-15;

/// Why a float state cannot serve a run in the box [domain_min, domain_max] at the model's h (the
/// numbers, in one sentence), or empty when it can.
std::string float_state_range_problem(const SimModel& model, const Vec3& domain_min,
                                      const Vec3& domain_max);

/// Bytes held by the state's particle arrays and workspace (for bytes-per-particle reports).
template <class S>
int64_t state_memory_bytes(const SimStateOf<S>& state);

}  // namespace mudcrack
