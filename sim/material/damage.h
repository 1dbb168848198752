#pragma once
/// Permanent tensile damage (docs/physics.md §6.2): the "traditional softening-based
/// fracture" Tu et al. 2023 combine with their model for the bunny (Section 7.2), in its simplest
/// form. NACC softens a particle that fails in tension (the tension tip, and the dry side of the
/// ellipse): alpha rises, p0 falls. Drying then hardens the same particle again
/// (alpha += eps log(Jw ratio) < 0) and heals the crack, so a shrinking crust can close its own
/// cracks. Damage keeps what tension did: the softening increments, summed and divided by a
/// damage strain, give d in [0, 1], never decreasing, and the particle's cohesion is
/// beta (1 - d). At d = 1 the tension tip sits at p = 0 whatever p0 drying builds: the soil there
/// carries compression and shear under compression, but no tension, for good.
/// Pure functions for the G2P particle loop.
#include <algorithm>

#include "sim/core/types.h"

namespace mudcrack {

/// The damage after a return mapping that moved alpha from alpha_before to alpha_after:
/// d + max(alpha_after - alpha_before, 0) / damage_strain, at most 1. Hardening returns
/// (alpha falls) leave d unchanged. @param damage_strain > 0 [-]
inline Real damage_after_return(Real damage, Real alpha_before, Real alpha_after,
                                Real damage_strain) {
    const Real softening = alpha_after - alpha_before;
    if (!(softening > 0)) return damage;
    return std::min(Real(1), damage + softening / damage_strain);
}

/// NACC cohesion of a damaged particle: beta (1 - d).
inline Real damaged_cohesion(Real beta, Real damage) { return beta * (1 - damage); }

}  // namespace mudcrack
