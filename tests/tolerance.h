#pragma once
/// Named tolerances for assertions (MuJoCo's MjTol): say which kind of error a test allows.
namespace mudcrack::tol {
constexpr double kRoundoff = 1e-12;   // pure round-off in double precision, relative
constexpr double kRoundoffLoose = 1e-9;  // round-off accumulated over many particles/steps
constexpr double kFiniteDiff = 1e-5;  // central differences with h ~ 1e-6
constexpr double kFloat = 1e-5;       // values that passed through a float cache
}  // namespace mudcrack::tol
