#pragma once
/// Seeded random and named degenerate deformation gradients shared by the material tests and
/// benchmarks.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sim/core/types.h"

namespace mudcrack::test {

/// A uniformly distributed rotation (normalized Gaussian quaternion).
inline Mat3 random_rotation(std::mt19937_64& rng) {
    std::normal_distribution<Real> n(0, 1);
    Eigen::Quaternion<Real> q(n(rng), n(rng), n(rng), n(rng));
    q.normalize();
    return q.toRotationMatrix();
}

/// R1 diag(sigma) R2^T with random rotations R1, R2.
inline Mat3 with_singular_values(std::mt19937_64& rng, const Vec3& sigma) {
    return random_rotation(rng) * sigma.asDiagonal() * random_rotation(rng).transpose();
}

/// A matrix with independent entries uniform in [-1, 1].
inline Mat3 random_matrix(std::mt19937_64& rng) {
    std::uniform_real_distribution<Real> u(-1, 1);
    Mat3 F;
    for (int i = 0; i < 9; ++i) F(i) = u(rng);
    return F;
}

/// An elastic deformation gradient as MPM produces them: a rotation times a stretch with
/// singular values exp(N(0, spread)).
inline Mat3 random_deformation(std::mt19937_64& rng, Real spread) {
    std::normal_distribution<Real> n(0, spread);
    return with_singular_values(rng, Vec3(std::exp(n(rng)), std::exp(n(rng)), std::exp(n(rng))));
}

struct NamedMatrix {
    std::string name;
    Mat3 F;
};

/// Degenerate and extreme matrices every 3x3 kernel must survive.
inline std::vector<NamedMatrix> degenerate_matrices() {
    std::mt19937_64 rng(7);
    const Mat3 R = random_rotation(rng), Q = random_rotation(rng);
    Mat3 permutation;
    permutation << 0, 1, 0, 0, 0, 1, 1, 0, 0;
    Mat3 reflection = Mat3::Identity();
    reflection(1, 1) = -1;
    std::vector<NamedMatrix> m = {
        {"identity", Mat3::Identity()},
        {"minus_identity", -Mat3::Identity()},
        {"zero", Mat3::Zero()},
        {"rotation", R},
        {"rotation_x_pi", Eigen::AngleAxis<Real>(M_PI, Vec3::UnitX()).toRotationMatrix()},
        {"small_rotation",
         Eigen::AngleAxis<Real>(1e-9, Vec3(1, 2, 3).normalized()).toRotationMatrix()},
        {"permutation", permutation},
        {"reflection", reflection},
        {"reflected_rotation", R * reflection},
        {"scaled_rotation", 3.5 * R},
        {"diagonal_distinct", Vec3(3, 2, 1).asDiagonal()},
        {"diagonal_unsorted", Vec3(0.5, 4, -2).asDiagonal()},
        {"repeated_12", R * Vec3(2, 2, 1).asDiagonal() * Q.transpose()},
        {"repeated_23", R * Vec3(2, 1, 1).asDiagonal() * Q.transpose()},
        {"nearly_repeated", R * Vec3(1 + 1e-9, 1, 1 - 1e-9).asDiagonal() * Q.transpose()},
        {"nearly_identity", Mat3::Identity() + 1e-10 * Mat3::Ones()},
        {"rank_2", R * Vec3(2, 1, 0).asDiagonal() * Q.transpose()},
        {"rank_1", R * Vec3(2, 0, 0).asDiagonal() * Q.transpose()},
        {"rank_1_outer", Vec3(1, 2, 3) * Vec3(-1, 0.5, 2).transpose()},
        {"near_singular", R * Vec3(1, 1, 1e-12).asDiagonal() * Q.transpose()},
        {"near_rank_1", R * Vec3(1, 1e-8, 1e-13).asDiagonal() * Q.transpose()},
        {"inverted", R * Vec3(1.5, 1, -0.5).asDiagonal() * Q.transpose()},
        {"inverted_small", R * Vec3(1, 1, -1e-6).asDiagonal() * Q.transpose()},
        {"compressed_J_1e-3", R * Vec3(0.1, 0.1, 0.1).asDiagonal() * Q.transpose()},
        {"stretched_5", R * Vec3(5, 4.5, 0.3).asDiagonal() * Q.transpose()},
        {"huge", 1e200 * (R * Vec3(3, 2, 1).asDiagonal() * Q.transpose())},
        {"tiny", 1e-200 * (R * Vec3(3, 2, 1).asDiagonal() * Q.transpose())},
        {"huge_identity", 1e300 * Mat3::Identity()},
        {"subnormal_entries", 1e-310 * R},
        {"mixed_scales", R * Vec3(1e150, 1, 1e-150).asDiagonal() * Q.transpose()},
        {"one_entry", (Mat3() << 0, 0, 0, 0, 0, 0, 0, 5, 0).finished()},
    };
    return m;
}

}  // namespace mudcrack::test
