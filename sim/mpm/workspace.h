#pragma once
/// The step's scratch: the sparse grid, the moisture node fields (empty without moisture),
/// per-thread scatter windows and the particle-permutation buffer. Never serialized: it carries
/// nothing from one step to the next (what does, such as the moisture flux history, is SimState's).
#include <cstdint>
#include <vector>

#include "sim/core/stats.h"
#include "sim/moisture/moisture_solver.h"
#include "sim/mpm/sparse_grid.h"

namespace mudcrack {

struct SimWorkspace {
    mpm::SparseGrid grid;
    MoistureGrid moisture;                      // allocated only when a moisture solve runs
    std::vector<std::vector<Real>> windows;     // per thread, 8 values per window node
    std::vector<Real> permute_buffer;           // one attribute's values while reordering slots

    int64_t memory_bytes() const {
        int64_t total = grid.memory_bytes() + moisture.memory_bytes() + capacity_bytes(permute_buffer);
        for (const auto& w : windows) total += capacity_bytes(w);
        return total;
    }
};

}  // namespace mudcrack
