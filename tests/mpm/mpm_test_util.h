#pragma once
// Small scenes for the MPM tests: lattice blocks of particles and a minimal model.
#include <cmath>
#include <cstring>
#include <vector>

#include "sim/core/types.h"
#include "sim/model.h"
#include "sim/mpm/simulation.h"

namespace mudcrack::test {

/// Particles on a regular lattice: n[d] per axis, spacing `spacing`, first particle at
/// lo + spacing/2 (cell-centred, like 2x2x2 per cell when spacing = h/2).
struct Lattice {
    std::vector<Vec3> X;
    std::vector<Real> V0;
};

inline Lattice make_lattice(const Vec3& lo, const Vec3i& n, Real spacing) {
    Lattice l;
    for (int k = 0; k < n.z(); ++k)
        for (int j = 0; j < n.y(); ++j)
            for (int i = 0; i < n.x(); ++i) {
                l.X.push_back(lo + spacing * Vec3(i + 0.5, j + 0.5, k + 0.5));
                l.V0.push_back(spacing * spacing * spacing);
            }
    return l;
}

/// An elastic model without gravity, ground, plasticity or moisture (every test adds its parts).
inline SimModel plain_model(Real h) {
    SimModel m;
    m.h = h;
    m.gravity = Vec3::Zero();
    m.elastic.density = 1000;
    m.elastic.youngs_modulus = 1e4;
    m.elastic.poisson_ratio = 0.3;
    m.time.dt_max = 1e-3;
    return m;
}

/// A NACC soil block's model: gravity, a sticky ground, hardening and drying moisture, at
/// h = 0.1 (tests add their initial velocity or other parts).
inline SimModel soil_model() {
    SimModel m = plain_model(0.1);
    m.gravity = Vec3(0, -9.81, 0);
    m.ground = GroundParams{};
    m.nacc = NaccParams{};
    m.nacc->alpha0 = std::log(0.99);
    m.nacc->beta0 = m.nacc->beta1 = 2;
    m.nacc->xi = 3;
    m.moisture = MoistureParams{};
    m.moisture->lambda = 1;
    return m;
}

/// Sum of m_p v_p.
inline Vec3 total_momentum(const SimState& s) {
    Vec3 p = Vec3::Zero();
    for (size_t i = 0; i < s.size(); ++i) p += s.mass[i] * s.v[i];
    return p;
}

inline Real total_mass(const SimState& s) {
    Real m = 0;
    for (Real v : s.mass) m += v;
    return m;
}

/// Whether two arrays hold the same bytes.
template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// Particle slot of each id.
template <class S>
inline std::vector<size_t> slot_of_id(const SimStateOf<S>& s) {
    std::vector<size_t> slot(s.size());
    for (size_t i = 0; i < s.size(); ++i) slot[s.id[i]] = i;
    return slot;
}

}  // namespace mudcrack::test
