// The moisture CG's flux history: exact extrapolation of fluxes linear in time (uniform and
// varying dt), blocks that come and go, and forgetting.
#include <gtest/gtest.h>

#include <cmath>

#include "mpm/mpm_test_util.h"
#include "sim/grid/sparse_grid.h"
#include "sim/moisture/flux_history.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

using mpm::kBlockNodes;

// a grid whose blocks cover particles on a lattice at lo (h = 0.1, 2 per cell per axis)
mpm::SparseGrid grid_over(const Vec3& lo, const Vec3i& n) {
    const test::Lattice l = test::make_lattice(lo, n, 0.05);
    mpm::SparseGrid grid;
    grid.geo = mpm::make_grid_geometry(Vec3::Constant(-1), Vec3::Constant(1), 0.1, 3);
    std::vector<int32_t> id(l.X.size());
    for (size_t i = 0; i < id.size(); ++i) id[i] = static_cast<int32_t>(i);
    mpm::bin_particles(grid, l.X, id);
    return grid;
}

// a flux that depends on the node's block key, its index in the block and the time
Real flux_at(uint32_t key, int k, Real t) {
    return std::sin(0.1 * key + 0.3 * k) + (1 + 0.01 * k) * t;
}

std::vector<Real> flux_field(const mpm::SparseGrid& g, Real t) {
    std::vector<Real> f(g.n_blocks() * kBlockNodes);
    for (size_t b = 0; b < g.n_blocks(); ++b)
        for (int k = 0; k < kBlockNodes; ++k)
            f[b * kBlockNodes + k] = flux_at(g.block_keys[b], k, t);
    return f;
}

TEST(MoistureFluxHistory, ExtrapolatesAFluxLinearInTimeExactly) {
    const mpm::SparseGrid g = grid_over(Vec3(-0.3, -0.2, -0.25), Vec3i(12, 8, 10));
    ASSERT_GT(g.n_blocks(), 1u);
    // steps of varying length; each solve's flux is the flux at its step's midpoint
    const Real dts[] = {0.02, 0.05, 0.03};
    MoistureFluxHistory h;
    Real t = 0;
    std::vector<Real> predicted(g.n_blocks() * kBlockNodes);
    for (int s = 0; s < 2; ++s) {
        record_moisture_flux(h, g, flux_field(g, t + dts[s] / 2).data(), dts[s]);
        t += dts[s];
    }
    EXPECT_EQ(h.count, 2);
    predict_moisture_flux(h, g, dts[2], predicted.data());
    const std::vector<Real> expected = flux_field(g, t + dts[2] / 2);
    for (size_t i = 0; i < expected.size(); ++i)
        ASSERT_NEAR(predicted[i], expected[i], tol::kRoundoff) << "node " << i;

    // one solve recorded: the flux is held
    MoistureFluxHistory one;
    const std::vector<Real> f0 = flux_field(g, 0.5);
    record_moisture_flux(one, g, f0.data(), 0.01);
    predict_moisture_flux(one, g, 0.04, predicted.data());
    for (size_t i = 0; i < f0.size(); ++i) ASSERT_EQ(predicted[i], f0[i]);

    // forgotten: nothing to predict from
    one.clear();
    EXPECT_EQ(one.count, 0);
}

TEST(MoistureFluxHistory, FollowsBlocksByKeyAsTheMaterialMoves) {
    // the second grid drops the first's lowest blocks and gains new ones above
    const mpm::SparseGrid g0 = grid_over(Vec3(-0.3, -0.4, -0.2), Vec3i(10, 8, 8));
    const mpm::SparseGrid g1 = grid_over(Vec3(-0.3, -0.1, -0.2), Vec3i(10, 8, 8));
    MoistureFluxHistory h;
    record_moisture_flux(h, g0, flux_field(g0, 0.0).data(), 0.1);
    record_moisture_flux(h, g1, flux_field(g1, 0.1).data(), 0.1);
    std::vector<Real> predicted(g1.n_blocks() * kBlockNodes);
    predict_moisture_flux(h, g1, 0.1, predicted.data());
    int shared = 0, fresh = 0;
    for (size_t b = 0; b < g1.n_blocks(); ++b) {
        const bool in_g0 = g0.find_block(g1.block_keys[b]) >= 0;
        (in_g0 ? shared : fresh) += 1;
        for (int k = 0; k < kBlockNodes; ++k) {
            // a block in both grids extrapolates; a new one holds its only flux (no slope from 0)
            const Real expected = flux_at(g1.block_keys[b], k, in_g0 ? 0.2 : 0.1);
            ASSERT_NEAR(predicted[b * kBlockNodes + k], expected, tol::kRoundoff) << "block " << b;
        }
    }
    EXPECT_GT(shared, 0);
    EXPECT_GT(fresh, 0);

    // a grid with blocks the history never saw predicts zero there
    const mpm::SparseGrid g2 = grid_over(Vec3(0.4, 0.4, 0.4), Vec3i(4, 4, 4));
    std::vector<Real> far(g2.n_blocks() * kBlockNodes, 1);
    predict_moisture_flux(h, g2, 0.1, far.data());
    int unseen = 0;
    for (size_t b = 0; b < g2.n_blocks(); ++b) {
        if (g1.find_block(g2.block_keys[b]) >= 0) continue;
        ++unseen;
        for (int k = 0; k < kBlockNodes; ++k)
            ASSERT_EQ(far[b * kBlockNodes + k], 0.0) << "block " << b;
    }
    EXPECT_GT(unseen, 0);
}

}  // namespace
}  // namespace mudcrack
