#pragma once
// G2P and the per-particle update of docs/physics.md §7 steps 4-8: the templates, instantiated
// once per state precision, in g2p.cpp (double) and g2p_float.cpp (float). One unit per precision,
// because in a single unit holding both g++ 12 ran out of its inlining budget: it left the cube
// roots, the pore step and the inside test as calls, and the double G2P took 1.18x the time
// (mpm_bench's ns_g2p, 107 against 91 ns per particle-step, 2026-11-27).
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "sim/core/lanes.h"
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

// max(x, 0) as std::max(x, Real(0)) gives it (x itself when x is NaN), per lane for Lanes
template <class T>
inline T max_with_zero(T x) {
    if constexpr (!std::is_same_v<T, Real>)
        return lanes_select(x < 0, splat<T>(0), x);
    else
        return std::max(x, Real(0));
}

// The NACC inside test (docs/physics.md §2.2, case 3a) without an SVD, on Fe's Neo-Hookean terms
// (J = det Fe; ||dev b_hat|| is the rotation-invariant ||dev(Fe Fe^T)||) and p0's lower bound
// times the particle's strength (from below, its ulps of rounding far inside kInsideMargin: a
// smaller ellipse, so "clearly inside" stays on the safe side). True (all ones in a lane) only
// when the state is inside with a relative margin, so the return map (which would return Fe
// unchanged) can be skipped; near the surface and at the tips the full kernel decides. T is Real
// (a bool-valued int) or Lanes (a LaneMask).
template <class T>
inline auto clearly_inside_yield_surface(T J, const T (&b)[6], T mean_b, T shear, T p0, T beta,
                                         const NaccParams& nacc, const LameParams& lame) {
    const T p = -lame.kappa / 2 * (J * J - 1);
    const T b_norm2 =
        b[0] * b[0] + b[1] * b[1] + b[2] * b[2] + 2 * (b[3] * b[3] + b[4] * b[4] + b[5] * b[5]);
    const T dev_b2 = b_norm2 - 3 * mean_b * mean_b;  // ||b - mean_b I||^2
    const T s2 = shear * shear * max_with_zero(dev_b2);
    const T a = Real(1.5) * (1 + 2 * beta);
    const T y_s = a * s2;
    const T y_p = nacc.M * nacc.M * (p + beta * p0) * (p - p0);  // < 0 between the tips
    return (J > 0) & (p < p0) & (p > -beta * p0) & (y_s + y_p < -kInsideMargin * (y_s - y_p));
}

// The gather of one particle: v_p = sum w v_i, B_p = sum w v_i ((a,b,c) - fx)^T and, with
// kTheta, dth = sum w dtheta_i, over the 3x3x3 stencil, into sums: v_p's entries in
// sums[0][0..2], B_p's column k in sums[1 + k][0..2], dth in sums[4][3]. The weight is a product
// w = wx_a wy_b wz_c, so the sums separate: each z row of nodes is contracted first (by wz and by
// wz (c - fz)), then the rows of each x plane (by wy and wy (b - fy)), then the planes (by wx and
// wx (a - fx)). That takes 93 multiply-adds where the node-by-node sum took 135 (162 with
// dtheta), in chains 3 long instead of 27; dtheta rides in the 4th lane of v_p's sum. The sums'
// order is fixed, so the same thread count gives the same bits. The caller reads the sums back
// one number at a time: each read lies inside one vector store, which the CPU forwards without
// a stall (a Mat3 built from them and read two entries at a time stalled on every read).
template <bool kTheta>
inline void gather_velocity(const Real* win, const Stencil& st, const Vec3i& origin,
                            Real (&sums)[5][kLaneCount]) {
    const AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
    const Real* corner =
        win +
        window_index(ax.base - origin.x(), ay.base - origin.y(), az.base - origin.z()) * kStride;
    // per axis: the weights w and the first moments w (k - f)
    Real gx[3], gy[3], gz[3];
    for (int k = 0; k < 3; ++k) {
        gx[k] = ax.w[k] * (k - ax.fx);
        gy[k] = ay.w[k] * (k - ay.fx);
        gz[k] = az.w[k] * (k - az.fx);
    }
    // one node's (v, dtheta) as four lanes; Lanes are one AVX register where the CPU has AVX
    Lanes v = splat<Lanes>(0), b0 = v, b1 = v, b2 = v;
    for (int a = 0; a < 3; ++a) {
        Lanes plane_w = splat<Lanes>(0), plane_gy = plane_w, plane_gz = plane_w;
        for (int b = 0; b < 3; ++b) {
            const Real* row = corner + window_index(a, b, 0) * kStride;
            const Lanes n0 = lanes_load(row), n1 = lanes_load(row + kStride),
                        n2 = lanes_load(row + 2 * kStride);
            const Lanes row_w =
                fused_madd(splat<Lanes>(az.w[2]), n2,
                           fused_madd(splat<Lanes>(az.w[1]), n1, splat<Lanes>(az.w[0]) * n0));
            const Lanes row_gz =
                fused_madd(splat<Lanes>(gz[2]), n2,
                           fused_madd(splat<Lanes>(gz[1]), n1, splat<Lanes>(gz[0]) * n0));
            plane_w = fused_madd(splat<Lanes>(ay.w[b]), row_w, plane_w);
            plane_gy = fused_madd(splat<Lanes>(gy[b]), row_w, plane_gy);
            plane_gz = fused_madd(splat<Lanes>(ay.w[b]), row_gz, plane_gz);
        }
        v = fused_madd(splat<Lanes>(ax.w[a]), plane_w, v);
        b0 = fused_madd(splat<Lanes>(gx[a]), plane_w, b0);
        b1 = fused_madd(splat<Lanes>(ax.w[a]), plane_gy, b1);
        b2 = fused_madd(splat<Lanes>(ax.w[a]), plane_gz, b2);
    }
    lanes_store(sums[0], v);
    lanes_store(sums[1], b0);
    lanes_store(sums[2], b1);
    lanes_store(sums[3], b2);
    sums[4][3] = kTheta ? v[3] : Real(0);
}

// a b, four particles' 3x3 matrices at once: each entry a fused multiply-add chain over k in
// order, rounded the same at every optimisation level (no product left for the compiler to fuse)
inline LaneMat3 lanes_product(const LaneMat3& a, const LaneMat3& b) {
    LaneMat3 r;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
            r(i, j) = fused_madd(a(i, 2), b(2, j), fused_madd(a(i, 1), b(1, j), a(i, 0) * b(0, j)));
    return r;
}

// det m, four particles at once: the cofactor expansion along the first row, rounded as
// neo_hookean_terms rounds J
inline Lanes lanes_determinant(const LaneMat3& m) {
    const Lanes c0 = fused_madd(m(1, 1), m(2, 2), -(m(1, 2) * m(2, 1)));
    const Lanes c1 = fused_madd(m(1, 0), m(2, 2), -(m(1, 2) * m(2, 0)));
    const Lanes c2 = fused_madd(m(1, 0), m(2, 1), -(m(1, 1) * m(2, 0)));
    return fused_madd(m(0, 2), c2, fused_madd(-m(0, 1), c1, m(0, 0) * c0));
}

// Particles per chunk: a chunk's arrays (about 11 KB) stay in L1 between its passes, and each
// pass's scalar stores have retired long before the next pass loads them as lanes (a vector load
// of four fresh scalar stores would stall on store-to-load forwarding).
constexpr int kChunk = 32;

// One chunk of a particle block's particles, field by field (slot j of each array is the chunk's
// j-th particle): the per-particle passes of the G2P fill and read it one particle at a time, its
// lane passes four at a time. Past the chunk's last particle, up to the next multiple of four,
// the lanes hold copies of it, so the lane passes compute on numbers of the kind they expect.
struct ParticleChunk {
    using Field = Real[kChunk];
    alignas(32) Field v[3], C[9], F[9], J_start, J_new, dtheta, alpha, beta, p0, J_trial, b[6],
        mean_b, shear, tau[6];
    bool inside[kChunk];

    static Lanes lanes(const Field& f, int j) { return lanes_load(f + j); }
    static void store(Field& f, int j, Lanes x) { lanes_store(f + j, x); }

    // particle j's gathered sums (gather_velocity): v_p, C_p = B_scale B_p and dtheta
    void set_gathered(int j, const Real (&sums)[5][kLaneCount], Real B_scale) {
        for (int k = 0; k < 3; ++k) v[k][j] = sums[0][k];
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row) C[3 * col + row][j] = B_scale * sums[1 + col][row];
        dtheta[j] = sums[4][3];
    }
    // copies of the last particle's kinematic inputs into the lanes past it
    void pad_kinematics(int n) {
        for (int j = n; j % kLaneCount != 0; ++j) {
            for (int k = 0; k < 9; ++k) {
                C[k][j] = C[k][n - 1];
                F[k][j] = F[k][n - 1];
            }
            J_start[j] = J_start[n - 1];
        }
    }
    // the same for the hardening the inside test reads (the padded lanes' Fe_trial keeps the
    // copy made before the pore update: any Fe of the kind will do there)
    void pad_hardening(int n) {
        for (int j = n; j % kLaneCount != 0; ++j) {
            alpha[j] = alpha[n - 1];
            beta[j] = beta[n - 1];
            p0[j] = p0[n - 1];
        }
    }
    // particle j's Neo-Hookean terms of Fe_trial, as the lane pass left them
    NeoHookeanTerms terms(int j) const {
        return {J_trial[j],
                {b[0][j], b[1][j], b[2][j], b[3][j], b[4][j], b[5][j]},
                mean_b[j],
                shear[j]};
    }
};

// @note Longer than a page on purpose: its body is the step's per-particle hot loop (the G2P
// share of mpm_bench's particle-steps/s), a chunk's passes (gather, kinematics, pores, terms and
// inside test, plasticity with advection and checks) sharing the chunk's arrays; the kernels
// they call are the small, tested functions.
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
    Real* const theta_rate = kPore ? moisture.theta_rate : nullptr;
    const Real inv_moisture_dt = kTheta && theta_rate ? 1 / moisture.dt : Real(0);
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
        ParticleChunk chunk;
        const int32_t block_end = grid.pblock_begin[pb + 1];
        for (int32_t i0 = grid.pblock_begin[pb]; i0 < block_end; i0 += kChunk) {
            const int n = std::min(kChunk, block_end - i0);
            const int32_t* slots = grid.order.data() + i0;

            // 1. gather v_p, B_p = sum w v_i (x_i - x_p)^T / h and the theta increment; C_p =
            // (4/h^2) sum w v_i (x_i - x_p)^T, with x_i - x_p = h ((a,b,c) - fx)
            for (int j = 0; j < n; ++j) {
                const int32_t p = slots[j];
                const Stencil st = make_stencil(geo.to_grid(state.x[p].template cast<Real>()));
                alignas(32) Real sums[5][kLaneCount];
                gather_velocity<kTheta>(win, st, origin, sums);
                chunk.set_gathered(j, sums, c_scale * h);
                speed2 = std::max(speed2, Vec3(sums[0][0], sums[0][1], sums[0][2]).squaredNorm());
                const Mat3 Fe = state.Fe[p].template cast<Real>();
                for (int k = 0; k < 9; ++k) chunk.F[k][j] = Fe(k);
                chunk.J_start[j] = state.J[p];
            }
            chunk.pad_kinematics(n);

            // 2. kinematics, four particles at a time: Fe_trial = (I + dt C) Fe, J *= det(I + dt C)
            for (int j = 0; j < n; j += kLaneCount) {
                LaneMat3 dF, Fe;
                const Lanes dt_lanes = splat<Lanes>(dt);
                for (int col = 0; col < 3; ++col)
                    for (int row = 0; row < 3; ++row) {
                        const Lanes C = chunk.lanes(chunk.C[3 * col + row], j);
                        dF(row, col) =
                            row == col ? fused_madd(dt_lanes, C, splat<Lanes>(1)) : dt_lanes * C;
                        Fe(row, col) = chunk.lanes(chunk.F[3 * col + row], j);
                    }
                const LaneMat3 Fe_trial = lanes_product(dF, Fe);
                for (int k = 0; k < 9; ++k) chunk.store(chunk.F[k], j, Fe_trial.m[k]);
                chunk.store(chunk.J_new, j, chunk.lanes(chunk.J_start, j) * lanes_determinant(dF));
            }

            // 3. pore update (Eq. 6, 10, 11, 12): theta, Jw, Fe compensation, mass, cohesion;
            // the hardening and p0's lower bound the inside test reads
            for (int j = 0; j < n; ++j) {
                const int32_t p = slots[j];
                Real beta = beta_saturated;
                Real alpha = kNacc ? state.alpha[p] : Real(0);
                if constexpr (kPore) {
                    Real theta = state.theta[p];
                    if constexpr (kTheta) {
                        Real solved = std::clamp(theta + chunk.dtheta[j], Real(0), moist.eta);
                        if (evaporating && evaporating[p]) {
                            // the volume the moisture solve saw
                            const Real V = state.V0[p] * chunk.J_start[j];
                            solved = moist.theta0 +
                                     (solved - moist.theta0) *
                                         std::exp(-evaporation_rate_dt * inv_cube_root(V));
                        }
                        if (theta_rate)
                            theta_rate[p] = (solved - theta) * inv_moisture_dt;
                        else
                            theta = solved;
                    }
                    // a solve every k steps: its increment spread over the steps that follow,
                    // so the crust shrinks every step, not in k-step jolts
                    if (theta_rate)
                        theta = std::clamp(theta + theta_rate[p] * dt, Real(0), moist.eta);
                    state.theta[p] = theta;
                    const Real s = saturation_of(theta, moist.eta);
                    const PoreStep ps = pore_step(state.Jw[p], s, moist.eta, moist.max_log_jw_step);
                    if (ps.Fe_scale != 1)
                        for (int k = 0; k < 9; ++k) chunk.F[k][j] *= ps.Fe_scale;
                    state.Jw[p] = ps.Jw;
                    if constexpr (kNacc) {
                        alpha += moist.eps * ps.log_ratio;
                        beta = cohesion_of(nacc, s);
                    }
                    state.mass[p] = moist_mass(state.V0[p], rho_s, s, moist);
                }
                if constexpr (kNacc) {
                    const Real strength = has_strength ? state.strength[p] : Real(1);
                    if (has_damage) beta = damaged_cohesion(beta, state.damage[p]);
                    chunk.alpha[j] = alpha;
                    chunk.beta[j] = beta;
                    chunk.p0[j] = strength * nacc_p0_lower_bound(alpha, nacc.xi, lame.kappa);
                }
            }
            if constexpr (kNacc) chunk.pad_hardening(n);

            // 4. the Neo-Hookean terms of Fe_trial, the inside test and the Kirchhoff stress,
            // four particles at a time
            for (int j = 0; j < n; j += kLaneCount) {
                LaneMat3 Fe_trial;
                for (int k = 0; k < 9; ++k) Fe_trial.m[k] = chunk.lanes(chunk.F[k], j);
                const NeoHookeanLaneTerms terms = neo_hookean_terms(Fe_trial, lame);
                chunk.store(chunk.J_trial, j, terms.J);
                for (int k = 0; k < 6; ++k) chunk.store(chunk.b[k], j, terms.b[k]);
                chunk.store(chunk.mean_b, j, terms.mean_b);
                chunk.store(chunk.shear, j, terms.shear);
                if constexpr (kNacc) {
                    const LaneMask inside = clearly_inside_yield_surface(
                        terms.J, terms.b, terms.mean_b, terms.shear, chunk.lanes(chunk.p0, j),
                        chunk.lanes(chunk.beta, j), nacc, lame);
                    for (int l = 0; l < kLaneCount; ++l) chunk.inside[j + l] = inside[l] != 0;
                }
                if constexpr (std::is_same_v<S, Real>) {
                    Lanes tau_lanes[6];
                    neo_hookean_kirchhoff_of(terms.J, terms.b, terms.mean_b, terms.shear, lame,
                                             tau_lanes);
                    for (int k = 0; k < 6; ++k) chunk.store(chunk.tau[k], j, tau_lanes[k]);
                }
            }

            // 5. plasticity: NACC return mapping with the particle's strength and damage where
            // the state is not clearly inside, else Fe_trial (what the return map would return,
            // case 3a); the stress of the new Fe for the next P2G; advection; checks
            for (int j = 0; j < n; ++j) {
                const int32_t p = slots[j];
                state.J[p] = chunk.J_new[j];
                Mat3 Fe_trial;
                for (int k = 0; k < 9; ++k) Fe_trial(k) = chunk.F[k][j];
                bool is_elastic = true;
                if constexpr (kNacc) {
                    is_elastic = chunk.inside[j];
                    if (is_elastic) {
                        state.alpha[p] = chunk.alpha[j];
                    } else {
                        const Real strength = has_strength ? state.strength[p] : Real(1);
                        const NeoHookeanTerms trial_terms = chunk.terms(j);
                        const NaccProjection r = nacc_project(Fe_trial, trial_terms, chunk.alpha[j],
                                                              chunk.beta[j], nacc, lame, strength);
                        if (has_damage)
                            state.damage[p] = damage_after_return(state.damage[p], chunk.alpha[j],
                                                                  r.alpha, nacc.damage_strain);
                        state.Fe[p] = r.Fe.template cast<S>();
                        state.alpha[p] = r.alpha;
                    }
                }
                bool is_inverted = false;  // the stored Fe (checked in float only: see below)
                if constexpr (std::is_same_v<S, Real>) {
                    if (is_elastic) {
                        state.Fe[p] = Fe_trial;
                        tau[p] = {chunk.tau[0][j], chunk.tau[1][j], chunk.tau[2][j],
                                  chunk.tau[3][j], chunk.tau[4][j], chunk.tau[5][j]};
                    } else {
                        tau[p] = neo_hookean_kirchhoff(neo_hookean_terms(state.Fe[p], lame), lame);
                    }
                } else {
                    // the stress of Fe as stored (rounded to float), as kirchhoff_stresses
                    // computes it after a resume or a rollback, so a resumed run continues bit for
                    // bit. Read back through a volatile pointer: g++ 12 at -O3 -march=native gave
                    // the stress the unrounded Fe when the stored matrix was read back directly
                    // (caught by FloatState.ACopyContinuesBitForBit and the float resume test)
                    if (is_elastic) state.Fe[p] = Fe_trial.template cast<S>();
                    const volatile S* stored = state.Fe[p].data();
                    Mat3 Fe_stored;
                    for (int k = 0; k < 9; ++k) Fe_stored(k) = static_cast<Real>(stored[k]);
                    const NeoHookeanTerms stored_terms = neo_hookean_terms(Fe_stored, lame);
                    tau[p] = neo_hookean_kirchhoff(stored_terms, lame);
                    // rounding a nearly singular Fe can invert it (a 200 m/s impact in the
                    // stability matrix: 305 particles with det Fe <= 0 and no error, while J, kept
                    // in double, stayed > 0): the step fails its checks and is retried, as for
                    // J <= 0
                    is_inverted = !(stored_terms.J > 0);
                }

                // advect, clamped into the domain box
                const Vec3 vp(chunk.v[0][j], chunk.v[1][j], chunk.v[2][j]);
                Mat3 Cp;
                for (int k = 0; k < 9; ++k) Cp(k) = chunk.C[k][j];
                Vec3 x = state.x[p].template cast<Real>() + dt * vp;
                x = x.cwiseMax(lo).cwiseMin(hi);
                state.x[p] = x.template cast<S>();
                state.v[p] = vp.template cast<S>();
                state.C[p] = Cp.template cast<S>();

                // finite-ness: a NaN or inf anywhere poisons the sum; J <= 0 is an inverted
                // particle, which no stable step produces (it precedes the overflow by many steps)
                // (as stored: a float state overflows to inf at its own range)
                Real check = Real(state.x[p].sum()) + Real(state.v[p].sum()) +
                             Real(state.Fe[p].sum()) + state.J[p];
                if constexpr (kNacc) check += state.alpha[p];
                if constexpr (kPore) check += state.theta[p];
                if ((!std::isfinite(check) || !(state.J[p] > 0) || is_inverted) &&
                    (bad[t] < 0 || p < bad[t]))
                    bad[t] = p;
            }
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
    if (pore_update) {
        MoistureUpdate rate_only;  // between two solves only the theta rate applies
        rate_only.theta_rate = moisture.theta_rate;
        return dispatch_nacc<false, true>(model, state, grid, rate_only, dt, windows, tau);
    }
    return dispatch_nacc<false, false>(model, state, grid, MoistureUpdate{}, dt, windows, tau);
}

}  // namespace mudcrack::mpm
