#pragma once
/// The step's scratch: the sparse grid, the moisture node fields (empty without moisture),
/// per-thread scatter windows, the particle-permutation buffer and the stress cache. Never
/// serialized: nothing in it changes a step's result (what does, such as the moisture flux
/// history, is SimState's); the stress cache only saves recomputing what G2P already knew.
#include <cstdint>
#include <vector>

#include "sim/core/stats.h"
#include "sim/grid/sparse_grid.h"
#include "sim/moisture/moisture_solver.h"

namespace mudcrack {

struct SimWorkspace {
    mpm::SparseGrid grid;
    MoistureGrid moisture;                   // allocated only when a moisture solve runs
    std::vector<std::vector<Real>> windows;  // per thread, 8 values per window node
    std::vector<Real> permute_buffer;        // one attribute's values while reordering slots
    // Kirchhoff stress of each slot's Fe as the last step's G2P left it, for the next P2G
    // (docs/physics.md §7): G2P has J, b and J^(-2/3) in hand for the inside test, so P2G need
    // not read Fe and recompute them. Current only while tau_step == SimState::step_count; a
    // step sets tau_step = -1 before it touches the state and to its own count once it has
    // succeeded, so after a failed step, a rollback or in a fresh copy the step recomputes it
    // from Fe first (mpm::kirchhoff_stresses, same bits).
    // Code that edits SimState::Fe between steps must reset the workspace.
    std::vector<SymMat3> tau;
    int64_t tau_step = -1;

    int64_t memory_bytes() const {
        int64_t total = grid.memory_bytes() + moisture.memory_bytes() +
                        capacity_bytes(permute_buffer) + capacity_bytes(tau);
        for (const auto& w : windows) total += capacity_bytes(w);
        return total;
    }
};

}  // namespace mudcrack
