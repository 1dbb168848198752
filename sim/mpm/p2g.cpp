// P2G: mass, APIC momentum with the fused MLS stress, and the moisture fields (docs/physics.md
// §1.2, §4.3).
#include <algorithm>

#include <Eigen/Core>

#include "sim/core/lanes.h"
#include "sim/core/parallel.h"
#include "sim/grid/bspline.h"
#include "sim/material/material_math.h"
#include "sim/material/neo_hookean.h"
#include "sim/mpm/transfer.h"

namespace mudcrack::mpm {

namespace {

// window layout: per node m, (m v) x y z; with moisture then two planar windows W and (V theta),
// kMoistureStride apart, whose z rows are updated as 4 lanes (the z weights with a zero 4th lane:
// one SIMD operation per row; the stride keeps that lane inside the scratch)
constexpr int kMoistureStride = kWindowNodes + 8;

// @note Longer than a page on purpose: its body is the step's per-particle scatter, a hot loop
// (the P2G share of mpm_bench's particle-steps/s), each particle's weights, stress and moisture
// terms sharing locals in one pass over its window.
template <bool kMoisture, class S>
void p2g_impl(const SimStateOf<S>& state, const SymMat3* kirchhoff, SparseGrid& grid,
              MoistureGrid* mg, Real dt, std::vector<std::vector<Real>>& windows) {
    constexpr int kStride = kNodeFields;
    const GridGeometry& geo = grid.geo;
    const Real h = geo.h;
    const Real stress_scale = dt * kInertiaInvScale * geo.inv_h * geo.inv_h;
    const auto* x = state.x.data();
    const auto* v = state.v.data();
    const auto* C = state.C.data();
    const Real* mass = state.mass.data();
    const Real* V0 = state.V0.data();
    const Real* J = state.J.data();
    const Real* theta = kMoisture ? state.theta.data() : nullptr;

    for_each_pblock_colored(grid, [&](int t, int32_t pb) {
        Real* win = windows[t].data();
        Real* mw = win + kWindowNodes * kStride;  // moisture windows
        std::fill(win, win + kWindowNodes * kStride + (kMoisture ? 2 * kMoistureStride : 0),
                  Real(0));
        const Vec3i origin = geo.block_coord(grid.pblock_key[pb]) * kBlockWidth;
        for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i) {
            const int32_t p = grid.order[i];
            const Stencil st = make_stencil(geo.to_grid(x[p].template cast<Real>()));
            const AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
            const int o0 = ax.base - origin.x(), o1 = ay.base - origin.y(),
                      o2 = az.base - origin.z();

            // affine momentum with the stress folded in, A_p h = h (m C - dt V0 (4/h^2) tau), by
            // columns as 4-lane vectors: (mass, momentum) at node (a,b,c) is
            // w (base + a da + b db + c dc), mass in lane 0 with a zero affine part, so each node
            // update is one vector multiply-add. Built in registers from the particle's arrays and
            // rounded by explicit FMAs: the Mat3 expression the compiler made of it spilled a
            // column to the stack and read it back across two stores, which stalled store-to-load
            // forwarding on every particle.
            const Real m = mass[p];
            const auto& Cp = C[p];
            const SymMat3& tau = kirchhoff[p];
            const Lanes m4 = splat<Lanes>(m), minus_cs = splat<Lanes>(-stress_scale * V0[p]),
                        h4 = splat<Lanes>(h);
            auto affine_column = [&](int j, Lanes tau_column) {
                const Lanes C_column = {0, Real(Cp(0, j)), Real(Cp(1, j)), Real(Cp(2, j))};
                return h4 * fused_madd(minus_cs, tau_column, m4 * C_column);
            };
            const Lanes da = affine_column(0, Lanes{0, tau.xx, tau.xy, tau.xz});
            const Lanes db = affine_column(1, Lanes{0, tau.xy, tau.yy, tau.yz});
            const Lanes dc = affine_column(2, Lanes{0, tau.xz, tau.yz, tau.zz});
            // (m, m v - A h fx): the base node's values
            const Lanes affine_at_base =
                fused_madd(dc, splat<Lanes>(az.fx),
                           fused_madd(db, splat<Lanes>(ay.fx), da * splat<Lanes>(ax.fx)));
            const auto& vp = v[p];
            const Lanes base =
                fused_madd(m4, Lanes{1, Real(vp.x()), Real(vp.y()), Real(vp.z())}, -affine_at_base);
            // the moisture rows' z profiles, scaled once per particle: V wz and V theta wz (each
            // row then takes one multiply-add per field)
            Lanes V_wz = splat<Lanes>(0), Vtheta_wz = splat<Lanes>(0);
            if constexpr (kMoisture) {
                const Real V = V0[p] * J[p];
                V_wz = splat<Lanes>(V) * Lanes{az.w[0], az.w[1], az.w[2], 0};
                Vtheta_wz = splat<Lanes>(theta[p]) * V_wz;
            }

            // scatter to the 3x3x3 stencil
            for (int a = 0; a < 3; ++a) {
                for (int b = 0; b < 3; ++b) {
                    const Real wab = ax.w[a] * ay.w[b];
                    Real* row = win + window_index(o0 + a, o1 + b, o2) * kStride;
                    // a da, b db and c dc are exact for 0, 1, 2, so fused or not these sums round
                    // alike
                    const Lanes q = fused_madd(splat<Lanes>(Real(b)), db,
                                               fused_madd(splat<Lanes>(Real(a)), da, base));
                    for (int c = 0; c < 3; ++c) {
                        Real* node = row + c * kStride;
                        const Lanes t = fused_madd(splat<Lanes>(Real(c)), dc, q);
                        lanes_store(node,
                                    fused_madd(splat<Lanes>(wab * az.w[c]), t, lanes_load(node)));
                    }
                    if constexpr (kMoisture) {
                        const int n = window_index(o0 + a, o1 + b, o2);
                        Real* W_row = mw + n;
                        Real* Vtheta_row = mw + kMoistureStride + n;
                        lanes_store(W_row, fused_madd(splat<Lanes>(wab), V_wz, lanes_load(W_row)));
                        lanes_store(Vtheta_row, fused_madd(splat<Lanes>(wab), Vtheta_wz,
                                                           lanes_load(Vtheta_row)));
                    }
                }
            }
        }

        // flush the window into the 8 blocks it overlaps
        flush_window<kNodeFields, kStride>(grid, pb, win, grid.nodes.data());
        if constexpr (kMoisture) {
            flush_window<1, 1>(grid, pb, mw, mg->W.data());
            flush_window<1, 1>(grid, pb, mw + kMoistureStride, mg->theta.data());
        }
    });
}

}  // namespace

template <class S>
void kirchhoff_stresses(const SimModel& model, const SimStateOf<S>& state,
                        std::vector<SymMat3>& tau) {
    const LameParams lame = lame_params(model.elastic);
    tau.resize(state.size());
    parallel_for(static_cast<int64_t>(state.size()), [&](int64_t p) {
        tau[p] =
            neo_hookean_kirchhoff(neo_hookean_terms(state.Fe[p].template cast<Real>(), lame), lame);
    });
}

template <class S>
void particle_to_grid(const SimStateOf<S>& state, const SymMat3* tau, SparseGrid& grid,
                      MoistureGrid* moisture, Real dt, std::vector<std::vector<Real>>& windows) {
    if (moisture)
        p2g_impl<true, S>(state, tau, grid, moisture, dt, windows);
    else
        p2g_impl<false, S>(state, tau, grid, nullptr, dt, windows);
}

template void kirchhoff_stresses(const SimModel&, const SimStateOf<double>&, std::vector<SymMat3>&);
template void kirchhoff_stresses(const SimModel&, const SimStateOf<float>&, std::vector<SymMat3>&);
template void particle_to_grid(const SimStateOf<double>&, const SymMat3*, SparseGrid&,
                               MoistureGrid*, Real, std::vector<std::vector<Real>>&);
template void particle_to_grid(const SimStateOf<float>&, const SymMat3*, SparseGrid&, MoistureGrid*,
                               Real, std::vector<std::vector<Real>>&);

}  // namespace mudcrack::mpm
