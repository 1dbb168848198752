#pragma once
// G2P and the per-particle update of docs/physics.md §7 steps 4-8: the templates, instantiated
// once per state precision, in g2p.cpp (double) and g2p_float.cpp (float). One unit per precision,
// because in a single unit holding both g++ 12 ran out of its inlining budget: it left the cube
// roots, the pore step and the inside test as calls, and the double G2P took 1.18x the time
// (mpm_bench's ns_g2p, 107 against 91 ns per particle-step, 2026-11-27).
#include <algorithm>
#include <cmath>
#include <type_traits>

#include <immintrin.h>

#include "sim/grid/bspline.h"
#include "sim/material/damage.h"
#include "sim/material/material_math.h"
#include "sim/material/nacc.h"
#include "sim/material/neo_hookean.h"
#include "sim/moisture/pore.h"
#include "sim/mpm/transfer.h"

namespace mudcrack::mpm {

namespace g2p_detail {

// window layout per node: velocity x y z, then theta^{n+1} - theta^n
constexpr int kStride = 4;

// relative margin that keeps the SVD-free inside test on the safe side of the kernel's own test
constexpr Real kInsideMargin = 1e-9;

// The NACC inside test (docs/physics.md §2.2, case 3a) without an SVD, on Fe's Neo-Hookean terms
// (J = det Fe; ||dev b_hat|| is the rotation-invariant ||dev(Fe Fe^T)||). True only when the
// state is inside with a relative margin, so the return map (which would return Fe unchanged) can
// be skipped; near the surface and at the tips the full kernel decides.
inline bool clearly_inside_yield_surface(const NeoHookeanTerms& fe, Real alpha, Real beta,
                                         Real strength, const NaccParams& nacc,
                                         const LameParams& lame) {
    const Real J = fe.J;
    if (!(J > 0)) return false;
    // p0 from below (its ulps of rounding are far inside kInsideMargin): a smaller ellipse,
    // so "clearly inside" stays on the safe side
    const Real p0 = strength * nacc_p0_lower_bound(alpha, nacc.xi, lame.kappa);
    const Real p = -lame.kappa / 2 * (J * J - 1);
    if (!(p < p0 && p > -beta * p0)) return false;
    const Real dev_b2 = fe.b.squared_norm() - 3 * fe.mean_b * fe.mean_b;  // ||b - mean_b I||^2
    const Real s2 = fe.shear * fe.shear * std::max(dev_b2, Real(0));
    const Real a = Real(1.5) * (1 + 2 * beta);
    const Real y_s = a * s2;
    const Real y_p = nacc.M * nacc.M * (p + beta * p0) * (p - p0);  // < 0 between the tips
    return y_s + y_p < -kInsideMargin * (y_s - y_p);
}

// The gather of one particle: v_p = sum w v_i, B_p = sum w v_i ((a,b,c) - fx)^T and, with
// kTheta, dth = sum w dtheta_i, over the 3x3x3 stencil in (a, b, c) order. Every sum takes its
// terms in the same order and with the same roundings (w v_i rounded, then added to v_p and
// fused-multiply-added into B_p; w dtheta_i fused into dth) in both versions below, so their
// results are the same bits.
template <bool kTheta>
inline void gather_velocity(const Real* win, int o0, int o1, int o2, const AxisWeights& ax,
                            const AxisWeights& ay, const AxisWeights& az, Vec3& vp, Mat3& B,
                            Real& dth) {
#if defined(__AVX__) && defined(__FMA__)
    // one node's (v, dtheta) as a 4-lane vector: each update is one instruction for v_p and one
    // per column of B_p, instead of a 2-lane and a scalar one
    __m256d v_sum = _mm256_setzero_pd(), b0 = v_sum, b1 = v_sum, b2 = v_sum, th_sum = v_sum;
    const __m256d dz[3] = {_mm256_set1_pd(0 - az.fx), _mm256_set1_pd(1 - az.fx),
                           _mm256_set1_pd(2 - az.fx)};
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const Real wab = ax.w[a] * ay.w[b];
            const Real* row = win + window_index(o0 + a, o1 + b, o2) * kStride;
            const __m256d dx = _mm256_set1_pd(a - ax.fx), dy = _mm256_set1_pd(b - ay.fx);
            for (int c = 0; c < 3; ++c) {
                const __m256d w = _mm256_set1_pd(wab * az.w[c]);
                const __m256d node = _mm256_loadu_pd(row + c * kStride);
                const __m256d wv = _mm256_mul_pd(w, node);
                v_sum = _mm256_add_pd(v_sum, wv);
                b0 = _mm256_fmadd_pd(wv, dx, b0);
                b1 = _mm256_fmadd_pd(wv, dy, b1);
                b2 = _mm256_fmadd_pd(wv, dz[c], b2);
                if constexpr (kTheta) th_sum = _mm256_fmadd_pd(w, node, th_sum);
            }
        }
    alignas(32) Real lanes[5][4];
    _mm256_store_pd(lanes[0], v_sum);
    _mm256_store_pd(lanes[1], b0);
    _mm256_store_pd(lanes[2], b1);
    _mm256_store_pd(lanes[3], b2);
    _mm256_store_pd(lanes[4], th_sum);
    vp = Vec3(lanes[0][0], lanes[0][1], lanes[0][2]);
    for (int k = 0; k < 3; ++k) B.col(k) = Vec3(lanes[1 + k][0], lanes[1 + k][1], lanes[1 + k][2]);
    dth = kTheta ? lanes[4][3] : Real(0);
#else
    vp.setZero();
    B.setZero();
    dth = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const Real wab = ax.w[a] * ay.w[b];
            const Real* row = win + window_index(o0 + a, o1 + b, o2) * kStride;
            const Vec3 dpos_ab(a - ax.fx, b - ay.fx, 0);
            for (int c = 0; c < 3; ++c) {
                const Real w = wab * az.w[c];
                const Real* node = row + c * kStride;
                const Vec3 wv(w * node[0], w * node[1], w * node[2]);
                vp += wv;
                B.col(0) += wv * dpos_ab.x();
                B.col(1) += wv * dpos_ab.y();
                B.col(2) += wv * (c - az.fx);
                if constexpr (kTheta) dth += w * node[3];
            }
        }
#endif
}

// @note Longer than a page on purpose: its body is the step's per-particle hot loop (the G2P
// share of mpm_bench's particle-steps/s), each particle's phases (gather, kinematics, pores,
// plasticity, advection, checks) sharing locals in one pass; the kernels it calls are the
// small, tested functions.
template <bool kTheta, bool kPore, bool kNacc, class S>
G2PResult g2p_impl(const SimModel& model, SimStateOf<S>& state, const SparseGrid& grid,
                   const MoistureUpdate& moisture, Real dt, std::vector<std::vector<Real>>& windows,
                   SymMat3* tau) {
    const Real* dtheta = moisture.dtheta;
    const GridGeometry& geo = grid.geo;
    const Real h = geo.h;
    const Real c_scale = kInertiaInvScale * geo.inv_h * geo.inv_h;
    const LameParams lame = lame_params(model.elastic);
    const NaccParams nacc = kNacc ? *model.nacc : NaccParams{};
    const MoistureParams moist = kPore ? *model.moisture : MoistureParams{};
    const Real rho_s = model.elastic.density;
    // without pores the soil counts as saturated: beta = beta1 (docs/physics.md §2.3)
    const Real beta_saturated = nacc.beta1;
    const bool has_strength = kNacc && !state.strength.empty();
    const bool has_damage = kNacc && !state.damage.empty();
    // surface evaporation: theta - theta0 decays as exp(-lambda S_p dt_m / V_p) on the exposed
    // layer, with S_p = c V_p^(2/3) (particle_area), so the rate is lambda c V_p^(-1/3)
    const uint8_t* evaporating = kTheta ? moisture.evaporating : nullptr;
    const Real evaporation_rate_dt =
        evaporating ? moisture.lambda * moisture.dt * particle_area(1) : Real(0);
    // particles stay inside the box with a full stencil on the grid
    const Vec3 lo = geo.origin + Vec3::Constant(h);
    const Vec3 hi = geo.origin + (geo.cells.cast<Real>() - Vec3::Ones()) * h;

    const int nt = thread_count();
    std::vector<Real> max_speed2(nt, 0);
    std::vector<int32_t> bad(nt, -1);

    for_each_pblock(grid, [&](int t, int32_t pb) {
        Real* win = windows[t].data();
        // gather velocity (and the moisture increment) of the 6x6x6 window
        gather_window<3, kNodeFields, kStride>(grid, pb, grid.nodes.data(), 1, win);
        if constexpr (kTheta) {
            const WindowMap& map = window_map();
            const std::array<int32_t, 8>& nb = grid.pblock_neighbors[pb];
            for (int n = 0; n < kWindowNodes; ++n)
                win[n * kStride + 3] =
                    dtheta[static_cast<int64_t>(nb[map.neighbor[n]]) * kBlockNodes + map.local[n]];
        }
        const Vec3i origin = geo.block_coord(grid.pblock_key[pb]) * kBlockWidth;
        Real speed2 = max_speed2[t];
        for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i) {
            const int32_t p = grid.order[i];
            const Stencil st = make_stencil(geo.to_grid(state.x[p].template cast<Real>()));
            const AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
            const int o0 = ax.base - origin.x(), o1 = ay.base - origin.y(),
                      o2 = az.base - origin.z();

            // gather v_p, B_p = sum w v_i (x_i - x_p)^T / h and the theta increment
            Vec3 vp;
            Mat3 B;
            Real dth;
            gather_velocity<kTheta>(win, o0, o1, o2, ax, ay, az, vp, B, dth);
            // C_p = (4/h^2) sum w v_i (x_i - x_p)^T, with x_i - x_p = h ((a,b,c) - fx)
            const Mat3 Cp = (c_scale * h) * B;

            // kinematics: Fe_trial = (I + dt C) Fe, J *= det(I + dt C)
            Mat3 dF = dt * Cp;
            dF.diagonal().array() += 1;
            Mat3 Fe_trial = dF * state.Fe[p].template cast<Real>();
            const Real J_start = state.J[p];  // the volume the moisture solve saw
            state.J[p] = J_start * dF.determinant();

            // pore update (Eq. 6, 10, 11, 12): theta, Jw, Fe compensation, mass, cohesion
            Real beta = beta_saturated;
            Real alpha = kNacc ? state.alpha[p] : Real(0);
            if constexpr (kPore) {
                Real theta = state.theta[p];
                if constexpr (kTheta) {
                    theta = std::clamp(theta + dth, Real(0), moist.eta);
                    if (evaporating && evaporating[p]) {
                        const Real V = state.V0[p] * J_start;
                        theta =
                            moist.theta0 + (theta - moist.theta0) *
                                               std::exp(-evaporation_rate_dt * inv_cube_root(V));
                    }
                }
                state.theta[p] = theta;
                const Real s = saturation_of(theta, moist.eta);
                const PoreStep ps = pore_step(state.Jw[p], s, moist.eta, moist.max_log_jw_step);
                if (ps.Fe_scale != 1) Fe_trial *= ps.Fe_scale;
                state.Jw[p] = ps.Jw;
                if constexpr (kNacc) {
                    alpha += moist.eps * ps.log_ratio;
                    beta = cohesion_of(nacc, s);
                }
                state.mass[p] = moist_mass(state.V0[p], rho_s, s, moist);
            }

            // plasticity: NACC return mapping with the particle's strength and damage, else pure
            // elasticity; then the Kirchhoff stress of the new Fe for the next P2G (inside the
            // yield surface from the terms the inside test already has)
            const NeoHookeanTerms trial_terms = neo_hookean_terms(Fe_trial, lame);
            bool is_elastic = true;
            if constexpr (kNacc) {
                const Real strength = has_strength ? state.strength[p] : Real(1);
                if (has_damage) beta = damaged_cohesion(beta, state.damage[p]);
                is_elastic =
                    clearly_inside_yield_surface(trial_terms, alpha, beta, strength, nacc, lame);
                if (is_elastic) {
                    // and Fe_trial is what the return map returns (case 3a)
                    state.alpha[p] = alpha;
                } else {
                    const NaccProjection r =
                        nacc_project(Fe_trial, trial_terms, alpha, beta, nacc, lame, strength);
                    if (has_damage)
                        state.damage[p] = damage_after_return(state.damage[p], alpha, r.alpha,
                                                              nacc.damage_strain);
                    state.Fe[p] = r.Fe.template cast<S>();
                    state.alpha[p] = r.alpha;
                }
            }
            bool is_inverted = false;  // the stored Fe (checked in float only: see below)
            if constexpr (std::is_same_v<S, Real>) {
                if (is_elastic) state.Fe[p] = Fe_trial;
                tau[p] = neo_hookean_kirchhoff(
                    is_elastic ? trial_terms : neo_hookean_terms(state.Fe[p], lame), lame);
            } else {
                // the stress of Fe as stored (rounded to float), as kirchhoff_stresses computes it
                // after a resume or a rollback, so a resumed run continues bit for bit. Read back
                // through a volatile pointer: g++ 12 at -O3 -march=native gave the stress the
                // unrounded Fe when the stored matrix was read back directly (caught by
                // FloatState.ACopyContinuesBitForBit and the float resume test)
                if (is_elastic) state.Fe[p] = Fe_trial.template cast<S>();
                const volatile S* stored = state.Fe[p].data();
                Mat3 Fe_stored;
                for (int k = 0; k < 9; ++k) Fe_stored(k) = static_cast<Real>(stored[k]);
                const NeoHookeanTerms stored_terms = neo_hookean_terms(Fe_stored, lame);
                tau[p] = neo_hookean_kirchhoff(stored_terms, lame);
                // rounding a nearly singular Fe can invert it (a 200 m/s impact in the stability
                // matrix: 305 particles with det Fe <= 0 and no error, while J, kept in double,
                // stayed > 0): the step fails its checks and is retried, as for J <= 0
                is_inverted = !(stored_terms.J > 0);
            }

            // advect, clamped into the domain box
            Vec3 x = state.x[p].template cast<Real>() + dt * vp;
            x = x.cwiseMax(lo).cwiseMin(hi);
            state.x[p] = x.template cast<S>();
            state.v[p] = vp.template cast<S>();
            state.C[p] = Cp.template cast<S>();

            // finite-ness: a NaN or inf anywhere poisons the sum; J <= 0 is an inverted particle,
            // which no stable step produces (it precedes the overflow by many steps)
            // (as stored: a float state overflows to inf at its own range)
            Real check = Real(state.x[p].sum()) + Real(state.v[p].sum()) + Real(state.Fe[p].sum()) +
                         state.J[p];
            if constexpr (kNacc) check += state.alpha[p];
            if constexpr (kPore) check += state.theta[p];
            if ((!std::isfinite(check) || !(state.J[p] > 0) || is_inverted) &&
                (bad[t] < 0 || p < bad[t]))
                bad[t] = p;
            speed2 = std::max(speed2, vp.squaredNorm());
        }
        max_speed2[t] = speed2;
    });

    G2PResult result;
    for (int t = 0; t < nt; ++t) {
        result.max_speed = std::max(result.max_speed, std::sqrt(max_speed2[t]));
        if (bad[t] >= 0 && (result.bad_slot < 0 || bad[t] < result.bad_slot))
            result.bad_slot = bad[t];
    }
    return result;
}

template <bool kTheta, bool kPore, class S>
G2PResult dispatch_nacc(const SimModel& model, SimStateOf<S>& state, const SparseGrid& grid,
                        const MoistureUpdate& moisture, Real dt,
                        std::vector<std::vector<Real>>& windows, SymMat3* tau) {
    if (model.nacc)
        return g2p_impl<kTheta, kPore, true>(model, state, grid, moisture, dt, windows, tau);
    return g2p_impl<kTheta, kPore, false>(model, state, grid, moisture, dt, windows, tau);
}

}  // namespace g2p_detail

template <class S>
G2PResult grid_to_particle(const SimModel& model, SimStateOf<S>& state, const SparseGrid& grid,
                           const MoistureUpdate& moisture, bool pore_update, Real dt,
                           std::vector<std::vector<Real>>& windows, SymMat3* tau) {
    using g2p_detail::dispatch_nacc;
    if (moisture.dtheta)
        return dispatch_nacc<true, true>(model, state, grid, moisture, dt, windows, tau);
    if (pore_update)
        return dispatch_nacc<false, true>(model, state, grid, MoistureUpdate{}, dt, windows, tau);
    return dispatch_nacc<false, false>(model, state, grid, MoistureUpdate{}, dt, windows, tau);
}

}  // namespace mudcrack::mpm
