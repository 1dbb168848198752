#pragma once
/// Fragments (docs/physics.md §5.3 step 7): the connected components of particles through unbroken
/// edges. Each fragment's boundary and crack pieces form a closed surface.
#include <cstdint>
#include <vector>

#include "surfacing/core_topology.h"

namespace mudcrack {

struct Fragments {
    std::vector<int32_t> id;  // fragment of each particle, -1 when culled, (n_particles)
    int32_t count = 0;        // kept fragments; ids 0..count-1 in order of smallest particle id
    int32_t culled = 0;       // fragments with fewer than min_particles particles
};

/// Labels particles by fragment through the edges with is_broken[e] == 0, deterministically
/// (ids ordered by each fragment's smallest particle id), culling fragments smaller than
/// min_particles particles.
Fragments find_fragments(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                         int min_particles);

}  // namespace mudcrack
