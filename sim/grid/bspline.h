#pragma once
/// Quadratic B-spline weights of MLS-MPM (docs/physics.md §1.1): the 3x3x3 stencil of a particle,
/// its weights and their gradients. Pure functions, no grid access.
#include <cmath>

#include "sim/core/types.h"

namespace mudcrack::mpm {

/// D_p^{-1} = 4/h^2 of the quadratic B-spline, in units of 1/h^2 (docs/physics.md §1.1, paper typo
/// T4).
constexpr Real kInertiaInvScale = 4;

/// One axis of the quadratic B-spline stencil: nodes base, base+1, base+2.
struct AxisWeights {
    int base = 0;     // first stencil node index along this axis
    Real fx = 0;      // particle position relative to base, in cells, in [0.5, 1.5)
    Real w[3] = {};   // weights of the three nodes
    Real dw[3] = {};  // d w / d fx (divide by h for world units)
};

/// The first node of the 3-node stencil along one axis for a particle at grid coordinate xg: the
/// base fill_axis_weights computes with the weights, for the passes that need only the node
/// (the binning, a particle's place in its block's window).
inline int stencil_base(Real xg) { return static_cast<int>(std::floor(xg - Real(0.5))); }

/// Fills `a` with the weights along one axis for a particle at grid coordinate xg = (x - origin)/h.
/// Writes the fields in place: building an AxisWeights by value and copying it into a Stencil
/// makes the compiler move the 4-byte base as part of 8-byte words, a store-forwarding stall that
/// cost more than the weights themselves in the per-particle loops.
inline void fill_axis_weights(Real xg, AxisWeights& a) {
    const Real fb = std::floor(xg - Real(0.5));
    a.base = static_cast<int>(fb);
    a.fx = xg - fb;
    const Real d0 = Real(1.5) - a.fx, d1 = a.fx - 1, d2 = a.fx - Real(0.5);
    a.w[0] = Real(0.5) * d0 * d0;
    a.w[1] = Real(0.75) - d1 * d1;
    a.w[2] = Real(0.5) * d2 * d2;
    a.dw[0] = -d0;
    a.dw[1] = -2 * d1;
    a.dw[2] = d2;
}

/// Weights along one axis for a particle at grid coordinate xg = (x - origin)/h.
inline AxisWeights axis_weights(Real xg) {
    AxisWeights a;
    fill_axis_weights(xg, a);
    return a;
}

/// The full 3D stencil of a particle: w_ip = wx[a] wy[b] wz[c] at node base + (a,b,c).
struct Stencil {
    AxisWeights axis[3];
    /// Weight of stencil node (a,b,c), each in [0,3).
    Real weight(int a, int b, int c) const { return axis[0].w[a] * axis[1].w[b] * axis[2].w[c]; }
    /// World-space gradient of w_ip at stencil node (a,b,c) [1/m].
    Vec3 gradient(int a, int b, int c, Real inv_h) const {
        return inv_h * Vec3(axis[0].dw[a] * axis[1].w[b] * axis[2].w[c],
                            axis[0].w[a] * axis[1].dw[b] * axis[2].w[c],
                            axis[0].w[a] * axis[1].w[b] * axis[2].dw[c]);
    }
};

/// Stencil of a particle at grid coordinates xg = (x - origin)/h.
inline Stencil make_stencil(const Vec3& xg) {
    Stencil s;
    for (int d = 0; d < 3; ++d) fill_axis_weights(xg[d], s.axis[d]);
    return s;
}

}  // namespace mudcrack::mpm
