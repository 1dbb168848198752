#pragma once
/// The rotation of a particle core (docs/physics.md §5.3 step 2; Tu et al. 2023 Eq. 13).
#include "sim/core/types.h"

namespace mudcrack {

/// R = U V^T from the SVD Fe = U diag(sigma) V^T with det(U) = det(V) = +1 (the last columns
/// and the last singular value flipped together), so R is a proper rotation even for an
/// inverted Fe. For det(Fe) > 0 this is the rotation of the polar decomposition.
/// @param Fe elastic deformation gradient [-]
Mat3 core_rotation(const Mat3& Fe);

}  // namespace mudcrack
