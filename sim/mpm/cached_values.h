#pragma once
/// The value each cached attribute (MC_CACHED_ATTRIBUTES) takes for the particle in slot p: one
/// function per attribute, named as its ParticleFrame member, called by state_to_frame.
/// @note Without moisture the soil counts as saturated (theta = eta = 0, s = 1, Jw = 1); without
/// plasticity alpha is 0.
#include <cstddef>

#include "sim/core/particle_attributes.h"
#include "sim/model.h"
#include "sim/moisture/pore.h"
#include "sim/mpm/simulation.h"

namespace mudcrack::cached_value {

template <class S>
inline Vec3f v(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.v[p].template cast<float>();
}

template <class S>
inline float theta(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.theta.empty() ? 0.f : static_cast<float>(s.theta[p]);
}

template <class S>
inline float saturation(const SimModel& model, const SimStateOf<S>& s, size_t p) {
    const Real eta = model.moisture ? model.moisture->eta : 0;
    return s.theta.empty() ? 1.f : static_cast<float>(saturation_of(s.theta[p], eta));
}

template <class S>
inline float alpha(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.alpha.empty() ? 0.f : static_cast<float>(s.alpha[p]);
}

template <class S>
inline float Jw(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.theta.empty() ? 1.f : static_cast<float>(s.Jw[p]);
}

template <class S>
inline Mat3f Fe(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.Fe[p].template cast<float>();
}

template <class S>
inline float damage(const SimModel&, const SimStateOf<S>& s, size_t p) {
    return s.damage.empty() ? 0.f : static_cast<float>(s.damage[p]);
}

}  // namespace mudcrack::cached_value
