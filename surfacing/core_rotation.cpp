#include "surfacing/core_rotation.h"

#include <Eigen/Dense>
#include <Eigen/SVD>

namespace mudcrack {

Mat3 core_rotation(const Mat3& Fe) {
    const Eigen::JacobiSVD<Mat3> svd(Fe, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 U = svd.matrixU(), V = svd.matrixV();
    // sign fix: flipping a last column of U or V flips the sign of sigma_3 instead
    if (U.determinant() < 0) U.col(2) *= -1;
    if (V.determinant() < 0) V.col(2) *= -1;
    return U * V.transpose();
}

}  // namespace mudcrack
