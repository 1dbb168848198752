#pragma once
/// The implicit moisture diffusion on the MPM grid (Tu et al. 2023 Section 5.2; docs/physics.md
/// §4):   (M + L) theta^{n+1} = M theta^n + r,   M_ii = W_i/dt,  W_i = sum_p V_p w_ip,
///   L_ij = sum_p V_p D grad w_ip . grad w_jp,   r_i = -sum_{p boundary} S_p lambda (theta_p -
///   theta_0) w_ip
/// (the minus sign of r is required, docs/physics.md §4.2), solved matrix-free with
/// Jacobi-preconditioned CG from theta^n plus one Jacobi step on the explicit evaporation, theta^n
/// + r / diag (that step removes most of the initial residual: usually one CG iteration reaches
/// 1e-6). Node fields live on the sparse grid's allocated blocks; they exist only when the model
/// has moisture.
#include <cstdint>
#include <vector>

#include "sim/core/types.h"
#include "sim/grid/sparse_grid.h"
#include "sim/model.h"
#include "sim/moisture/flux_history.h"

namespace mudcrack {

/// The Jacobi preconditioner's stiffness part, L's diagonal sum_p V_p D |grad w_ip|^2, taken as
/// this factor times D W_i / h^2 (W_i = sum_p V_p w_ip): the ratio for a node amid particles spread
/// evenly over its support, int |grad N|^2 / int N = 3 (int N'^2)(int N^2)^2 = 3 (1)(11/20)^2 for
/// the quadratic B-spline N(x) N(y) N(z) with h = 1 (docs/physics.md §4.5). The diagonal only
/// preconditions the CG (and takes the explicit evaporation's Jacobi step), so it need not be
/// exact, and M_ii = W_i / dt outweighs it by h^2 / (D dt) (about 2,000 on the demo, 100 on
/// mpm_bench's reference scene): the P2G is spared a third moisture field.
constexpr Real kJacobiStiffnessPerWeight = Real(3 * 121) / 400;

/// Moisture node fields, (n_blocks * 64) each, and per-particle boundary flags.
struct MoistureGrid {
    std::vector<Real> W;      // sum_p V_p w_ip [m^3]
    std::vector<Real> theta;  // (V theta)_i after the P2G, then theta_i^n
    // the Jacobi diagonal, then its inverse
    std::vector<Real> diag;
    // r (explicit), or r_0 = sum S lambda theta_0 w (implicit Robin)
    std::vector<Real> evaporation;
    std::vector<Real> x;         // CG iterate; after the solve: theta^{n+1} - theta^n
    std::vector<Real> r, p, Ap;  // CG residual, direction, operator times direction
    std::vector<Real> surface;   // 1 at surface nodes (docs/physics.md §4.4), else 0
    // the grid operator's conductances to the +x, +y and +z neighbour, 3 per node (§4.9)
    std::vector<Real> conductance;
    std::vector<uint8_t> particle_is_boundary;  // per slot: evaporates this step
    std::vector<Real> block_partial;            // per-block partial sums (deterministic dots)
    // slots of the 6 face-adjacent blocks or -1
    std::vector<std::array<int32_t, 6>> block_face_neighbors;

    int64_t memory_bytes() const;
};

/// Which empty neighbours of a surface node are walls rather than air (docs/physics.md §4.4 item
/// 3).
struct MoistureSeal {
    bool seal_colliders = true;  // faces against the ground / domain walls do not evaporate
    bool has_ground = false;
    Real ground_height = 0;  // [m]
};

/// The particles as the moisture solve reads them, in slot order.
template <class StateReal>
struct MoistureParticlesOf {
    const Eigen::Matrix<StateReal, 3, 1>* x = nullptr;  // positions x^n [m]
    const Real* V0 = nullptr;                           // rest volumes [m^3]
    const Real* J = nullptr;                            // total volume ratio: V^n = V0 J
    const Real* theta = nullptr;                        // water content theta^n
};
using MoistureParticles = MoistureParticlesOf<double>;

struct MoistureSolveStats {
    int iterations = 0;  // CG iterations (operator applications after the initial residual)
    Real residual = 0;   // final ||b - A x|| / ||b||
};

/// Resizes and zeroes the node fields the P2G accumulates (W, theta) for the current grid.
void begin_moisture_p2g(MoistureGrid& mg, const mpm::SparseGrid& grid);

/// Solves one implicit moisture step of length dt after the P2G filled W and (V theta).
/// On return mg.x holds theta^{n+1} - theta^n per node (zero off the material) and
/// mg.particle_is_boundary flags the evaporating particles. The CG starts from theta^n plus the
/// Jacobi step on the explicit evaporation plus the flux `history` predicts, and this solve's
/// flux is recorded there (flux_history.h).
/// @param dt moisture time step [s] (k dt when solving every k MPM steps)
/// @param windows per-thread scratch, at least 5 * 224 values each
template <class StateReal>
MoistureSolveStats solve_moisture(const MoistureParams& params, const MoistureSeal& seal,
                                  const mpm::SparseGrid& grid,
                                  const MoistureParticlesOf<StateReal>& particles, Real dt,
                                  MoistureGrid& mg, MoistureFluxHistory& history,
                                  std::vector<std::vector<Real>>& windows);

/// The grid operator's conductance between two face-adjacent nodes of material weights W_i and
/// W_j, per D / h^2: their harmonic mean, 0 when either is empty (docs/physics.md §4.9) [m^3].
inline Real face_weight(Real Wi, Real Wj) {
    return Wi > 0 && Wj > 0 ? 2 * Wi * Wj / (Wi + Wj) : Real(0);
}

/// Equivalent-sphere cross-section S = pi R^2, R = (3 V / (4 pi))^(1/3) of a particle of
/// volume V (docs/physics.md §4.4) [m^2].
Real particle_area(Real volume);

}  // namespace mudcrack
