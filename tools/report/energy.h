#pragma once
/// Mechanical energy of a simulation state, for the energy drift of the stability matrix.
#include "sim/core/types.h"
#include "sim/model.h"
#include "sim/mpm/simulation.h"

namespace mudcrack::report {

/// Kinetic, gravitational and elastic energy of the particles [J].
struct EnergyBreakdown {
    Real kinetic = 0;        // sum 1/2 m |v|^2
    Real gravitational = 0;  // sum -m g . (x - x_ref), x_ref on the ground plane (or y = 0)
    Real elastic = 0;        // sum V0 psi(Fe), the paper's Neo-Hookean energy (Eq. 4)
    Real total() const { return kinetic + gravitational + elastic; }
};

/// The energy of `state` under `model`. Elastic energy is +infinity if some Fe is inverted.
/// @note With moisture the particle masses change and evaporated water takes its momentum with
/// it, so the total is not conserved even by an exact integrator; the drift is still reported.
template <class S>
EnergyBreakdown state_energy(const SimModel& model, const SimStateOf<S>& state);

}  // namespace mudcrack::report
