#pragma once
/// The scalar and small fixed-size linear-algebra types used everywhere (pbrt's Float,
/// MuJoCo's mjtNum): change `Real` here and nowhere else.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace mudcrack {

using Real = double;
using Vec2 = Eigen::Matrix<Real, 2, 1>;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Vec3i = Eigen::Matrix<int, 3, 1>;
using Vec3f = Eigen::Matrix<float, 3, 1>;
using Vec2f = Eigen::Matrix<float, 2, 1>;

/// A symmetric 3x3 matrix (a stress) as its six distinct entries: half a Mat3's memory.
struct SymMat3 {
    Real xx, yy, zz, xy, xz, yz;

    /// The Frobenius norm squared (the off-diagonal entries count twice).
    Real squared_norm() const {
        return xx * xx + yy * yy + zz * zz + 2 * (xy * xy + xz * xz + yz * yz);
    }
    Mat3 matrix() const {
        Mat3 m;
        m << xx, xy, xz, xy, yy, yz, xz, yz, zz;
        return m;
    }
};

/// What an array element is made of, for code that moves arrays as plain numbers (reordering,
/// checkpoints): Scalar, kCount of them, packed. A number is one of itself; an Eigen fixed-size
/// matrix is its entries (column-major, no padding); SymMat3 is its six Reals.
template <class T, class = void>
struct PackedNumbers {
    using Scalar = T;
    static constexpr size_t kCount = 1;
};
template <class T>
struct PackedNumbers<T, std::void_t<typename T::Scalar>> {
    using Scalar = typename T::Scalar;
    static constexpr size_t kCount = sizeof(T) / sizeof(Scalar);
    static_assert(kCount * sizeof(Scalar) == sizeof(T), "Eigen fixed-size types are packed");
};
template <>
struct PackedNumbers<SymMat3> {
    using Scalar = Real;
    static constexpr size_t kCount = 6;
    static_assert(kCount * sizeof(Scalar) == sizeof(SymMat3), "SymMat3 is six packed Reals");
};

using Tet = std::array<int32_t, 4>;  // particle ids of a tetrahedron's corners
using Tri = std::array<int32_t, 3>;  // vertex ids of a triangle

constexpr int kDim = 3;
constexpr Real kPi = 3.14159265358979323846;  // pi, the one definition

}  // namespace mudcrack
