// Quadratic B-spline weights: partition of unity, linear reproduction, gradient identities.
#include <gtest/gtest.h>

#include <random>

#include "sim/grid/bspline.h"
#include "tolerance.h"

namespace mudcrack::mpm {
namespace {

std::vector<Vec3> sample_positions() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<Real> u(2.0, 9.0);
    std::vector<Vec3> xs;
    for (int i = 0; i < 200; ++i) xs.emplace_back(u(rng), u(rng), u(rng));
    // named degenerate ones: on a node, on a cell face, at the stencil switch (fx = 0.5)
    xs.emplace_back(3.0, 4.0, 5.0);
    xs.emplace_back(3.5, 4.5, 5.5);
    xs.emplace_back(3.5 + 1e-15, 4.5 - 1e-15, 5.0);
    return xs;
}

TEST(BSpline, AxisWeightsPartitionOfUnityAndFxRange) {
    for (const Vec3& xg : sample_positions())
        for (int d = 0; d < 3; ++d) {
            const AxisWeights a = axis_weights(xg[d]);
            EXPECT_GE(a.fx, 0.5);
            EXPECT_LT(a.fx, 1.5);
            EXPECT_NEAR(a.w[0] + a.w[1] + a.w[2], 1.0, tol::kRoundoff) << "xg = " << xg[d];
            EXPECT_NEAR(a.dw[0] + a.dw[1] + a.dw[2], 0.0, tol::kRoundoff) << "xg = " << xg[d];
            for (int k = 0; k < 3; ++k) EXPECT_GE(a.w[k], 0.0);
        }
}

TEST(BSpline, StencilReproducesLinearFieldsAndGradients) {
    const Real h = 0.05, inv_h = 1 / h;
    const Vec3 origin(0.3, -0.2, 0.1);
    for (const Vec3& xg : sample_positions()) {
        const Stencil st = make_stencil(xg);
        const Vec3 xp = origin + h * xg;
        Real wsum = 0;
        Vec3 xsum = Vec3::Zero(), gsum = Vec3::Zero();
        Mat3 grad_x = Mat3::Zero();  // sum_i x_i grad w_i^T must be the identity
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                for (int c = 0; c < 3; ++c) {
                    const Vec3 xi = origin + h * Vec3(st.axis[0].base + a, st.axis[1].base + b,
                                                      st.axis[2].base + c);
                    const Real w = st.weight(a, b, c);
                    const Vec3 g = st.gradient(a, b, c, inv_h);
                    wsum += w;
                    xsum += w * xi;
                    gsum += g;
                    grad_x += xi * g.transpose();
                }
        EXPECT_NEAR(wsum, 1.0, tol::kRoundoff);
        EXPECT_LT((xsum - xp).norm(), tol::kRoundoff * 10) << "x = " << xp.transpose();
        EXPECT_LT(gsum.norm(), tol::kRoundoff * inv_h);
        EXPECT_LT((grad_x - Mat3::Identity()).norm(), tol::kRoundoffLoose) << grad_x;
    }
}

TEST(BSpline, GradientMatchesFiniteDifference) {
    const Real h = 1, eps = 1e-6;
    const Vec3 xg(4.3, 5.8, 6.05);
    const Stencil st = make_stencil(xg);
    for (int d = 0; d < 3; ++d) {
        Vec3 xp = xg, xm = xg;
        xp[d] += eps;
        xm[d] -= eps;
        const Stencil sp = make_stencil(xp), sm = make_stencil(xm);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                for (int c = 0; c < 3; ++c) {
                    // the stencil base does not change for these small offsets
                    const Real fd = (sp.weight(a, b, c) - sm.weight(a, b, c)) / (2 * eps);
                    // grad w_ip is the derivative with respect to the particle position
                    EXPECT_NEAR(st.gradient(a, b, c, 1 / h)[d], fd, tol::kFiniteDiff);
                }
    }
}

}  // namespace
}  // namespace mudcrack::mpm
