#include "surfacing/fragments.h"

#include "sim/core/union_find.h"

namespace mudcrack {

Fragments find_fragments(const CoreTopology& topo, const std::vector<uint8_t>& is_broken,
                         int min_particles) {
    const int32_t n = topo.n_particles;
    // each root is its component's smallest particle, so fragment ids follow the particles' order
    UnionFind components(n);
    for (int32_t e = 0; e < topo.n_edges(); ++e)
        if (!is_broken[e]) components.unite(topo.edges[e][0], topo.edges[e][1]);
    // sizes per root, then ids in root order for the fragments that are kept
    std::vector<int32_t> size(n, 0);
    for (int32_t p = 0; p < n; ++p) ++size[components.find(p)];
    Fragments frag;
    std::vector<int32_t> id_of_root(n, -1);
    for (int32_t p = 0; p < n; ++p) {
        if (components.find(p) != p) continue;
        if (size[p] >= min_particles)
            id_of_root[p] = frag.count++;
        else
            ++frag.culled;
    }
    frag.id.resize(n);
    for (int32_t p = 0; p < n; ++p) frag.id[p] = id_of_root[components.find(p)];
    return frag;
}

}  // namespace mudcrack
