#include "render/scene.h"

namespace mudcrack {

Bounds scene_bounds(const Scene& scene) {
    Bounds b;
    for (const SceneMesh& m : scene.meshes) b.extend(mesh_bounds(m.mesh));
    const Vec3f r = Vec3f::Constant(scene.particles.radius);
    for (const Vec3f& p : scene.particles.positions) {
        b.extend(p - r);
        b.extend(p + r);
    }
    return b;
}

size_t triangle_count(const Scene& scene) {
    size_t n = 0;
    for (const SceneMesh& m : scene.meshes) n += m.mesh.faces.size();
    return n;
}

}  // namespace mudcrack
