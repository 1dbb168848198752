#pragma once
/// One cached frame of the simulation as the later stages see it (surfacing, render): a tiny
/// view of the particles, in particle-id order, never the MPM internals. Attributes that the
/// shot did not cache are empty.
#include <vector>

#include "sim/core/particle_attributes.h"
#include "sim/core/types.h"

namespace mudcrack {

struct ParticleFrame {
    int frame = 0;         // 1-based frame number
    double time = 0;       // simulated time at the end of the frame [s]
    int substeps = 0;      // MPM steps taken during this frame
    std::vector<Vec3f> P;  // positions [m], (n_particles), index = particle id
    // one array per cached attribute (MC_CACHED_ATTRIBUTES), (n_particles), index = particle id
#define MC_FRAME_ARRAY(T, member, key, vdb, physics, policy, doc) std::vector<T> member;
    MC_CACHED_ATTRIBUTES(MC_FRAME_ARRAY)
#undef MC_FRAME_ARRAY
    size_t size() const { return P.size(); }
};

}  // namespace mudcrack
