#include "pipeline/init/boundary_uv.h"

#include <Eigen/Geometry>

#include <algorithm>

namespace mudcrack {

std::vector<CornerUVs> project_boundary_uvs(const std::vector<Vec3>& X,
                                            const std::vector<Tri>& boundary) {
    std::vector<CornerUVs> uv(boundary.size());
    if (boundary.empty()) return uv;
    Vec3 lo = X[boundary[0][0]], hi = lo;
    for (const Tri& t : boundary)
        for (int32_t v : t) {
            lo = lo.cwiseMin(X[v]);
            hi = hi.cwiseMax(X[v]);
        }
    const Real extent = std::max((hi - lo).maxCoeff(), Real(1e-30));
    for (size_t f = 0; f < boundary.size(); ++f) {
        const Tri& t = boundary[f];
        const Vec3 n = (X[t[1]] - X[t[0]]).cross(X[t[2]] - X[t[0]]).cwiseAbs();
        // (u axis, v axis) of the plane the triangle is projected on
        int u_axis = 0, v_axis = 2;  // dominant y: the XZ plane
        if (n.x() >= n.y() && n.x() >= n.z())
            u_axis = 2, v_axis = 1;  // dominant x: ZY
        else if (n.z() > n.y())
            u_axis = 0, v_axis = 1;  // dominant z: XY
        for (int c = 0; c < 3; ++c) {
            const Vec3 p = (X[t[c]] - lo) / extent;
            uv[f][c] = Vec2(p[u_axis], p[v_axis]);
        }
    }
    return uv;
}

}  // namespace mudcrack
