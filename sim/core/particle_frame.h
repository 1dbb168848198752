#pragma once
/// One cached frame of the simulation as the later stages see it (surfacing, render): a tiny
/// view of the particles, in particle-id order, never the MPM internals. Attributes that the
/// shot did not cache are empty.
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

using Mat3f = Eigen::Matrix<float, 3, 3>;

struct ParticleFrame {
    int frame = 0;                 // 1-based frame number
    double time = 0;               // simulated time at the end of the frame [s]
    int substeps = 0;              // MPM steps taken during this frame
    std::vector<Vec3f> P;          // positions [m], (n_particles), index = particle id
    std::vector<Vec3f> v;          // velocities [m/s]
    std::vector<float> theta;      // volumetric water content in [0, eta]
    std::vector<float> saturation; // s = theta/eta in [0,1]
    std::vector<float> alpha;      // NACC hardening state (log Jp plus eps log Jw)
    std::vector<float> Jw;         // pore deformation determinant, 1 - eta (1 - s)
    std::vector<Mat3f> Fe;         // elastic deformation gradient
    size_t size() const { return P.size(); }
};

}  // namespace mudcrack
