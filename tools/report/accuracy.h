#pragma once
/// Accuracy sweeps of `make report`: the simulation against analytic solutions, each
/// knob swept with its error and wall time, and the fitted convergence order. Each sweep runs
/// with a double or a float particle state (SimStateOf, /sim/precision).
#include <functional>
#include <vector>

#include "sim/model.h"
#include "tools/report/report_types.h"

namespace mudcrack::report {

using DiffusionOperator = MoistureParams::DiffusionOperator;
constexpr DiffusionOperator kParticleOperator = DiffusionOperator::Particles;

/// Moisture diffusion along a long insulated bar (no evaporation, no motion) from an erfc step
/// profile at t0 to t1, against eta/2 erfc(x / (2 sqrt(D t))); h swept with dt ~ h^2. `op`: the
/// paper's particle-quadrature L or the grid operator (/moisture/diffusion_operator).
Sweep sweep_diffusion_1d_h(Scale scale, StatePrecision precision = StatePrecision::Double,
                           DiffusionOperator op = kParticleOperator);

/// The same bar at a fine h, dt swept (backward Euler: first order in time).
Sweep sweep_diffusion_1d_dt(Scale scale, StatePrecision precision = StatePrecision::Double);

/// A cube with theta = eta/2 + A cos(pi x/L) cos(pi y/L) cos(pi z/L) and zero-flux faces,
/// against its decay exp(-3 D (pi/L)^2 t); h swept with dt ~ h^2; `op` as above.
Sweep sweep_diffusion_3d_h(Scale scale, StatePrecision precision = StatePrecision::Double,
                           DiffusionOperator op = kParticleOperator);

/// A free block (no gravity, no plasticity) drying fully: its final volume against
/// (1 - eta) V0, over h (2x2x2 particles per cell).
Sweep sweep_shrinkage_h(Scale scale, StatePrecision precision = StatePrecision::Double);

/// The drying block over particles per cell (per axis 1..4) at a fixed h.
Sweep sweep_shrinkage_ppc(Scale scale, StatePrecision precision = StatePrecision::Double);

/// An elastic column (nu = 0) settling under gravity on a sticky ground against the small-strain
/// settlement u(y) = rho g (H y - y^2/2) / E, over h.
Sweep sweep_column_h(Scale scale, StatePrecision precision = StatePrecision::Double);

/// The column over Young's modulus E at a fixed h (the strain rho g H / E shrinks with E).
Sweep sweep_column_E(Scale scale, StatePrecision precision = StatePrecision::Double);

/// CG iteration caps 1, 2, 5, 10 against a converged solve in a drying slab, one sweep per
/// D dt / h^2 (the paper's regime first). The converged run is the last point, error 0.
std::vector<Sweep> sweep_cg_caps(Scale scale, StatePrecision precision = StatePrecision::Double);

/// Moisture solve intervals k = 1, 2, 4, 8 (/moisture/interval: a solve every k-th step with
/// dt_m = k dt) in the drying slab at the paper's D dt / h^2, against a solve every step.
Sweep sweep_moisture_interval(Scale scale, StatePrecision precision = StatePrecision::Double);

/// Every sweep above in report order, each in double and then in float (/sim/precision); `on_done`
/// (if set) is called after each one (progress).
std::vector<Sweep> all_sweeps(Scale scale, const std::function<void(const Sweep&)>& on_done = {});

}  // namespace mudcrack::report
