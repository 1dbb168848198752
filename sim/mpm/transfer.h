#pragma once
/// The three grid passes of one MLS-MPM step (docs/physics.md §1.2-1.4 and §7): P2G with the fused
/// MLS stress, the grid velocity update with colliders, and G2P with the per-particle constitutive
/// update (kinematics, pore update, return mapping, advection, finite-ness check).
#include <cstdint>
#include <vector>

#include "sim/core/types.h"
#include "sim/grid/sparse_grid.h"
#include "sim/model.h"
#include "sim/moisture/moisture_solver.h"
#include "sim/mpm/simulation.h"

namespace mudcrack::mpm {

/// Scatters mass and APIC momentum with the MLS stress term
/// A_p = m_p C_p - dt V0_p (4/h^2) tau_p (docs/physics.md §1.2) into grid.nodes, which
/// bin_particles zeroed. With `moisture` non-null also W_i and (V theta)_i (docs/physics.md §7
/// step 1); those fields must be zeroed (begin_moisture_p2g).
/// tau_p is read from `tau` (per slot, the Kirchhoff stress of Fe: what the last G2P left, or
/// kirchhoff_stresses).
/// @param dt time step [s]  @param windows per-thread scratch of 8 * 216 values
template <class S>
void particle_to_grid(const SimStateOf<S>& state, const SymMat3* tau, SparseGrid& grid,
                      MoistureGrid* moisture, Real dt, std::vector<std::vector<Real>>& windows);

/// Each slot's Kirchhoff stress of its Fe, into `tau` (resized to n): P2G's input when the last
/// G2P's is not at hand (the first step, after a checkpoint load, a rollback or a failed step).
template <class S>
void kirchhoff_stresses(const SimModel& model, const SimStateOf<S>& state,
                        std::vector<SymMat3>& tau);

/// Grid update v_i = (m v)_i / m_i + dt g, then the ground collider and the domain walls
/// (docs/physics.md §1.3). Nodes without mass get v = 0.
void update_grid_velocity(const SimModel& model, SparseGrid& grid, Real dt);

/// What G2P found.
struct G2PResult {
    Real max_speed = 0;     // max |v_p| after the step [m/s]
    int32_t bad_slot = -1;  // a slot whose state is not finite, or -1
};

/// What the moisture solve of this step hands to G2P (all null when it did not run).
struct MoistureUpdate {
    const Real* dtheta = nullptr;  // node field theta^{n+1} - theta^n
    // per slot: the particle loses water itself (surface evaporation)
    const uint8_t* evaporating = nullptr;
    Real dt = 0;      // the moisture step dt_m: the time since the last solve [s]
    Real lambda = 0;  // the evaporation coefficient this step (MoistureParams::lambda_at) [m/s]
    // per slot, with /moisture/interval > 1: theta's rate, which a solve step sets from its
    // increment over dt_m and every step applies over its own dt (null: the increment at once)
    Real* theta_rate = nullptr;
};

/// G2P and the particle update of docs/physics.md §7 steps 4-8: v, C, theta (FLIP increment from
/// moisture.dtheta, if non-null, then the exact decay of the evaporating particles; with
/// moisture.theta_rate that increment sets the rate instead, and every step applies rate dt),
/// Fe_trial = (I + dt C) Fe, J *= det(I + dt C), the pore update when `pore_update`, the NACC
/// return mapping with the particle's strength and damage (when the model has plasticity), x += dt
/// v clamped into the domain box. Checks every particle for a finite state. Writes each slot's
/// Kirchhoff stress of its new Fe to `tau` (n entries), for the next step's P2G.
template <class S>
G2PResult grid_to_particle(const SimModel& model, SimStateOf<S>& state, const SparseGrid& grid,
                           const MoistureUpdate& moisture, bool pore_update, Real dt,
                           std::vector<std::vector<Real>>& windows, SymMat3* tau);

}  // namespace mudcrack::mpm
