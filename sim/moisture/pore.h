#pragma once
/// Porosity and saturation update of one particle (Tu et al. 2023 Eq. 6, 10, 11, 12;
/// docs/physics.md §3.2 and §4.6). Pure functions for the G2P particle loop.
#include <algorithm>
#include <cmath>

#include "sim/core/types.h"
#include "sim/material/material_math.h"
#include "sim/model.h"

namespace mudcrack {

/// Saturation s = theta/eta clamped to [0, 1]; eta = 0 means s = 1 (no pores, docs/physics.md
/// §3.1).
/// @note Multiplies by 1/eta (computed once per loop when eta is loop-invariant) rather than
/// dividing: in the G2P the division sat on every particle's dependency chain. theta >= eta is
/// exactly 1, as with the division.
inline Real saturation_of(Real theta, Real eta) {
    if (!(eta > 0) || theta >= eta) return 1;
    return std::clamp(theta * (1 / eta), Real(0), Real(1));
}

/// Pore determinant J_w = (1 - eta)(1 - s) + s = 1 - eta (1 - s)  (Eq. 6).
inline Real pore_jw(Real saturation, Real eta) { return 1 - eta * (1 - saturation); }

/// Particle mass from its water content, m = V0 (rho_s (1 - eta) + rho_w eta s) with
/// rho_w = rho_s / k_r: the closed form of Eq. 11 (docs/physics.md §4.6), drift-free. [kg]
/// @param V0 rest volume [m^3]  @param rho_s solid density [kg/m^3]
inline Real moist_mass(Real V0, Real rho_s, Real saturation, const MoistureParams& mp) {
    const Real rho_w = rho_s / mp.k_r;
    return V0 * (rho_s * (1 - mp.eta) + rho_w * mp.eta * saturation);
}

/// NACC cohesion beta = beta0 (1 - s) + beta1 s (paper Section 4.2).
inline Real cohesion_of(const NaccParams& np, Real saturation) {
    return np.beta0 * (1 - saturation) + np.beta1 * saturation;
}

/// Relative J_w changes below this use the series path of pore_step (truncation < 2e-19). It is
/// the default cap on |log(J_w ratio)| per step: a drying surface particle's change stays near it.
constexpr Real kPoreSeriesLimit = 1e-3;

/// One step of the pore update of a particle.
struct PoreStep {
    Real Jw = 1;         // new pore determinant
    Real Fe_scale = 1;   // multiply Fe (trial) by this: (Jw_old / Jw_new)^(1/3)  (Eq. 10)
    Real log_ratio = 0;  // log(Jw_new / Jw_old), for the hardening alpha += eps log_ratio (Eq. 12)
};

/// Moves J_w towards the target 1 - eta (1 - s) of the particle's current saturation, with
/// |log(J_w ratio)| capped at max_log_step per step; the remainder is carried to later steps
/// because the target is recomputed from theta every step (docs/physics.md §3.2: one large jump
/// of Fe injects elastic energy, a spurious "pop").
inline PoreStep pore_step(Real Jw_old, Real saturation, Real eta, Real max_log_step) {
    PoreStep r;
    // 1/Jw_old depends only on the stored state, so it is ready before the saturation is
    const Real inv_Jw_old = 1 / Jw_old;
    const Real target = pore_jw(saturation, eta);
    r.Jw = Jw_old;
    if (target == Jw_old) return r;  // no change in saturation: nothing to do, bit for bit
    // rel = target/Jw_old - 1 without the cancellation of the "- 1"
    const Real rel = (target - Jw_old) * inv_Jw_old;
    if (std::abs(rel) < kPoreSeriesLimit) {
        // the common small change: log1p(rel) to rel^6 and (1 + rel)^(-1/3) to rel^5 by their
        // series (truncation < 2e-19 for |rel| < 1e-3), a fraction of the cost of log1p + cbrt,
        // and side by side rather than one after the other: they sit on the particle loop's
        // dependency chain
        const Real l =
            rel *
            (1 - rel * (Real(1) / 2 -
                        rel * (Real(1) / 3 -
                               rel * (Real(1) / 4 - rel * (Real(1) / 5 - rel * (Real(1) / 6))))));
        r.log_ratio = l;
        r.Jw = target;
        r.Fe_scale =
            1 +
            rel * (Real(-1) / 3 +
                   rel * (Real(2) / 9 + rel * (Real(-14) / 81 +
                                               rel * (Real(35) / 243 + rel * (Real(-91) / 729)))));
        if (max_log_step <= 0 || std::abs(l) <= max_log_step) return r;
    }
    const Real log_ratio = std::log1p(rel);
    if (max_log_step > 0 && std::abs(log_ratio) > max_log_step) {
        r.log_ratio = std::copysign(max_log_step, log_ratio);
        r.Jw = Jw_old * std::exp(r.log_ratio);
        r.Fe_scale = std::exp(-r.log_ratio / 3);
    } else {
        r.log_ratio = log_ratio;
        r.Jw = target;
        r.Fe_scale = cube_root(Jw_old / target);
    }
    return r;
}

}  // namespace mudcrack
