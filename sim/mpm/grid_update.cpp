// Grid velocity update and boundary conditions (docs/physics.md §1.3).
#include <cmath>

#include "sim/mpm/transfer.h"

namespace mudcrack::mpm {

namespace {

// Coulomb friction on the tangential part after a normal projection (taichi_elements' rule):
// v_n < 0 is the approach speed before the projection
inline void apply_friction(Vec3& v, Real v_n, Real mu_f) {
    if (!(v_n < 0) || mu_f <= 0) return;
    const Real vt = std::sqrt(v.x() * v.x() + v.z() * v.z());
    if (!(vt > 0)) return;
    const Real scale = std::max(Real(0), vt + mu_f * v_n) / vt;
    v.x() *= scale;
    v.z() *= scale;
}

// ground plane y = height, outward normal +y
inline void apply_ground(const GroundParams& g, Vec3& v) {
    const Real v_n = v.y();
    switch (g.mode) {
        case ColliderMode::Sticky: v.setZero(); return;
        case ColliderMode::Slip:
            v.y() = 0;
            apply_friction(v, v_n, g.friction);
            return;
        case ColliderMode::Separate:
            if (v_n < 0) {
                v.y() = 0;
                apply_friction(v, v_n, g.friction);
            }
            return;
    }
}

}  // namespace

void update_grid_velocity(const SimModel& model, SparseGrid& grid, Real dt) {
    const GridGeometry& geo = grid.geo;
    const Vec3 dv_gravity = dt * model.gravity;
    const bool has_ground = model.ground.has_value();
    const GroundParams ground = has_ground ? *model.ground : GroundParams{};
    const int pad = geo.padding;
    parallel_for(static_cast<int64_t>(grid.n_blocks()), [&](int64_t b) {
        const Vec3i corner = geo.block_coord(grid.block_keys[b]) * kBlockWidth;
        Real* block = grid.nodes.data() + b * kBlockNodes * kNodeFields;
        for (int a = 0; a < kBlockWidth; ++a)
            for (int bb = 0; bb < kBlockWidth; ++bb)
                for (int c = 0; c < kBlockWidth; ++c) {
                    Real* node = block + block_node_index(a, bb, c) * kNodeFields;
                    const Real m = node[0];
                    if (!(m > 0)) {
                        node[1] = node[2] = node[3] = 0;
                        continue;
                    }
                    // momentum to velocity, then gravity
                    const Real inv_m = 1 / m;
                    Vec3 v(node[1] * inv_m + dv_gravity.x(), node[2] * inv_m + dv_gravity.y(),
                           node[3] * inv_m + dv_gravity.z());
                    const Vec3i g = corner + Vec3i(a, bb, c);
                    // ground collider on nodes inside or on the plane
                    if (has_ground && geo.origin.y() + geo.h * g.y() <= ground.height)
                        apply_ground(ground, v);
                    // domain walls: nodes in the padding band lose their outward component
                    for (int d = 0; d < 3; ++d) {
                        if (g[d] < pad && v[d] < 0) v[d] = 0;
                        if (g[d] > geo.cells[d] - pad && v[d] > 0) v[d] = 0;
                    }
                    node[1] = v.x();
                    node[2] = v.y();
                    node[3] = v.z();
                }
    });
}

}  // namespace mudcrack::mpm
