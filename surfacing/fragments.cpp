#include "surfacing/fragments.h"

#include <utility>

namespace mudcrack {

Fragments find_fragments(const CoreTopology& topo, const std::vector<uint8_t>& is_broken, int min_particles) {
    const int32_t n = topo.n_particles;
    // union-find with the smaller id as root, so each root is its component's smallest particle
    std::vector<int32_t> parent(n);
    for (int32_t p = 0; p < n; ++p) parent[p] = p;
    auto find = [&](int32_t p) {
        while (parent[p] != p) {
            parent[p] = parent[parent[p]];  // path halving
            p = parent[p];
        }
        return p;
    };
    for (int32_t e = 0; e < topo.n_edges(); ++e) {
        if (is_broken[e]) continue;
        int32_t a = find(topo.edges[e][0]), b = find(topo.edges[e][1]);
        if (a == b) continue;
        if (a > b) std::swap(a, b);
        parent[b] = a;
    }
    // sizes per root, then ids in root order for the fragments that are kept
    std::vector<int32_t> size(n, 0);
    for (int32_t p = 0; p < n; ++p) ++size[parent[p] = find(p)];
    Fragments frag;
    std::vector<int32_t> id_of_root(n, -1);
    for (int32_t p = 0; p < n; ++p) {
        if (parent[p] != p) continue;
        if (size[p] >= min_particles)
            id_of_root[p] = frag.count++;
        else
            ++frag.culled;
    }
    frag.id.resize(n);
    for (int32_t p = 0; p < n; ++p) frag.id[p] = id_of_root[parent[p]];
    return frag;
}

}  // namespace mudcrack
