// P2G: mass, APIC momentum with the fused MLS stress, and the moisture fields (docs/physics.md
// §1.2, §4.3).
#include <algorithm>

#include <immintrin.h>

#include <Eigen/Core>

#include "sim/core/parallel.h"
#include "sim/grid/bspline.h"
#include "sim/material/neo_hookean.h"
#include "sim/mpm/transfer.h"

namespace mudcrack::mpm {

namespace {

// window layout: per node m, (m v) x y z; with moisture then two planar windows W and (V theta),
// kMoistureStride apart, whose z rows are updated as 4 lanes (the z weights with a zero 4th lane:
// one SIMD operation per row; the stride keeps that lane inside the scratch)
constexpr int kMoistureStride = kWindowNodes + 8;
using ZRow = Eigen::Array<Real, 4, 1>;  // a z row of three nodes and the zero lane

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

            // affine momentum with the stress folded in: A_p = m C - dt V0 (4/h^2) tau
            const Real m = mass[p];
            const Mat3 tau = kirchhoff[p].matrix();
            const Mat3 Ah = h * (m * C[p].template cast<Real>() - (stress_scale * V0[p]) * tau);
            // (mass, momentum) at node (a,b,c): w (m, m v + A h ((a,b,c) - fx)), as 4-vectors
            // (mass first, with a zero affine part) so each node update is one SIMD add
            const Vec3 q0 = m * v[p].template cast<Real>() - Ah * Vec3(ax.fx, ay.fx, az.fx);
#if defined(__AVX__) && defined(__FMA__)
            // assembled in registers: written to memory entry by entry and read back as one
            // vector, they stalled store-to-load forwarding for each particle
            const __m256d base = _mm256_set_pd(q0.z(), q0.y(), q0.x(), m);
            const __m256d da = _mm256_set_pd(Ah(2, 0), Ah(1, 0), Ah(0, 0), 0);
            const __m256d db = _mm256_set_pd(Ah(2, 1), Ah(1, 1), Ah(0, 1), 0);
            const __m256d dc = _mm256_set_pd(Ah(2, 2), Ah(1, 2), Ah(0, 2), 0);
#else
            const Real base[4] = {m, q0.x(), q0.y(), q0.z()};
            const Real da[4] = {0, Ah(0, 0), Ah(1, 0), Ah(2, 0)};
            const Real db[4] = {0, Ah(0, 1), Ah(1, 1), Ah(2, 1)};
            const Real dc[4] = {0, Ah(0, 2), Ah(1, 2), Ah(2, 2)};
#endif
            // the moisture rows' z profiles, scaled once per particle: V wz and V theta wz (each
            // row then takes one multiply-add per field)
            ZRow V_wz = ZRow::Zero(), Vtheta_wz = ZRow::Zero();
            if constexpr (kMoisture) {
                const Real V = V0[p] * J[p];
                const ZRow wz(az.w[0], az.w[1], az.w[2], 0);
                V_wz = V * wz;
                Vtheta_wz = theta[p] * V_wz;
            }

            // scatter to the 3x3x3 stencil
            for (int a = 0; a < 3; ++a) {
                for (int b = 0; b < 3; ++b) {
                    const Real wab = ax.w[a] * ay.w[b];
                    Real* row = win + window_index(o0 + a, o1 + b, o2) * kStride;
#if defined(__AVX__) && defined(__FMA__)
                    // the loop below as 4-lane vectors with each product fused into its sum, as
                    // the compiler contracts the scalar loop (a da, b db and c dc are exact for
                    // 0, 1, 2, so fused or not those sums round alike): the same window bits
                    const __m256d q =
                        _mm256_fmadd_pd(_mm256_set1_pd(Real(b)), db,
                                        _mm256_fmadd_pd(_mm256_set1_pd(Real(a)), da, base));
                    for (int c = 0; c < 3; ++c) {
                        Real* node = row + c * kStride;
                        const __m256d t = _mm256_fmadd_pd(_mm256_set1_pd(Real(c)), dc, q);
                        _mm256_storeu_pd(node, _mm256_fmadd_pd(_mm256_set1_pd(wab * az.w[c]), t,
                                                               _mm256_loadu_pd(node)));
                    }
#else
                    Real q[4];
                    for (int k = 0; k < 4; ++k) q[k] = base[k] + Real(a) * da[k] + Real(b) * db[k];
                    for (int c = 0; c < 3; ++c) {
                        const Real w = wab * az.w[c];
                        Real* node = row + c * kStride;
                        for (int k = 0; k < 4; ++k) node[k] += w * (q[k] + Real(c) * dc[k]);
                    }
#endif
                    if constexpr (kMoisture) {
                        const int n = window_index(o0 + a, o1 + b, o2);
                        Eigen::Map<ZRow>(mw + n) += wab * V_wz;
                        Eigen::Map<ZRow>(mw + kMoistureStride + n) += wab * Vtheta_wz;
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
