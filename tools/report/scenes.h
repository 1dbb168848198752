#pragma once
/// Building blocks of the report's scenes: particle lattices, a bare model, a wall clock.
#include <chrono>
#include <vector>

#include "sim/core/types.h"
#include "sim/model.h"

namespace mudcrack::report {

/// Particles with their rest volumes.
struct ParticleBlock {
    std::vector<Vec3> X;   // rest positions [m]
    std::vector<Real> V0;  // rest volumes [m^3]
};

/// A box lattice of n[d] particles per axis at `spacing`, the first at lo + spacing/2, each with
/// volume spacing^3 (cell-centred: spacing = h/2 gives 2x2x2 particles per cell).
ParticleBlock lattice_block(const Vec3& lo, const Vec3i& n, Real spacing);

/// An elastic model with no gravity, ground, plasticity or moisture (each scene adds its parts).
SimModel bare_model(Real h, Real youngs_modulus, Real poisson_ratio, Real density);

/// Seconds since construction, monotonic.
class WallClock {
public:
    WallClock() : m_start(std::chrono::steady_clock::now()) {}
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }

private:
    std::chrono::steady_clock::time_point m_start;
};

}  // namespace mudcrack::report
