#pragma once
/// The moisture CG's initial guess: the nodal water fluxes of the last two solves, extrapolated
/// to the next one.
///
/// A solve's increment theta^{n+1} - theta^n splits into the explicit evaporation's Jacobi step
/// r / diag, which the solver recomputes exactly every step, and the rest, mostly diffusion.
/// The rest, as a water flux (W / dt)(theta^{n+1} - theta^n - r / diag) into a node, changes
/// smoothly in time: grid nodes sit at fixed positions, and the flux follows the material's
/// volume around a node as it moves. Extrapolated linearly through the last two solves it is
/// off by O(dt^2), often inside the CG tolerance, and the solve then needs no CG iteration.
/// (Measured on the simulation benchmarks' reference scene (tests/mpm/mpm_bench.cpp): extrapolated
/// rates instead of fluxes, or the whole increment without the exact evaporation step, need more
/// iterations; a quadratic extrapolation amplifies the step-to-step noise and needs more too.)
#include <cstdint>
#include <vector>

#include "sim/core/types.h"
#include "sim/grid/sparse_grid.h"

namespace mudcrack {

struct MoistureFluxHistory {
    int count = 0;                // solves recorded: 0, 1 or 2
    std::vector<uint32_t> keys;   // block keys of the newest solve, ascending
    std::vector<Real> flux;       // its fluxes per node of the `keys` blocks [m^3/s]
    std::vector<Real> flux_prev;  // the solve before's, on the same nodes
    Real dt = 0, dt_prev = 0;     // the two solves' time steps [s]
    std::vector<int32_t> remap;   // scratch: the `keys` slot of each current block, or -1

    /// Forgets every solve: the next one starts as the first did.
    void clear() { count = 0; }
    int64_t memory_bytes() const;
};

/// The extrapolated flux of each node of the current grid into `flux` (n_blocks * 64): the
/// line through the two recorded solves' fluxes, at their midpoints in time, evaluated at the
/// middle of this step of length dt; the newest flux when only one is recorded; 0 on the
/// blocks the history has none for.
/// @pre history.count > 0
void predict_moisture_flux(MoistureFluxHistory& history, const mpm::SparseGrid& grid, Real dt,
                           Real* flux);

/// Records a solve's nodal fluxes (n_blocks * 64 values on the current grid) over a step dt.
/// A block the history lacks takes this solve's flux as its previous one as well: no slope
/// there, rather than one from zero.
void record_moisture_flux(MoistureFluxHistory& history, const mpm::SparseGrid& grid,
                          const Real* flux, Real dt);

}  // namespace mudcrack
