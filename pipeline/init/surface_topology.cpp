// The CGAL-free half of surface_check.h: counting what is combinatorially wrong with a soup.
#include <algorithm>
#include <numeric>
#include <sstream>

#include "pipeline/init/surface_check.h"
#include "sim/core/tet_mesh.h"
#include "sim/core/union_find.h"

namespace mudcrack {
namespace {

std::string point_text(const Vec3& p) {
    std::ostringstream s;
    s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return s.str();
}

/// One use of an undirected edge by a face.
struct EdgeUse {
    int32_t lo, hi;   // the edge's vertex ids, lo < hi
    bool is_forward;  // the face traverses it lo -> hi
};

/// Faces with a repeated vertex (zero area by construction).
void add_repeated_vertex_problems(const InputSurface& surface, const std::string& name,
                                  std::vector<std::string>& problems) {
    const auto& X = surface.positions;
    int64_t repeated = 0;
    int64_t first_repeated = -1;
    for (size_t f = 0; f < surface.faces.size(); ++f) {
        const Tri& t = surface.faces[f];
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            if (repeated++ == 0) first_repeated = static_cast<int64_t>(f);
        }
    }
    if (repeated > 0)
        problems.push_back(name + ": " + std::to_string(repeated) +
                           " faces use the same vertex twice (degenerate), first is face " +
                           std::to_string(first_repeated) + " at " +
                           point_text(X[surface.faces[first_repeated][0]]));
}

/// Border, non-manifold and inconsistently wound edges.
void add_edge_problems(const InputSurface& surface, const std::string& name,
                       std::vector<std::string>& problems) {
    const auto& X = surface.positions;
    // edge uses, sorted so each undirected edge's uses are adjacent
    std::vector<EdgeUse> uses;
    uses.reserve(3 * surface.faces.size());
    for (const Tri& t : surface.faces)
        for (int k = 0; k < 3; ++k) {
            const int32_t a = t[k], b = t[(k + 1) % 3];
            if (a != b) uses.push_back({std::min(a, b), std::max(a, b), a < b});
        }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& u, const EdgeUse& v) {
        return u.lo != v.lo ? u.lo < v.lo : u.hi < v.hi;
    });
    int64_t border = 0, non_manifold = 0, misoriented = 0;
    Vec3 first_border, first_non_manifold, first_misoriented;
    for (size_t i = 0; i < uses.size();) {
        size_t j = i + 1;
        while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
        const Vec3 mid = 0.5 * (X[uses[i].lo] + X[uses[i].hi]);
        if (j - i == 1) {
            if (border++ == 0) first_border = mid;
        } else if (j - i > 2) {
            if (non_manifold++ == 0) first_non_manifold = mid;
        } else if (uses[i].is_forward == uses[i + 1].is_forward) {
            if (misoriented++ == 0) first_misoriented = mid;
        }
        i = j;
    }
    if (border > 0)
        problems.push_back(name + ": " + std::to_string(border) +
                           " border edges (the mesh is not closed), first at " +
                           point_text(first_border));
    if (non_manifold > 0)
        problems.push_back(name + ": " + std::to_string(non_manifold) +
                           " non-manifold edges (shared by more than two faces), first at " +
                           point_text(first_non_manifold));
    if (misoriented > 0)
        problems.push_back(name + ": " + std::to_string(misoriented) +
                           " edges whose two faces have opposite orientations (the faces are not "
                           "consistently wound), first at " +
                           point_text(first_misoriented));
}

/// Non-manifold vertices: the faces around a vertex must form a single fan, i.e. the opposite
/// edges of its faces (its link) must be connected.
void add_vertex_fan_problems(const InputSurface& surface, const std::string& name,
                             std::vector<std::string>& problems) {
    const auto& X = surface.positions;
    std::vector<int32_t> offset(X.size() + 1, 0), incident;
    for (const Tri& t : surface.faces)
        for (int32_t v : t) ++offset[v + 1];
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    incident.resize(offset.back());
    {
        std::vector<int32_t> fill(offset.begin(), offset.end() - 1);
        for (size_t f = 0; f < surface.faces.size(); ++f)
            for (int32_t v : surface.faces[f]) incident[fill[v]++] = static_cast<int32_t>(f);
    }
    int64_t bad_vertices = 0;
    int32_t first_bad = -1;
    std::vector<int32_t> link;
    UnionFind uf;
    for (size_t v = 0; v < X.size(); ++v) {
        if (offset[v] == offset[v + 1]) continue;  // unused vertex: harmless
        link.clear();
        for (int32_t e = offset[v]; e < offset[v + 1]; ++e)
            for (int32_t w : surface.faces[incident[e]])
                if (w != static_cast<int32_t>(v)) link.push_back(w);
        std::vector<int32_t> ids = link;
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        uf.reset(static_cast<int32_t>(ids.size()));
        auto index_of = [&](int32_t w) {
            return static_cast<int>(std::lower_bound(ids.begin(), ids.end(), w) - ids.begin());
        };
        for (size_t k = 0; k + 1 < link.size(); k += 2)
            uf.unite(index_of(link[k]), index_of(link[k + 1]));
        int components = 0;
        for (size_t k = 0; k < ids.size(); ++k)
            components += uf.find(static_cast<int>(k)) == static_cast<int>(k);
        if (components > 1 && bad_vertices++ == 0) first_bad = static_cast<int32_t>(v);
    }
    if (bad_vertices > 0)
        problems.push_back(name + ": " + std::to_string(bad_vertices) +
                           " non-manifold vertices (where separate sheets touch), first at " +
                           point_text(X[first_bad]));
}

}  // namespace

std::vector<std::string> surface_topology_problems(const InputSurface& surface,
                                                   const std::string& name) {
    std::vector<std::string> problems;
    add_repeated_vertex_problems(surface, name, problems);
    add_edge_problems(surface, name, problems);
    // a vertex fan is only well defined on closed, manifold, consistently wound edges
    if (problems.empty()) add_vertex_fan_problems(surface, name, problems);
    return problems;
}

Real enclosed_volume(const InputSurface& surface) {
    // sum of the signed tets spanned by each face and the origin, shifted to the first vertex
    // to keep round-off small for meshes far from the origin
    if (surface.positions.empty()) return 0;
    const Vec3 o = surface.positions[0];
    Real v = 0;
    for (const Tri& t : surface.faces)
        v += signed_tet_volume(o, surface.positions[t[0]], surface.positions[t[1]],
                               surface.positions[t[2]]);
    return v;
}

}  // namespace mudcrack
