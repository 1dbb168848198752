#include "sim/moisture/moisture_solver.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include <Eigen/Core>

#include "sim/core/parallel.h"
#include "sim/core/stats.h"
#include "sim/grid/bspline.h"

namespace mudcrack {

using mpm::kBlockNodes;
using mpm::kBlockWidth;
using mpm::kWindowNodes;
using mpm::kWindowWidth;
using mpm::SparseGrid;

namespace {

int64_t node_count(const SparseGrid& grid) {
    return static_cast<int64_t>(grid.n_blocks()) * kBlockNodes;
}

void resize_zero(std::vector<Real>& v, int64_t n) {
    v.resize(n);
    parallel_chunks(
        n, [&](int, int64_t b, int64_t e) { std::fill(v.begin() + b, v.begin() + e, Real(0)); });
}

// The N sums over nodes of what body(node, sums) adds to them, taken per block and then over the
// blocks in block order: the same bits for any thread count. The body may update its node too,
// so a vector update and the dot products that follow it share one pass over the nodes.
template <int N, class Body>
std::array<Real, N> block_sums(const SparseGrid& grid, std::vector<Real>& partial, Body&& body) {
    const int64_t nb = static_cast<int64_t>(grid.n_blocks());
    partial.resize(nb * N);
    parallel_for(nb, [&](int64_t b) {
        std::array<Real, N> acc{};
        const int64_t base = b * kBlockNodes;
        for (int k = 0; k < kBlockNodes; ++k) body(base + k, acc);
        for (int j = 0; j < N; ++j) partial[b * N + j] = acc[j];
    });
    std::array<Real, N> total{};
    for (int64_t b = 0; b < nb; ++b)
        for (int j = 0; j < N; ++j) total[j] += partial[b * N + j];
    return total;
}

// face-adjacent block slots of every allocated block (-1 where none is allocated)
void build_face_neighbors(const SparseGrid& grid, MoistureGrid& mg) {
    const int64_t nb = static_cast<int64_t>(grid.n_blocks());
    mg.block_face_neighbors.resize(nb);
    parallel_for(nb, [&](int64_t b) {
        const Vec3i c = grid.geo.block_coord(grid.block_keys[b]);
        for (int d = 0; d < 3; ++d)
            for (int side = 0; side < 2; ++side) {
                Vec3i q = c;
                q[d] += side ? 1 : -1;
                int32_t slot = -1;
                if (q[d] >= 0 && q[d] < grid.geo.blocks[d])
                    slot = grid.find_block(grid.geo.block_key(q.x(), q.y(), q.z()));
                mg.block_face_neighbors[b][2 * d + side] = slot;
            }
    });
}

// Whether grid node g lies in the ground or in the domain's wall band, when the shot seals them:
// such a node is never air, neither for mark_surface_nodes nor for the exposed layer's air probe,
// which counts it as full of soil.
bool node_is_sealed(const mpm::GridGeometry& geo, const MoistureSeal& seal, const Vec3i& g) {
    if (!seal.seal_colliders) return false;
    for (int d = 0; d < 3; ++d)
        if (g[d] < geo.padding || g[d] > geo.cells[d] - geo.padding) return true;
    return seal.has_ground && geo.origin.y() + geo.h * g.y() <= seal.ground_height;
}

// surface nodes: mass > 0 and an empty face neighbour that is air (not sealed by a collider).
// Each block copies its "has mass" flags with a one-node halo from its 6 face neighbours into a
// 6x6x6 array, so the 6-neighbour test is six loads at fixed offsets.
void mark_surface_nodes(const SparseGrid& grid, const MoistureSeal& seal, MoistureGrid& mg) {
    constexpr int kW = kBlockWidth + 2;  // halo array width
    const mpm::GridGeometry& geo = grid.geo;
    const int64_t nb = static_cast<int64_t>(grid.n_blocks());
    mg.surface.resize(nb * kBlockNodes);
    // "has mass" read as W_i = sum_p V_p w_ip > 0: the same weights with positive V and m, so
    // the same nodes, from a quarter of the memory of the mechanics node array
    const Real* W = mg.W.data();
    auto has_mass = [&](int32_t slot, int a, int b, int c) {
        return W[static_cast<int64_t>(slot) * kBlockNodes + mpm::block_node_index(a, b, c)] > 0;
    };
    auto at = [](int a, int b, int c) { return (a * kW + b) * kW + c; };
    const int step[3] = {kW * kW, kW, 1};
    parallel_for(nb, [&](int64_t b) {
        uint8_t filled[kW * kW * kW] = {};
        const int32_t self = static_cast<int32_t>(b);
        for (int a = 0; a < kBlockWidth; ++a)
            for (int bb = 0; bb < kBlockWidth; ++bb)
                for (int c = 0; c < kBlockWidth; ++c)
                    filled[at(a + 1, bb + 1, c + 1)] = has_mass(self, a, bb, c);
        // the halo: the facing layer of each face neighbour (none allocated: empty)
        for (int d = 0; d < 3; ++d)
            for (int side = 0; side < 2; ++side) {
                const int32_t slot = mg.block_face_neighbors[b][2 * d + side];
                if (slot < 0) continue;
                for (int u = 0; u < kBlockWidth; ++u)
                    for (int v = 0; v < kBlockWidth; ++v) {
                        int src[3], dst[3];
                        const int e = (d + 1) % 3, f = (d + 2) % 3;
                        src[d] = side ? 0 : kBlockWidth - 1;
                        dst[d] = side ? kBlockWidth + 1 : 0;
                        src[e] = u, dst[e] = u + 1;
                        src[f] = v, dst[f] = v + 1;
                        filled[at(dst[0], dst[1], dst[2])] = has_mass(slot, src[0], src[1], src[2]);
                    }
            }
        const Vec3i corner = geo.block_coord(grid.block_keys[b]) * kBlockWidth;
        for (int a = 0; a < kBlockWidth; ++a)
            for (int bb = 0; bb < kBlockWidth; ++bb)
                for (int c = 0; c < kBlockWidth; ++c) {
                    const int n = at(a + 1, bb + 1, c + 1);
                    Real flag = 0;
                    if (filled[n]) {
                        for (int d = 0; d < 3 && flag == 0; ++d)
                            for (int side = 0; side < 2 && flag == 0; ++side) {
                                if (filled[n + (side ? step[d] : -step[d])]) continue;
                                Vec3i g = corner + Vec3i(a, bb, c);
                                g[d] += side ? 1 : -1;
                                if (!node_is_sealed(geo, seal, g)) flag = 1;
                            }
                    }
                    mg.surface[b * kBlockNodes + mpm::block_node_index(a, bb, c)] = flag;
                }
    });
}

// The window of one particle block as 4-lane z rows (ZRow; not sim/core/lanes.h's Lanes, which
// hold four particles): a particle's 3 stencil nodes along z are loaded and stored as 4
// contiguous values whose 4th lane has weight 0. Its sub-windows are
// kWindowStride apart so that lane past the last node stays inside the scratch.
using ZRow = Eigen::Array<Real, 4, 1>;
constexpr int kWindowStride = kWindowNodes + 8;

inline ZRow load_z_row(const Real* p) { return Eigen::Map<const ZRow>(p); }
inline void add_z_row(Real* p, const ZRow& v) { Eigen::Map<ZRow>(p) += v; }

// A particle's stencil base in its particle block's window coordinates (0 to 3 per axis).
inline Vec3i stencil_base_in_block(const Vec3& xg, const Vec3i& block_origin) {
    return Vec3i(mpm::stencil_base(xg.x()), mpm::stencil_base(xg.y()), mpm::stencil_base(xg.z())) -
           block_origin;
}

// Which of a particle block's 4x4x4 stencil bases have a surface node in their 3x3x3 stencil,
// from the block's window of surface flags: a separable 3-wide "any", along z, then y, then x.
using StencilBaseFlags = bool[kBlockWidth][kBlockWidth][kBlockWidth];
void stencil_bases_touching_surface(const Real* surface_window, StencilBaseFlags& touches) {
    bool along_z[kWindowWidth][kWindowWidth][kBlockWidth],
        along_yz[kWindowWidth][kBlockWidth][kBlockWidth];
    for (int a = 0; a < kWindowWidth; ++a)
        for (int b = 0; b < kWindowWidth; ++b)
            for (int c = 0; c < kBlockWidth; ++c) {
                const Real* row = surface_window + mpm::window_index(a, b, c);
                along_z[a][b][c] = row[0] > 0 || row[1] > 0 || row[2] > 0;
            }
    for (int a = 0; a < kWindowWidth; ++a)
        for (int b = 0; b < kBlockWidth; ++b)
            for (int c = 0; c < kBlockWidth; ++c)
                along_yz[a][b][c] =
                    along_z[a][b][c] || along_z[a][b + 1][c] || along_z[a][b + 2][c];
    for (int a = 0; a < kBlockWidth; ++a)
        for (int b = 0; b < kBlockWidth; ++b)
            for (int c = 0; c < kBlockWidth; ++c)
                touches[a][b][c] =
                    along_yz[a][b][c] || along_yz[a + 1][b][c] || along_yz[a + 2][b][c];
}

// Surface evaporation: a particle is in the exposed layer when the grid's volume fraction at it,
// sum_i w_ip W_i / h^3, is below this. On a flat face it is 0.62-0.66 on the outer particle layer
// and 0.84-0.87 on the next at 2 particles per cell and axis (over all offsets of the lattice to
// the grid; 0.64-0.69 and 0.89-0.92 at 0.6 h spacing, the tet init's), so the exposed layer is one
// particle thick; corners and edges lie lower still.
constexpr Real kExposedVolumeFraction = 0.75;

// The air an exposed-layer particle must face: the grid's volume fraction at most this, two cells
// outward from it. Over a flat face that point has none (the particle layers lie 2 and 2.5 cells
// from it, past the kernel's 1.5); in a crack it reaches the far wall's particles unless the walls
// stand about 3 cells apart, where the grid mode's first empty node appears, so narrow cracks keep
// their walls wet in both modes.
constexpr Real kAirProbeCells = 2;
constexpr Real kAirVolumeFraction = 0.25;
// A bottom layer (h / 4 above the ground at 2 particles per cell) has no surface node near and
// faces the ground: the node nearest half a cell outward from it is sealed.
constexpr Real kSealProbeCells = 0.5;

// The 27 blocks around a particle block (-1, 0, +1 per axis), looked up once when a particle of
// the block needs a node outside its window: a slot, or -1 where none is allocated (no mass).
struct BlockNeighborhood {
    Vec3i first_block;  // block coordinates of the (-1, -1, -1) neighbour
    int32_t slot[3][3][3];
};

BlockNeighborhood block_neighborhood(const SparseGrid& grid, int32_t pblock) {
    const mpm::GridGeometry& geo = grid.geo;
    BlockNeighborhood nb;
    nb.first_block = geo.block_coord(grid.pblock_key[pblock]) - Vec3i::Ones();
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            for (int c = 0; c < 3; ++c) {
                const Vec3i blk = nb.first_block + Vec3i(a, b, c);
                nb.slot[a][b][c] =
                    (blk.array() < 0).any() || (blk.array() >= geo.blocks.array()).any()
                        ? -1
                        : grid.find_block(geo.block_key(blk.x(), blk.y(), blk.z()));
            }
    return nb;
}

// sum_i w_i(xg) W_i / h^3 at a grid point within a cell of a particle block's window, a sealed
// node counting as a full cell.
Real volume_fraction_at(const SparseGrid& grid, const MoistureSeal& seal,
                        const std::vector<Real>& W, const BlockNeighborhood& nb, const Vec3& xg) {
    const mpm::GridGeometry& geo = grid.geo;
    const Real cell_volume = geo.h * geo.h * geo.h;
    const mpm::Stencil st = mpm::make_stencil(xg);
    Real sum = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            for (int c = 0; c < 3; ++c) {
                const Vec3i g(st.axis[0].base + a, st.axis[1].base + b, st.axis[2].base + c);
                if (node_is_sealed(geo, seal, g)) {
                    sum += st.weight(a, b, c) * cell_volume;
                    continue;
                }
                const Vec3i blk = (g.array() >= 0).select(g / kBlockWidth, -Vec3i::Ones());
                const Vec3i k = blk - nb.first_block;
                if ((k.array() < 0).any() || (k.array() > 2).any()) continue;  // beyond: empty
                const int32_t slot = nb.slot[k.x()][k.y()][k.z()];
                if (slot < 0) continue;
                const Vec3i in = g - blk * kBlockWidth;
                sum += st.weight(a, b, c) * W[static_cast<int64_t>(slot) * kBlockNodes +
                                              mpm::block_node_index(in.x(), in.y(), in.z())];
            }
    return sum / cell_volume;
}

// Surface evaporation's exposed layer (docs/physics.md §6.3): a particle evaporates when the
// grid's volume fraction phi_p = sum_i w_ip W_i / h^3 at it is below kExposedVolumeFraction and it
// faces air: a surface node (a node with mass beside an empty one that is not sealed) in its
// stencil, as the grid mode's boundary particles have, or else, looking along -grad phi_p, no
// ground or wall kSealProbeCells out (when the shot seals them) and no more than
// kAirVolumeFraction of soil kAirProbeCells out. The second test finds the floor of a dimple or a
// fold of a curled crust, where the soil around fills the nodes over the floor with mass up to a
// node beyond its particles' stencils; with the first alone those particles kept their water in
// cell-sized patches. It reads the sparse grid node by node, so it runs only where the first does
// not decide. Each particle writes its own flag: no colours.
template <class S>
void exposed_layer_pass(const MoistureSeal& seal, const SparseGrid& grid,
                        const MoistureParticlesOf<S>& pp, MoistureGrid& mg,
                        std::vector<std::vector<Real>>& windows) {
    const mpm::GridGeometry& geo = grid.geo;
    const Real exposed_W = kExposedVolumeFraction * geo.h * geo.h * geo.h;
    mpm::for_each_pblock(grid, [&](int t, int32_t pb) {
        Real* ww = windows[t].data();   // W_i
        Real* lw = ww + kWindowStride;  // 1 where W_i < exposed_W off the ground and walls
        Real* sw = lw + kWindowStride;  // surface flags
        mpm::gather_window<1, 1, 1>(grid, pb, mg.W.data(), 0, ww);
        const Vec3i origin = geo.block_coord(grid.pblock_key[pb]) * kBlockWidth;
        bool any_low = false;
        for (int n = 0; n < kWindowNodes; ++n) {
            lw[n] = 0;
            if (ww[n] >= exposed_W) continue;
            const int a = n / (kWindowWidth * kWindowWidth), b = n / kWindowWidth % kWindowWidth,
                      c = n % kWindowWidth;
            if (node_is_sealed(geo, seal, origin + Vec3i(a, b, c))) continue;
            lw[n] = 1;
            any_low = true;
        }
        // phi_p is a convex combination of its stencil's W_i / h^3, so a particle whose stencil
        // has no node below the threshold is not in the exposed layer; one whose only such nodes
        // are sealed faces the ground or a wall
        if (!any_low) {
            for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i)
                mg.particle_is_boundary[grid.order[i]] = 0;
            return;
        }
        std::optional<BlockNeighborhood> neighborhood;  // for the air probes, on first use
        StencilBaseFlags near_low, touches_surface;
        stencil_bases_touching_surface(lw, near_low);
        mpm::gather_window<1, 1, 1>(grid, pb, mg.surface.data(), 0, sw);
        stencil_bases_touching_surface(sw, touches_surface);
        for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i) {
            const int32_t p = grid.order[i];
            const Vec3 xg = geo.to_grid(pp.x[p].template cast<Real>());
            const Vec3i o = stencil_base_in_block(xg, origin);
            mg.particle_is_boundary[p] = 0;
            if (!near_low[o[0]][o[1]][o[2]]) continue;
            const mpm::Stencil st = mpm::make_stencil(xg);
            const mpm::AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
            Real phi = 0;  // times h^3
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    const Real* row = ww + mpm::window_index(o[0] + a, o[1] + b, o[2]);
                    phi += ax.w[a] * ay.w[b] *
                           (az.w[0] * row[0] + az.w[1] * row[1] + az.w[2] * row[2]);
                }
            if (phi >= exposed_W) continue;
            if (touches_surface[o[0]][o[1]][o[2]]) {
                mg.particle_is_boundary[p] = 1;
                continue;
            }
            // no surface node near: which way the outer layer faces here, and whether that is air
            Vec3 grad = Vec3::Zero();  // of phi h^3, per cell
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    const Real* row = ww + mpm::window_index(o[0] + a, o[1] + b, o[2]);
                    const Real wz = az.w[0] * row[0] + az.w[1] * row[1] + az.w[2] * row[2];
                    const Real dwz = az.dw[0] * row[0] + az.dw[1] * row[1] + az.dw[2] * row[2];
                    grad.x() += ax.dw[a] * ay.w[b] * wz;
                    grad.y() += ax.w[a] * ay.dw[b] * wz;
                    grad.z() += ax.w[a] * ay.w[b] * dwz;
                }
            const Real grad_norm = grad.norm();
            // no outward direction (a neighbourhood symmetric about the particle, as in the middle
            // of a narrow gap): no side to face the air from
            if (grad_norm == 0) continue;
            const Vec3 outward = -grad / grad_norm;
            const Vec3 near = xg + kSealProbeCells * outward;
            if (node_is_sealed(geo, seal,
                               Vec3i(static_cast<int>(std::floor(near.x() + 0.5)),
                                     static_cast<int>(std::floor(near.y() + 0.5)),
                                     static_cast<int>(std::floor(near.z() + 0.5)))))
                continue;
            if (!neighborhood) neighborhood = block_neighborhood(grid, pb);
            mg.particle_is_boundary[p] =
                volume_fraction_at(grid, seal, mg.W, *neighborhood,
                                   xg + kAirProbeCells * outward) <= kAirVolumeFraction;
        }
    });
}

// The evaporation pass (docs/physics.md §4.2, §4.4): finds the boundary particles (a surface node
// in their stencil; the containing-cell variant of docs/physics.md §4.4 misses flat faces: with 2
// particles per cell the last massive node lies 1.25 h above the top layer, outside its cell)
// and scatters their evaporation: r into mg.evaporation (zeroed), and lambda S w^2 into mg.diag
// when the Robin term is implicit. Particle blocks whose window holds no surface node are skipped.
template <class S>
void evaporation_pass(const MoistureParams& mp, const SparseGrid& grid,
                      const MoistureParticlesOf<S>& pp, MoistureGrid& mg,
                      std::vector<std::vector<Real>>& windows) {
    const mpm::GridGeometry& geo = grid.geo;
    const bool implicit_robin = mp.implicit_robin;
    auto visit_block = [&](int t, int32_t pb) {
        Real* sw = windows[t].data();   // surface flags
        Real* rw = sw + kWindowStride;  // evaporation r
        Real* dw = rw + kWindowStride;  // Robin diagonal
        mpm::gather_window<1, 1, 1>(grid, pb, mg.surface.data(), 0, sw);
        const bool any_surface = std::any_of(sw, sw + kWindowNodes, [](Real f) { return f > 0; });
        if (!any_surface) {
            for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i)
                mg.particle_is_boundary[grid.order[i]] = 0;
            return;
        }
        std::fill(rw, rw + 2 * kWindowStride, Real(0));
        StencilBaseFlags touches_surface;
        stencil_bases_touching_surface(sw, touches_surface);
        bool any_boundary = false;
        const Vec3i origin = geo.block_coord(grid.pblock_key[pb]) * kBlockWidth;
        for (int32_t i = grid.pblock_begin[pb]; i < grid.pblock_begin[pb + 1]; ++i) {
            const int32_t p = grid.order[i];
            // the stencil base first: the weights are needed only on boundary particles
            const Vec3 xg = geo.to_grid(pp.x[p].template cast<Real>());
            const Vec3i o = stencil_base_in_block(xg, origin);
            const bool is_boundary = touches_surface[o[0]][o[1]][o[2]];
            mg.particle_is_boundary[p] = is_boundary;
            if (!is_boundary) continue;
            any_boundary = true;
            const mpm::Stencil st = mpm::make_stencil(xg);
            const mpm::AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
            const int o0 = o[0], o1 = o[1], o2 = o[2];
            const Real lambda_S = mp.lambda * particle_area(pp.V0[p] * pp.J[p]);
            // explicit: r_i = -S lambda (theta_p - theta_0) w_ip; implicit: r_0,i =
            // S lambda theta_0 w_ip, and S lambda w_ip^2 on the diagonal
            const Real source =
                implicit_robin ? lambda_S * mp.theta0 : -lambda_S * (pp.theta[p] - mp.theta0);
            // z rows of 4 lanes (4th z weight 0), as in the operator pass
            const ZRow wz(az.w[0], az.w[1], az.w[2], 0);
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) {
                    const int n = mpm::window_index(o0 + a, o1 + b, o2);
                    const Real wab = ax.w[a] * ay.w[b];
                    add_z_row(rw + n, (source * wab) * wz);
                    if (implicit_robin) add_z_row(dw + n, (lambda_S * wab * wab) * (wz * wz));
                }
        }
        if (any_boundary) {
            mpm::flush_window<1, 1>(grid, pb, rw, mg.evaporation.data());
            if (implicit_robin) mpm::flush_window<1, 1>(grid, pb, dw, mg.diag.data());
        }
    };
    mpm::for_each_pblock_colored(grid, visit_block);
}

// What the operator pass keeps of one particle between its gather and its scatter.
struct OperatorParticle {
    Real wx[3], dwx[3], wy[3], dwy[3];  // x and y weights and their derivatives (d/d(x/h))
    ZRow wz, dwz;                       // z weights and derivatives, 4th lane 0
    Real gx, gy, gz;                    // V D grad theta_p (in units of 1/h^2)
    Real robin;                         // lambda S_p sum_j w_jp x_j (implicit Robin only)
    int offset;                         // window index of the stencil's first node
};

// particles processed per gather/scatter batch: small enough for L1, large enough that the
// independent gathers of a batch overlap in the out-of-order window
constexpr int kOperatorBatch = 32;

// One gather/scatter pass over the particles (docs/physics.md §4.5): y = L x (+ R x with the
// implicit Robin term, on the particles the evaporation pass flagged). The 3x3x3 gather and scatter
// run on z rows of 4 lanes (the z weights with a zero 4th lane), which the compiler maps to one
// SIMD operation per row, and are factored axis by axis (the stencil is a tensor product): the
// gather contracts the rows over y, then over x; the scatter builds the z-row profiles per y once
// and combines them per x. Particles go in batches, all gathers then all scatters: one particle's
// gather-reduce-scatter is a long dependency chain, and the batch's gathers are independent.
// @note Longer than a page on purpose: it is the CG's hot loop, one call per iteration (measured
// by mpm_bench's Moisture cases and tools/bench_moisture_cost.sh), its batch's gathers and
// scatters sharing the window and the row weights in one pass.
template <bool kImplicitRobin, class S>
void operator_pass(const MoistureParams& mp, const SparseGrid& grid,
                   const MoistureParticlesOf<S>& pp, const MoistureGrid& mg, const Real* x, Real* y,
                   std::vector<std::vector<Real>>& windows) {
    const int64_t n_nodes = node_count(grid);
    parallel_chunks(n_nodes, [&](int, int64_t b, int64_t e) { std::fill(y + b, y + e, Real(0)); });
    const mpm::GridGeometry& geo = grid.geo;
    const Real D_scale = mp.D * geo.inv_h * geo.inv_h;
    constexpr int kRow = kWindowWidth;                   // window stride between y rows
    constexpr int kPlane = kWindowWidth * kWindowWidth;  // window stride between x planes
    mpm::for_each_pblock_colored(grid, [&](int t, int32_t pb) {
        Real* xw = windows[t].data();
        Real* yw = xw + kWindowStride;
        OperatorParticle batch[kOperatorBatch];
        mpm::gather_window<1, 1, 1>(grid, pb, x, 0, xw);
        std::fill(xw + kWindowNodes, xw + kWindowStride, Real(0));
        std::fill(yw, yw + kWindowStride, Real(0));
        const Vec3i origin = geo.block_coord(grid.pblock_key[pb]) * kBlockWidth;
        for (int32_t first = grid.pblock_begin[pb]; first < grid.pblock_begin[pb + 1];
             first += kOperatorBatch) {
            const int count = std::min<int32_t>(kOperatorBatch, grid.pblock_begin[pb + 1] - first);
            // the batch's stencils first: its 4-lane z weights are built from scalar stores, and
            // a 4-lane load right after them stalls until they retire; a batch later they have
            for (int k = 0; k < count; ++k) {
                const int32_t p = grid.order[first + k];
                OperatorParticle& op = batch[k];
                const mpm::Stencil st =
                    mpm::make_stencil(geo.to_grid(pp.x[p].template cast<Real>()));
                const mpm::AxisWeights &ax = st.axis[0], &ay = st.axis[1], &az = st.axis[2];
                op.offset = mpm::window_index(ax.base - origin.x(), ay.base - origin.y(),
                                              az.base - origin.z());
                for (int a = 0; a < 3; ++a) {
                    op.wx[a] = ax.w[a];
                    op.dwx[a] = ax.dw[a];
                    op.wy[a] = ay.w[a];
                    op.dwy[a] = ay.dw[a];
                }
                op.wz = ZRow(az.w[0], az.w[1], az.w[2], 0);
                op.dwz = ZRow(az.dw[0], az.dw[1], az.dw[2], 0);
            }
            // gather g_p = sum_j x_j grad w_jp (in units of 1/h) and s_p = sum_j w_jp x_j as z
            // rows: contract over y (w and dw), then over x; the z weights close the sums
            for (int k = 0; k < count; ++k) {
                const int32_t p = grid.order[first + k];
                OperatorParticle& op = batch[k];
                const Real* xrow = xw + op.offset;
                ZRow rx = ZRow::Zero(), ry = ZRow::Zero(), rs = ZRow::Zero();
                for (int a = 0; a < 3; ++a) {
                    const Real* plane = xrow + a * kPlane;
                    const ZRow r0 = load_z_row(plane), r1 = load_z_row(plane + kRow),
                               r2 = load_z_row(plane + 2 * kRow);
                    const ZRow wy_rows = op.wy[0] * r0 + op.wy[1] * r1 + op.wy[2] * r2;
                    const ZRow dwy_rows = op.dwy[0] * r0 + op.dwy[1] * r1 + op.dwy[2] * r2;
                    rs += op.wx[a] * wy_rows;
                    rx += op.dwx[a] * wy_rows;
                    ry += op.wx[a] * dwy_rows;
                }
                // V D grad theta_p, the 1/h of both gradients in D_scale
                const Real V = pp.V0[p] * pp.J[p];
                const Real scale = V * D_scale;
                op.gx = scale * (rx * op.wz).sum();
                op.gy = scale * (ry * op.wz).sum();
                op.gz = scale * (rs * op.dwz).sum();
                op.robin = 0;
                if constexpr (kImplicitRobin) {
                    if (mg.particle_is_boundary[p])
                        op.robin = mp.lambda * particle_area(V) * (rs * op.wz).sum();
                }
            }
            // scatter V D grad w_ip . g_p and the implicit Robin term lambda S w_ip s_p: per z row,
            // y_ab += (gx dwx_a) q_b + wx_a u_b with q_b = wy_b wz and
            // u_b = (gy dwy_b [+ robin wy_b]) wz + gz wy_b dwz. Runs of particles with the same
            // stencil (neighbours in id order often share one) sum their rows in registers and
            // add them to the window once: the rows' load-add-store chains bound this loop.
            ZRow rows[9];
            int run_offset = -1;
            auto flush_run = [&] {
                if (run_offset < 0) return;
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b)
                        add_z_row(yw + run_offset + a * kPlane + b * kRow, rows[3 * a + b]);
            };
            for (int k = 0; k < count; ++k) {
                const OperatorParticle& op = batch[k];
                if (op.offset != run_offset) {
                    flush_run();
                    run_offset = op.offset;
                    for (ZRow& r : rows) r.setZero();
                }
                ZRow q[3], u[3];
                for (int b = 0; b < 3; ++b) {
                    q[b] = op.wy[b] * op.wz;
                    Real cwz = op.gy * op.dwy[b];
                    if constexpr (kImplicitRobin) cwz += op.robin * op.wy[b];
                    u[b] = cwz * op.wz + (op.gz * op.wy[b]) * op.dwz;
                }
                for (int a = 0; a < 3; ++a) {
                    const Real cx = op.gx * op.dwx[a], wx = op.wx[a];
                    for (int b = 0; b < 3; ++b) rows[3 * a + b] += cx * q[b] + wx * u[b];
                }
            }
            flush_run();
        }
        mpm::flush_window<1, 1>(grid, pb, yw, y);
    });
}

// The node beside node (a, b, c) of block slot `blk` along axis d, on the + side or the - side:
// its index in the node fields, or -1 where its block is not allocated (no material there).
inline int64_t face_neighbor_node(const MoistureGrid& mg, int64_t blk, int a, int b, int c, int d,
                                  bool plus) {
    int q[3] = {a, b, c};
    q[d] += plus ? 1 : -1;
    int64_t slot = blk;
    if (q[d] < 0 || q[d] >= kBlockWidth) {
        slot = mg.block_face_neighbors[blk][2 * d + (plus ? 1 : 0)];
        if (slot < 0) return -1;
        q[d] = plus ? 0 : kBlockWidth - 1;
    }
    return slot * kBlockNodes + mpm::block_node_index(q[0], q[1], q[2]);
}

// Calls body(blk, a, b, c, i) for every node of every allocated block, blocks in parallel: (a, b,
// c) its coordinates in block slot blk, i its index in the node fields.
template <class Body>
void for_each_node(const SparseGrid& grid, Body&& body) {
    parallel_for(static_cast<int64_t>(grid.n_blocks()), [&](int64_t blk) {
        for (int a = 0; a < kBlockWidth; ++a)
            for (int b = 0; b < kBlockWidth; ++b)
                for (int c = 0; c < kBlockWidth; ++c)
                    body(blk, a, b, c, blk * kBlockNodes + mpm::block_node_index(a, b, c));
    });
}

// The grid operator's conductances (docs/physics.md §4.9): mg.conductance[3 i + d] = D hm(W_i,
// W_{i+e_d}) / h^2 towards the + neighbour along axis d, 0 where either node is empty.
void build_conductances(const MoistureParams& mp, const SparseGrid& grid, MoistureGrid& mg) {
    const Real scale = mp.D * grid.geo.inv_h * grid.geo.inv_h;
    mg.conductance.resize(static_cast<int64_t>(grid.n_blocks()) * kBlockNodes * 3);
    for_each_node(grid, [&](int64_t blk, int a, int b, int c, int64_t i) {
        for (int d = 0; d < 3; ++d) {
            const int64_t j = face_neighbor_node(mg, blk, a, b, c, d, true);
            mg.conductance[3 * i + d] = j < 0 ? Real(0) : scale * face_weight(mg.W[i], mg.W[j]);
        }
    });
}

// Over node i's six faces: the sum of the conductances, and the sum of each times x at the node
// across it (x = nullptr: the first alone).
inline std::array<Real, 2> face_sums(const MoistureGrid& mg, int64_t blk, int a, int b, int c,
                                     int64_t i, const Real* x) {
    Real k_sum = 0, kx_sum = 0;
    for (int d = 0; d < 3; ++d) {
        const int64_t up = face_neighbor_node(mg, blk, a, b, c, d, true);
        const int64_t down = face_neighbor_node(mg, blk, a, b, c, d, false);
        const Real k_up = mg.conductance[3 * i + d];
        const Real k_down = down < 0 ? Real(0) : mg.conductance[3 * down + d];
        k_sum += k_up + k_down;
        if (x) {
            if (k_up != 0) kx_sum += k_up * x[up];
            if (k_down != 0) kx_sum += k_down * x[down];
        }
    }
    return {k_sum, kx_sum};
}

// y = L x with the grid operator: (L x)_i = sum over the faces k_f (x_i - x_j), node by node (no
// scatter, so no colours, and the same bits for any thread count).
void grid_operator_pass(const SparseGrid& grid, const MoistureGrid& mg, const Real* x, Real* y) {
    for_each_node(grid, [&](int64_t blk, int a, int b, int c, int64_t i) {
        const std::array<Real, 2> s = face_sums(mg, blk, a, b, c, i, x);
        y[i] = s[0] * x[i] - s[1];
    });
}

// The grid operator's Jacobi diagonal, W_i / dt plus the conductances of node i's six faces.
void grid_operator_diagonal(const SparseGrid& grid, Real dt, MoistureGrid& mg) {
    for_each_node(grid, [&](int64_t blk, int a, int b, int c, int64_t i) {
        mg.diag[i] =
            mg.W[i] > 0 ? mg.W[i] / dt + face_sums(mg, blk, a, b, c, i, nullptr)[0] : Real(0);
    });
}

// y = L x (+ R x when the evaporation is implicit and on)
template <class S>
void apply_stiffness(const MoistureParams& mp, const SparseGrid& grid,
                     const MoistureParticlesOf<S>& pp, const MoistureGrid& mg, const Real* x,
                     Real* y, std::vector<std::vector<Real>>& windows) {
    if (mp.diffusion_operator == MoistureParams::DiffusionOperator::Grid)
        grid_operator_pass(grid, mg, x, y);
    else if (mp.implicit_robin && mp.lambda > 0)
        operator_pass<true, S>(mp, grid, pp, mg, x, y, windows);
    else
        operator_pass<false, S>(mp, grid, pp, mg, x, y, windows);
}

}  // namespace

Real particle_area(Real volume) {
    // pi R^2 = c V^(2/3) with c = pi (3 / (4 pi))^(2/3), and V^(2/3) as exp(2/3 log V): a few
    // ulps, at half the cost of glibc's cbrt (every boundary particle, every step)
    static const Real c = kPi * std::cbrt(9 / (16 * kPi * kPi));
    return c * std::exp(Real(2) / 3 * std::log(volume));
}

int64_t MoistureGrid::memory_bytes() const {
    return capacity_bytes(W) + capacity_bytes(theta) + capacity_bytes(diag) +
           capacity_bytes(evaporation) + capacity_bytes(x) + capacity_bytes(r) + capacity_bytes(p) +
           capacity_bytes(Ap) + capacity_bytes(surface) + capacity_bytes(conductance) +
           capacity_bytes(particle_is_boundary) + capacity_bytes(block_partial) +
           capacity_bytes(block_face_neighbors);
}

void begin_moisture_p2g(MoistureGrid& mg, const SparseGrid& grid) {
    const int64_t n = node_count(grid);
    resize_zero(mg.W, n);
    resize_zero(mg.theta, n);
}

namespace {

// Jacobi-preconditioned conjugate gradients on (M + L [+ R]) x = b, from the x, r and p that
// solve_moisture set up (mg.diag holds the inverse Jacobi diagonal); b2 = |b|^2, rz0 = r.p,
// r2 = |r|^2 of that start
template <class S>
MoistureSolveStats conjugate_gradients(const MoistureParams& mp, const SparseGrid& grid,
                                       const MoistureParticlesOf<S>& pp, Real dt, MoistureGrid& mg,
                                       std::vector<std::vector<Real>>& windows, Real b2, Real rz0,
                                       Real r2) {
    const int64_t n_nodes = node_count(grid);
    const Real inv_dt = 1 / dt;
    const std::vector<Real>& inv_diag = mg.diag;
    MoistureSolveStats stats;
    const Real b_norm = std::sqrt(b2);
    if (b_norm > 0) {
        Real rz = rz0;
        Real r_norm = std::sqrt(r2);
        const Real target = mp.cg_tolerance * b_norm;
        while (r_norm > target && stats.iterations < mp.cg_max_iterations) {
            // Ap = (M + L [+ R]) p
            apply_stiffness(mp, grid, pp, mg, mg.p.data(), mg.Ap.data(), windows);
            ++stats.iterations;
            const Real pAp =
                block_sums<1>(grid, mg.block_partial, [&](int64_t i, std::array<Real, 1>& sum) {
                    mg.Ap[i] += mg.W[i] * inv_dt * mg.p[i];
                    sum[0] += mg.p[i] * mg.Ap[i];
                })[0];
            if (!(pAp > 0)) break;  // converged to round-off (or lost positivity): keep x
            const Real step = rz / pAp;
            // x += step p, r -= step Ap, and the new |r|^2 and r.D^-1 r
            const std::array<Real, 2> next =
                block_sums<2>(grid, mg.block_partial, [&](int64_t i, std::array<Real, 2>& sum) {
                    mg.x[i] += step * mg.p[i];
                    mg.r[i] -= step * mg.Ap[i];
                    sum[0] += mg.r[i] * mg.r[i];
                    sum[1] += mg.r[i] * mg.r[i] * inv_diag[i];
                });
            r_norm = std::sqrt(next[0]);
            const Real beta = next[1] / rz;
            rz = next[1];
            parallel_for(n_nodes,
                         [&](int64_t i) { mg.p[i] = mg.r[i] * inv_diag[i] + beta * mg.p[i]; });
        }
        stats.residual = r_norm / b_norm;
    }
    return stats;
}

}  // namespace

template <class S>
MoistureSolveStats solve_moisture(const MoistureParams& mp, const MoistureSeal& seal,
                                  const SparseGrid& grid, const MoistureParticlesOf<S>& pp, Real dt,
                                  MoistureGrid& mg, MoistureFluxHistory& history,
                                  std::vector<std::vector<Real>>& windows) {
    const mpm::GridGeometry& geo = grid.geo;
    const int64_t n_nodes = node_count(grid);
    const Real inv_dt = 1 / dt;
    const size_t n_particles = grid.order.size();

    // nodal theta^n = (V theta)_i / W_i and, for the paper's operator, the Jacobi diagonal M_ii +
    // kappa D W_i / h^2 (the grid operator's exact one is set below, §4.9)
    const bool grid_operator = mp.diffusion_operator == MoistureParams::DiffusionOperator::Grid;
    mg.diag.resize(n_nodes);
    parallel_for(n_nodes, [&](int64_t i) {
        const bool has_material = mg.W[i] > 0;
        mg.theta[i] = has_material ? mg.theta[i] / mg.W[i] : Real(0);
        if (grid_operator) return;
        mg.diag[i] =
            has_material
                ? mg.W[i] * (inv_dt + kJacobiStiffnessPerWeight * mp.D * geo.inv_h * geo.inv_h)
                : Real(0);
    });

    // surface nodes (docs/physics.md §4.4); the grid operator's conductances and its exact
    // diagonal (§4.9)
    if (mp.lambda > 0 || grid_operator) build_face_neighbors(grid, mg);
    if (mp.lambda > 0) mark_surface_nodes(grid, seal, mg);
    if (grid_operator) {
        build_conductances(mp, grid, mg);
        grid_operator_diagonal(grid, dt, mg);
    }
    resize_zero(mg.evaporation, n_nodes);
    mg.particle_is_boundary.resize(n_particles);
    mg.x.resize(n_nodes);
    mg.r.resize(n_nodes);
    mg.p.resize(n_nodes);
    mg.Ap.resize(n_nodes);

    // evaporation r (and the implicit Robin diagonal), then the initial guess: theta^n
    // plus the Jacobi step on the explicit evaporation, r / diag (it takes most of the
    // evaporation's share of the initial residual), plus the increment dt F / W of the flux F
    // the history predicts (most of the diffusion's share); x holds x0 - theta^n
    if (mp.lambda > 0 && mp.evaporation == MoistureParams::Evaporation::Surface)
        exposed_layer_pass(seal, grid, pp, mg, windows);
    else if (mp.lambda > 0)
        evaporation_pass(mp, grid, pp, mg, windows);
    else
        std::fill(mg.particle_is_boundary.begin(), mg.particle_is_boundary.end(), uint8_t(0));
    const bool explicit_evaporation =
        !mp.implicit_robin && mp.lambda > 0 && mp.evaporation == MoistureParams::Evaporation::Grid;
    const bool predicted = history.count > 0;
    if (predicted) predict_moisture_flux(history, grid, dt, mg.x.data());
    // from here on diag holds the inverse Jacobi diagonal (0 off the material)
    std::vector<Real>& inv_diag = mg.diag;
    parallel_for(n_nodes, [&](int64_t i) {
        Real dx = 0;
        inv_diag[i] = mg.diag[i] > 0 ? 1 / mg.diag[i] : Real(0);
        if (mg.W[i] > 0) {
            if (predicted) dx = mg.x[i] * dt / mg.W[i];
            if (explicit_evaporation) dx += mg.evaporation[i] * inv_diag[i];
        }
        mg.x[i] = dx;
        mg.p[i] = mg.theta[i] + dx;
    });
    apply_stiffness(mp, grid, pp, mg, mg.p.data(), mg.Ap.data(), windows);

    // b = M theta^n + r; residual b - (M + L) x0 = r - M (x0 - theta^n) - L x0, formed from
    // the small terms (the M theta^n parts cancel exactly); the first direction p = D^-1 r; and
    // with them |b|^2, r.p and |r|^2
    enum { kB2, kRZ, kR2 };
    const std::array<Real, 3> initial =
        block_sums<3>(grid, mg.block_partial, [&](int64_t i, std::array<Real, 3>& sum) {
            if (mg.W[i] > 0) {
                const Real m = mg.W[i] * inv_dt;
                const Real b = mg.evaporation[i] + m * mg.theta[i];
                mg.r[i] = mg.evaporation[i] - m * mg.x[i] - mg.Ap[i];
                mg.x[i] += mg.theta[i];
                sum[kB2] += b * b;
            } else {
                mg.r[i] = mg.x[i] = 0;
            }
            mg.p[i] = mg.r[i] * inv_diag[i];
            sum[kRZ] += mg.r[i] * mg.p[i];
            sum[kR2] += mg.r[i] * mg.r[i];
        });

    // Jacobi-preconditioned conjugate gradients
    const MoistureSolveStats stats = conjugate_gradients(mp, grid, pp, dt, mg, windows,
                                                         initial[kB2], initial[kRZ], initial[kR2]);

    // increment theta^{n+1} - theta^n for the FLIP G2P; the history records its part beyond the
    // evaporation's Jacobi step as a flux, (W / dt)(increment - r / diag), in the free Ap
    parallel_for(n_nodes, [&](int64_t i) {
        if (!(mg.W[i] > 0)) {
            mg.x[i] = mg.Ap[i] = 0;
            return;
        }
        const Real m = mg.W[i] * inv_dt;
        mg.x[i] -= mg.theta[i];
        const Real evaporation_step =
            explicit_evaporation ? mg.evaporation[i] * inv_diag[i] : Real(0);
        mg.Ap[i] = m * (mg.x[i] - evaporation_step);
    });
    record_moisture_flux(history, grid, mg.Ap.data(), dt);
    return stats;
}

template MoistureSolveStats solve_moisture(const MoistureParams&, const MoistureSeal&,
                                           const SparseGrid&, const MoistureParticlesOf<double>&,
                                           Real, MoistureGrid&, MoistureFluxHistory&,
                                           std::vector<std::vector<Real>>&);
template MoistureSolveStats solve_moisture(const MoistureParams&, const MoistureSeal&,
                                           const SparseGrid&, const MoistureParticlesOf<float>&,
                                           Real, MoistureGrid&, MoistureFluxHistory&,
                                           std::vector<std::vector<Real>>&);

}  // namespace mudcrack
