#include "sim/core/tet_mesh.h"

#include <cmath>

namespace mudcrack {

std::vector<Real> particle_rest_volumes(const TetMesh& mesh) {
    std::vector<Real> volume(mesh.X.size(), Real(0));
    for (const Tet& t : mesh.tets) {
        const Real v =
            std::abs(signed_tet_volume(mesh.X[t[0]], mesh.X[t[1]], mesh.X[t[2]], mesh.X[t[3]]));
        for (int k = 0; k < 4; ++k) volume[t[k]] += Real(0.25) * v;
    }
    return volume;
}

}  // namespace mudcrack
