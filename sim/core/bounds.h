#pragma once
/// Axis-aligned bounds of points and meshes: what the surfacing records per frame and what the
/// renderer frames a shot by, so both compute them the same way.
#include <limits>

#include "sim/core/tri_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Axis-aligned bounds [m]; empty until something is added.
struct Bounds {
    Vec3f min = Vec3f::Constant(std::numeric_limits<float>::infinity());
    Vec3f max = Vec3f::Constant(-std::numeric_limits<float>::infinity());

    bool is_empty() const { return !(min.x() <= max.x()); }
    void extend(const Vec3f& p) {
        min = min.cwiseMin(p);
        max = max.cwiseMax(p);
    }
    void extend(const Bounds& b) {
        if (b.is_empty()) return;
        extend(b.min);
        extend(b.max);
    }
    Vec3f center() const { return 0.5f * (min + max); }
    /// Corner i of 8: bit 0 picks max x, bit 1 max y, bit 2 max z.
    Vec3f corner(int i) const {
        return Vec3f((i & 1) ? max.x() : min.x(), (i & 2) ? max.y() : min.y(),
                     (i & 4) ? max.z() : min.z());
    }
    /// Half the diagonal [m].
    float radius() const { return 0.5f * (max - min).norm(); }
};

/// Bounds of a mesh's vertices.
inline Bounds mesh_bounds(const TriMesh& mesh) {
    Bounds b;
    for (const Vec3f& p : mesh.positions) b.extend(p);
    return b;
}

/// Bounds of the vertices the mesh's faces use (unused vertices left out), which is what a reader
/// of a written mesh gets: readers that rebuild vertices from face corners drop unused ones.
inline Bounds used_vertex_bounds(const TriMesh& mesh) {
    Bounds b;
    for (const Tri& t : mesh.faces)
        for (int c = 0; c < 3; ++c) b.extend(mesh.positions[size_t(t[c])]);
    return b;
}

}  // namespace mudcrack
