#include "sim/moisture/flux_history.h"

#include <algorithm>

#include "sim/core/check.h"
#include "sim/core/parallel.h"
#include "sim/core/stats.h"

namespace mudcrack {

using mpm::kBlockNodes;

namespace {

// remap[b] = the slot of to_keys[b] in from_keys, or -1 (both ascending)
void map_blocks(const std::vector<uint32_t>& from_keys, const std::vector<uint32_t>& to_keys,
                std::vector<int32_t>& remap) {
    remap.resize(to_keys.size());
    size_t j = 0;
    for (size_t b = 0; b < to_keys.size(); ++b) {
        while (j < from_keys.size() && from_keys[j] < to_keys[b]) ++j;
        remap[b] =
            j < from_keys.size() && from_keys[j] == to_keys[b] ? static_cast<int32_t>(j) : -1;
    }
}

}  // namespace

int64_t MoistureFluxHistory::memory_bytes() const {
    return capacity_bytes(keys) + capacity_bytes(flux) + capacity_bytes(flux_prev) +
           capacity_bytes(remap);
}

void predict_moisture_flux(MoistureFluxHistory& h, const mpm::SparseGrid& grid, Real dt,
                           Real* flux) {
    MC_CHECK(h.count > 0);
    map_blocks(h.keys, grid.block_keys, h.remap);
    // from the newest solve's midpoint to this step's, over the distance between the two midpoints
    const Real slope = h.count > 1 ? (dt + h.dt) / (h.dt + h.dt_prev) : Real(0);
    parallel_for(static_cast<int64_t>(grid.n_blocks()), [&](int64_t b) {
        Real* out = flux + b * kBlockNodes;
        const int32_t old = h.remap[b];
        if (old < 0) {
            std::fill(out, out + kBlockNodes, Real(0));
            return;
        }
        const Real* newest = h.flux.data() + static_cast<int64_t>(old) * kBlockNodes;
        const Real* before = h.flux_prev.data() + static_cast<int64_t>(old) * kBlockNodes;
        for (int k = 0; k < kBlockNodes; ++k) out[k] = newest[k] + slope * (newest[k] - before[k]);
    });
}

void record_moisture_flux(MoistureFluxHistory& h, const mpm::SparseGrid& grid, const Real* flux,
                          Real dt) {
    const int64_t nb = static_cast<int64_t>(grid.n_blocks());
    // the newest fluxes become the previous ones, moved onto this grid's blocks
    if (h.count > 0) map_blocks(h.keys, grid.block_keys, h.remap);
    h.flux_prev.resize(nb * kBlockNodes);
    parallel_for(nb, [&](int64_t b) {
        const int32_t old = h.count > 0 ? h.remap[b] : -1;
        const Real* src = old >= 0 ? h.flux.data() + static_cast<int64_t>(old) * kBlockNodes
                                   : flux + b * kBlockNodes;
        std::copy(src, src + kBlockNodes, h.flux_prev.data() + b * kBlockNodes);
    });
    h.flux.assign(flux, flux + nb * kBlockNodes);
    h.keys = grid.block_keys;
    h.dt_prev = h.count > 0 ? h.dt : dt;
    h.dt = dt;
    h.count = std::min(h.count + 1, 2);
}

}  // namespace mudcrack
