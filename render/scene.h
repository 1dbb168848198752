#pragma once
/// What the renderer draws: surfaced meshes tagged as boundary or crack, or (for shots without
/// surfacing) the particles as sphere impostors. Plain data; the renderer uploads it.
#include <vector>

#include "sim/core/bounds.h"
#include "sim/core/tri_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// Which surface a mesh is: the outer boundary, or the fresh crack faces (shaded as darker,
/// warmer interior soil).
enum class SurfaceKind { Boundary, Crack };

struct SceneMesh {
    TriMesh mesh;  // normals are computed (area-weighted) when empty
    SurfaceKind kind = SurfaceKind::Boundary;
};

/// Particles drawn as shaded spheres of one radius.
struct ParticleSprites {
    std::vector<Vec3f> positions;   // centers [m], (n)
    std::vector<float> saturation;  // s in [0,1], (n) or empty (dry)
    std::vector<float> alpha;       // hardening state, (n) or empty (alpha0: neutral)
    float radius = 0.01f;           // [m]
    size_t size() const { return positions.size(); }
};

struct Scene {
    std::vector<SceneMesh> meshes;
    ParticleSprites particles;  // empty: none
};

/// Bounds of everything in the scene (particles grown by their radius).
Bounds scene_bounds(const Scene& scene);
/// Number of triangles in the scene's meshes.
size_t triangle_count(const Scene& scene);

}  // namespace mudcrack
