#pragma once
/// Named tolerances for assertions (MuJoCo's MjTol): say which kind of error a test allows.
namespace mudcrack::tol {
constexpr double kRoundoff = 1e-12;        // pure round-off in double precision, relative
constexpr double kRoundoffLoose = 1e-9;    // round-off accumulated over many particles/steps
constexpr double kRoundoffKernel = 1e-14;  // one small kernel (3x3 SVD): a few dozen ulps, relative
constexpr double kFiniteDiff = 1e-5;       // central differences with h ~ 1e-6
constexpr double kFloat = 1e-5;            // values that passed through a float cache
// images, in 8-bit levels (0..255)
constexpr double kColor8 = 2.0;        // one level of quantization plus float rounding
constexpr double kImageMeanAbs = 1.5;  // golden images: mean |actual - golden| over all channels
constexpr double kImageP99 = 24.0;     // golden images: 99th percentile of per-pixel max error
}  // namespace mudcrack::tol
