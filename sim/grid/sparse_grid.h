#pragma once
/// The sparse MPM grid: 4x4x4-node blocks allocated only around particles, rebuilt every step
/// (memory and time grow with the occupied cells, not with the domain box).
///
/// Particles are binned by the block of their stencil base node ("particle blocks"). A particle
/// block's 3x3x3 stencils all fall inside a 6x6x6 node window that spans the block and its +1
/// neighbours, i.e. 8 allocated blocks. Kernels scatter into a small dense window per particle
/// block and then flush it into those 8 blocks. Particle blocks of one colour (parity of the
/// block coordinates) have disjoint windows, so flushing colour by colour is race-free and the
/// sum at every node is taken in the same order for any thread count (bitwise determinism).
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack::mpm {

constexpr int kBlockWidth = 4;     // nodes per block edge
constexpr int kBlockNodes = 64;    // nodes per block
constexpr int kWindowWidth = 6;    // nodes per window edge
constexpr int kWindowNodes = 216;  // nodes per window
constexpr int kNodeFields = 4;     // mass, then momentum / velocity (x, y, z)

/// The conceptually dense grid over the domain box: node i sits at origin + h i, with
/// i in [0, cells] per axis.
struct GridGeometry {
    Vec3 origin = Vec3::Zero();    // domain minimum corner [m]
    Real h = 1;                    // node spacing [m]
    Real inv_h = 1;                // 1/h [1/m]
    Vec3i cells = Vec3i::Zero();   // cells per axis (nodes per axis minus one)
    Vec3i blocks = Vec3i::Zero();  // block-grid dimensions (with a spare +1 layer)
    int padding = 3;               // wall band width [cells]

    uint32_t block_key(int bx, int by, int bz) const {
        return static_cast<uint32_t>(bx + blocks.x() * (by + blocks.y() * bz));
    }
    Vec3i block_coord(uint32_t key) const {
        const int bx = static_cast<int>(key % static_cast<uint32_t>(blocks.x()));
        const uint32_t rest = key / static_cast<uint32_t>(blocks.x());
        return Vec3i(bx, static_cast<int>(rest % static_cast<uint32_t>(blocks.y())),
                     static_cast<int>(rest / static_cast<uint32_t>(blocks.y())));
    }
    /// Grid coordinates (x - origin)/h of a world position.
    Vec3 to_grid(const Vec3& x) const { return (x - origin) * inv_h; }
};

/// Grid over [domain_min, domain_max] with spacing h. Throws InputError if the box has more
/// blocks than a 32-bit key can index.
GridGeometry make_grid_geometry(const Vec3& domain_min, const Vec3& domain_max, Real h,
                                int padding);

/// Maps each of the 216 window nodes to (which of the 8 neighbour blocks, node within it).
struct WindowMap {
    uint8_t neighbor[kWindowNodes];  // (dx*2 + dy)*2 + dz of the block holding the node
    uint8_t local[kWindowNodes];     // node index inside that block
};
const WindowMap& window_map();

/// Index of window node (a, b, c), each in [0, 6).
inline int window_index(int a, int b, int c) { return (a * kWindowWidth + b) * kWindowWidth + c; }
/// Index of block node (a, b, c), each in [0, 4).
inline int block_node_index(int a, int b, int c) { return (a * kBlockWidth + b) * kBlockWidth + c; }

struct SparseGrid {
    GridGeometry geo;

    // particle binning, rebuilt every step by bin_particles
    std::vector<uint32_t> particle_key;  // block key of each slot's stencil base, (n_particles)
    // slots grouped by particle block, stable, (n_particles)
    std::vector<int32_t> order;
    std::vector<uint32_t> pblock_key;  // key of each particle block, ascending
    // range of each particle block in `order`, (n_pblocks+1)
    std::vector<int32_t> pblock_begin;
    std::vector<std::array<int32_t, 8>> pblock_neighbors;  // block slots of pblock + {0,1}^3
    std::array<std::vector<int32_t>, 8> color_pblocks;     // particle blocks by colour
    // particles in the first k blocks of a colour
    std::array<std::vector<int32_t>, 8> color_prefix;

    // allocated blocks and their nodes
    std::vector<uint32_t> block_keys;  // ascending, (n_blocks)
    std::vector<Real> nodes;           // (n_blocks * 64, kNodeFields): m, (m v) or v

    // sort scratch, reused between steps
    std::vector<uint32_t> sort_key_tmp;
    std::vector<int32_t> sort_idx_tmp;
    std::vector<uint32_t> radix_count;
    std::vector<uint32_t> neighbor_keys_tmp;

    size_t n_blocks() const { return block_keys.size(); }
    size_t n_pblocks() const { return pblock_key.size(); }
    /// Slot of an allocated block, or -1.
    int32_t find_block(uint32_t key) const;
    /// Bytes held by this grid and its scratch.
    int64_t memory_bytes() const;
};

/// Bins particles by the block of their stencil base, ordered by (block, particle id) (a radix
/// sort of the slots), builds the particle-block lists and colours, allocates the blocks the
/// stencils touch, and zeroes the node fields. Positions must lie in [h, (cells-1) h] from the
/// origin (the step clamps them there). Ids must be distinct and in [0, n).
/// Positions in either precision a state keeps them in (SimStateOf).
template <class StateReal>
void bin_particles(SparseGrid& grid, const std::vector<Eigen::Matrix<StateReal, 3, 1>>& x,
                   const std::vector<int32_t>& id);

/// Runs fn(thread, pblock) over all particle blocks, colour by colour; blocks of one colour run
/// in parallel. Use for scatters (window flushes must not race).
template <class Fn>
void for_each_pblock_colored(const SparseGrid& grid, Fn&& fn);

/// Runs fn(thread, pblock) over all particle blocks in parallel (gathers, per-particle updates).
template <class Fn>
void for_each_pblock(const SparseGrid& grid, Fn&& fn);

}  // namespace mudcrack::mpm

#include "sim/core/parallel.h"

namespace mudcrack::mpm {

/// Adds window values into a node field: window node n holds kCount values at win[n*kStride],
/// the field kCount values per node. Call colour by colour (for_each_pblock_colored).
template <int kCount, int kStride>
inline void flush_window(const SparseGrid& grid, int32_t pblock, const Real* win, Real* field) {
    const WindowMap& map = window_map();
    const std::array<int32_t, 8>& nb = grid.pblock_neighbors[pblock];
    for (int n = 0; n < kWindowNodes; ++n) {
        Real* dst =
            field +
            (static_cast<int64_t>(nb[map.neighbor[n]]) * kBlockNodes + map.local[n]) * kCount;
        const Real* src = win + n * kStride;
        for (int c = 0; c < kCount; ++c) dst[c] += src[c];
    }
}

/// Copies a node field (kCount values per node, starting at component `first` of kFieldStride)
/// into a window with kStride values per node.
template <int kCount, int kFieldStride, int kStride>
inline void gather_window(const SparseGrid& grid, int32_t pblock, const Real* field, int first,
                          Real* win) {
    const WindowMap& map = window_map();
    const std::array<int32_t, 8>& nb = grid.pblock_neighbors[pblock];
    for (int n = 0; n < kWindowNodes; ++n) {
        const Real* src = field +
                          (static_cast<int64_t>(nb[map.neighbor[n]]) * kBlockNodes + map.local[n]) *
                              kFieldStride +
                          first;
        Real* dst = win + n * kStride;
        for (int c = 0; c < kCount; ++c) dst[c] = src[c];
    }
}

// splits `count` blocks among the threads by particle count: thread t takes the blocks whose
// first particle (prefix[k]) lies in its share of [0, prefix[count]); deterministic
template <class Fn>
void for_each_balanced(const std::vector<int32_t>& prefix, size_t count, Fn&& fn) {
    const int64_t total = prefix[count];
    parallel_chunks(total, [&](int t, int64_t b, int64_t e) {
        size_t k = static_cast<size_t>(std::lower_bound(prefix.begin(), prefix.begin() + count, b) -
                                       prefix.begin());
        for (; k < count && prefix[k] < e; ++k) fn(t, k);
    });
}

template <class Fn>
void for_each_pblock_colored(const SparseGrid& grid, Fn&& fn) {
    for (int color = 0; color < 8; ++color) {
        const std::vector<int32_t>& list = grid.color_pblocks[color];
        if (list.empty()) continue;
        for_each_balanced(grid.color_prefix[color], list.size(),
                          [&](int t, size_t k) { fn(t, list[k]); });
    }
}

template <class Fn>
void for_each_pblock(const SparseGrid& grid, Fn&& fn) {
    for_each_balanced(grid.pblock_begin, grid.n_pblocks(),
                      [&](int t, size_t k) { fn(t, static_cast<int32_t>(k)); });
}

}  // namespace mudcrack::mpm
