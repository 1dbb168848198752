#include "surfacing/weld_classes.h"

#include <algorithm>

#include "surfacing/core_topology.h"

namespace mudcrack {
namespace {

/// Union-find over n owners joined by the unbroken pairs, reduced to smallest-member reps.
template <size_t NPairs>
WeldReps reps_for(int n, const std::array<std::array<int, 2>, NPairs>& pairs,
                  unsigned broken_mask) {
    WeldReps rep = {0, 1, 2, 3};
    auto find = [&](int i) {
        while (rep[i] != i) i = rep[i];
        return i;
    };
    for (size_t k = 0; k < NPairs; ++k) {
        if (broken_mask & (1u << k)) continue;
        const int a = find(pairs[k][0]), b = find(pairs[k][1]);
        if (a != b) rep[std::max(a, b)] = static_cast<int8_t>(std::min(a, b));
    }
    for (int i = 0; i < n; ++i) rep[i] = static_cast<int8_t>(find(i));
    return rep;
}

struct Tables {
    std::array<WeldReps, 64> tet;
    std::array<WeldReps, 8> face;
    Tables() {
        for (unsigned m = 0; m < 64; ++m) tet[m] = reps_for(4, kTetEdgeCorners, m);
        for (unsigned m = 0; m < 8; ++m) face[m] = reps_for(3, kFaceEdgeOwners, m);
    }
};

const Tables kTables;

}  // namespace

const WeldReps& tet_weld_reps(unsigned broken_mask) { return kTables.tet[broken_mask & 63u]; }
const WeldReps& face_weld_reps(unsigned broken_mask) { return kTables.face[broken_mask & 7u]; }

}  // namespace mudcrack
