#include "sim/grid/sparse_grid.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "sim/core/error.h"
#include "sim/core/stats.h"
#include "sim/grid/bspline.h"

namespace mudcrack::mpm {

GridGeometry make_grid_geometry(const Vec3& domain_min, const Vec3& domain_max, Real h,
                                int padding) {
    GridGeometry g;
    g.origin = domain_min;
    g.h = h;
    g.inv_h = 1 / h;
    g.padding = padding;
    double total_blocks = 1;
    for (int d = 0; d < 3; ++d) {
        const Real extent = domain_max[d] - domain_min[d];
        if (!(extent > 4 * h)) {
            std::ostringstream os;
            os << "simulation domain axis " << d << " spans " << extent
               << " m: must be > 4 h = " << 4 * h << " m";
            throw InputError(os.str());
        }
        g.cells[d] = static_cast<int>(std::ceil(extent / h - 1e-9));
        // nodes 0..cells live in blocks 0..cells/4; one spare layer so pblock + 1 always exists
        g.blocks[d] = g.cells[d] / kBlockWidth + 2;
        total_blocks *= g.blocks[d];
    }
    if (total_blocks >= 4.0e9) {
        std::ostringstream os;
        os << "simulation domain of " << g.cells.transpose() << " cells at h = " << h << " m needs "
           << total_blocks << " grid blocks: must be < 4e9 (enlarge h or shrink the domain)";
        throw InputError(os.str());
    }
    return g;
}

const WindowMap& window_map() {
    static const WindowMap map = [] {
        WindowMap m{};
        for (int a = 0; a < kWindowWidth; ++a)
            for (int b = 0; b < kWindowWidth; ++b)
                for (int c = 0; c < kWindowWidth; ++c) {
                    const int n = window_index(a, b, c);
                    m.neighbor[n] = static_cast<uint8_t>(((a >> 2) * 2 + (b >> 2)) * 2 + (c >> 2));
                    m.local[n] = static_cast<uint8_t>(block_node_index(a & 3, b & 3, c & 3));
                }
        return m;
    }();
    return map;
}

int32_t SparseGrid::find_block(uint32_t key) const {
    const auto it = std::lower_bound(block_keys.begin(), block_keys.end(), key);
    if (it == block_keys.end() || *it != key) return -1;
    return static_cast<int32_t>(it - block_keys.begin());
}

int64_t SparseGrid::memory_bytes() const {
    int64_t total = capacity_bytes(particle_key) + capacity_bytes(order) +
                    capacity_bytes(pblock_key) + capacity_bytes(pblock_begin) +
                    capacity_bytes(pblock_neighbors) + capacity_bytes(block_keys) +
                    capacity_bytes(nodes) + capacity_bytes(sort_key_tmp) +
                    capacity_bytes(sort_idx_tmp) + capacity_bytes(radix_count) +
                    capacity_bytes(neighbor_keys_tmp);
    for (const auto& c : color_pblocks) total += capacity_bytes(c);
    for (const auto& c : color_prefix) total += capacity_bytes(c);
    return total;
}

namespace {

// One stable counting-sort pass of the n slots in `in` by bits [shift, shift + digit_bits) of
// their block key, into `out`, on the worker threads: each counts the digits of its contiguous
// share of `in`, the counts are summed in (digit, thread) order, and each scatters its share in
// input order, so the result is the serial pass's for any thread count. `out_key` gets the keys in
// `out`'s order.
void radix_pass(const uint32_t* key, int shift, int digit_bits, const int32_t* in, int32_t* out,
                uint32_t* out_key, int64_t n, std::vector<uint32_t>& count) {
    const uint32_t buckets = 1u << digit_bits, mask = buckets - 1;
    const int nt = std::max(1, thread_count());
    count.assign(static_cast<size_t>(nt) * buckets, 0u);
    parallel_chunks(n, [&](int t, int64_t b, int64_t e) {
        uint32_t* c = count.data() + static_cast<size_t>(t) * buckets;
        for (int64_t i = b; i < e; ++i) ++c[(key[in[i]] >> shift) & mask];
    });
    uint32_t sum = 0;
    for (uint32_t d = 0; d < buckets; ++d)
        for (int t = 0; t < nt; ++t) {
            uint32_t& c = count[static_cast<size_t>(t) * buckets + d];
            const uint32_t here = c;
            c = sum;
            sum += here;
        }
    parallel_chunks(n, [&](int t, int64_t b, int64_t e) {
        uint32_t* c = count.data() + static_cast<size_t>(t) * buckets;
        for (int64_t i = b; i < e; ++i) {
            const int32_t s = in[i];
            const uint32_t k = key[s];
            const uint32_t at = c[(k >> shift) & mask]++;
            out[at] = s;
            out_key[at] = k;
        }
    });
}

int bits_for(uint64_t count) {
    int bits = 1;
    while ((uint64_t(1) << bits) < count) ++bits;
    return bits;
}

}  // namespace

template <class StateReal>
void bin_particles(SparseGrid& grid, const std::vector<Eigen::Matrix<StateReal, 3, 1>>& x,
                   const std::vector<int32_t>& id) {
    const GridGeometry& geo = grid.geo;
    const int64_t n = static_cast<int64_t>(x.size());

    // block key of every particle's stencil base node
    grid.particle_key.resize(n);
    grid.order.resize(n);
    parallel_for(n, [&](int64_t p) {
        const Vec3 xg = geo.to_grid(x[p].template cast<Real>());
        int b[3];
        for (int d = 0; d < 3; ++d) b[d] = stencil_base(xg[d]) >> 2;
        grid.particle_key[p] = geo.block_key(b[0], b[1], b[2]);
    });

    // order slots by (block, particle id): canonical, so the scatter order (and every bit of the
    // result) does not depend on how the arrays happen to be ordered, e.g. after a resume.
    // Skipped when the slots are already in that order (right after the arrays were permuted).
    std::vector<uint32_t>& sorted_key = grid.sort_key_tmp;
    sorted_key.resize(n);
    bool sorted = true;
    for (int64_t p = 1; p < n && sorted; ++p)
        sorted = grid.particle_key[p - 1] < grid.particle_key[p] ||
                 (grid.particle_key[p - 1] == grid.particle_key[p] && id[p - 1] < id[p]);
    if (sorted) {
        parallel_for(n, [&](int64_t p) {
            grid.order[p] = static_cast<int32_t>(p);
            sorted_key[p] = grid.particle_key[p];
        });
    } else {
        // the slots in id order (the ids are a permutation of 0..n-1: one scatter, where sorting
        // by id took a radix pass per 11 bits), then stable passes by block
        std::vector<int32_t>& by_id = grid.sort_idx_tmp;
        by_id.assign(n, -1);
        for (int64_t p = 0; p < n; ++p) {
            const int32_t i = id[p];
            if (i < 0 || i >= n || by_id[i] >= 0)
                throw RuntimeError("particle binning: slot " + std::to_string(p) + " has id " +
                                   std::to_string(i) + ", which is out of [0, " +
                                   std::to_string(n) + ") or another slot's: a damaged state");
            by_id[i] = static_cast<int32_t>(p);
        }
        // as few passes as digits of at most 16 bits allow (a 2^16 count array per thread stays
        // in L2: one pass for up to 65,536 blocks)
        const int block_bits =
            bits_for(static_cast<uint64_t>(geo.blocks.x()) * geo.blocks.y() * geo.blocks.z());
        const int passes = (block_bits + 15) / 16;
        const int digit_bits = (block_bits + passes - 1) / passes;
        for (int k = 0; k < passes; ++k) {
            radix_pass(grid.particle_key.data(), k * digit_bits, digit_bits, by_id.data(),
                       grid.order.data(), sorted_key.data(), n, grid.radix_count);
            if (k + 1 < passes) by_id.swap(grid.order);
        }
    }

    // particle blocks: runs of equal keys
    grid.pblock_key.clear();
    grid.pblock_begin.clear();
    for (int64_t i = 0; i < n; ++i) {
        if (i == 0 || sorted_key[i] != sorted_key[i - 1]) {
            grid.pblock_key.push_back(sorted_key[i]);
            grid.pblock_begin.push_back(static_cast<int32_t>(i));
        }
    }
    grid.pblock_begin.push_back(static_cast<int32_t>(n));
    const size_t npb = grid.pblock_key.size();

    // allocated blocks: every particle block and its +1 neighbours. Keys are linear in the block
    // coordinates, so the neighbours at one offset are the particle blocks' keys plus a constant:
    // eight ascending runs, merged.
    uint32_t offset[8];  // block_key(b + d) - block_key(b), the key of d itself
    for (int dx = 0; dx < 2; ++dx)
        for (int dy = 0; dy < 2; ++dy)
            for (int dz = 0; dz < 2; ++dz)
                offset[(dx * 2 + dy) * 2 + dz] = geo.block_key(dx, dy, dz);
    std::vector<uint32_t>& keys = grid.neighbor_keys_tmp;
    keys.resize(npb * 8);
    for (int o = 0; o < 8; ++o)
        for (size_t i = 0; i < npb; ++i) keys[o * npb + i] = grid.pblock_key[i] + offset[o];
    for (size_t run = npb; run < keys.size(); run *= 2)
        for (size_t b = 0; b + run < keys.size(); b += 2 * run)
            std::inplace_merge(keys.begin() + b, keys.begin() + b + run,
                               keys.begin() + std::min(b + 2 * run, keys.size()));
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    grid.block_keys.assign(keys.begin(), keys.end());

    // neighbour slots: at each offset, one walk up the allocated keys beside the particle blocks'
    grid.pblock_neighbors.resize(npb);
    parallel_for(8, [&](int64_t o) {
        size_t j = 0;
        for (size_t i = 0; i < npb; ++i) {
            const uint32_t k = grid.pblock_key[i] + offset[o];
            while (grid.block_keys[j] < k) ++j;
            grid.pblock_neighbors[i][o] = static_cast<int32_t>(j);
        }
    });
    // colours of the particle blocks
    for (auto& c : grid.color_pblocks) c.clear();
    for (size_t i = 0; i < npb; ++i) {
        const Vec3i b = geo.block_coord(grid.pblock_key[i]);
        const int color = (b.x() & 1) | ((b.y() & 1) << 1) | ((b.z() & 1) << 2);
        grid.color_pblocks[color].push_back(static_cast<int32_t>(i));
    }
    for (int c = 0; c < 8; ++c) {
        std::vector<int32_t>& prefix = grid.color_prefix[c];
        prefix.assign(1, 0);
        for (int32_t pb : grid.color_pblocks[c])
            prefix.push_back(prefix.back() + grid.pblock_begin[pb + 1] - grid.pblock_begin[pb]);
    }

    // zeroed node fields
    const int64_t n_values = static_cast<int64_t>(grid.n_blocks()) * kBlockNodes * kNodeFields;
    grid.nodes.resize(n_values);
    parallel_chunks(n_values, [&](int, int64_t b, int64_t e) {
        std::fill(grid.nodes.begin() + b, grid.nodes.begin() + e, Real(0));
    });
}

template void bin_particles(SparseGrid&, const std::vector<Eigen::Matrix<double, 3, 1>>&,
                            const std::vector<int32_t>&);
template void bin_particles(SparseGrid&, const std::vector<Eigen::Matrix<float, 3, 1>>&,
                            const std::vector<int32_t>&);

}  // namespace mudcrack::mpm
