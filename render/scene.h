#pragma once
/// What the renderer draws: surfaced meshes tagged as boundary or crack, or (for shots without
/// surfacing) the particles as sphere impostors. Plain data; the renderer uploads it.
#include <limits>
#include <vector>

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
    /// Half the diagonal [m].
    float radius() const { return 0.5f * (max - min).norm(); }
};

/// Which surface a mesh is: the outer boundary, or the fresh crack faces (shaded as darker,
/// warmer interior soil).
enum class SurfaceKind { Boundary, Crack };

struct SceneMesh {
    TriMesh mesh;  // normals are computed (area-weighted) when empty
    SurfaceKind kind = SurfaceKind::Boundary;
};

/// Particles drawn as shaded spheres of one radius.
struct ParticleSprites {
    std::vector<Vec3f> positions;  // centers [m], (n)
    std::vector<float> saturation; // s in [0,1], (n) or empty (dry)
    std::vector<float> alpha;      // hardening state, (n) or empty (alpha0: neutral)
    float radius = 0.01f;          // [m]
    size_t size() const { return positions.size(); }
};

struct Scene {
    std::vector<SceneMesh> meshes;
    ParticleSprites particles;  // empty: none
};

/// Bounds of a mesh's vertices.
Bounds mesh_bounds(const TriMesh& mesh);
/// Bounds of everything in the scene (particles grown by their radius).
Bounds scene_bounds(const Scene& scene);
/// Number of triangles in the scene's meshes.
size_t triangle_count(const Scene& scene);

}  // namespace mudcrack
