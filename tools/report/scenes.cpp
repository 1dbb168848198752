#include "tools/report/scenes.h"

namespace mudcrack::report {

ParticleBlock lattice_block(const Vec3& lo, const Vec3i& n, Real spacing) {
    ParticleBlock b;
    const size_t count = static_cast<size_t>(n.x()) * n.y() * n.z();
    b.X.reserve(count);
    b.V0.assign(count, spacing * spacing * spacing);
    for (int k = 0; k < n.z(); ++k)
        for (int j = 0; j < n.y(); ++j)
            for (int i = 0; i < n.x(); ++i)
                b.X.push_back(lo + spacing * Vec3(i + 0.5, j + 0.5, k + 0.5));
    return b;
}

SimModel bare_model(Real h, Real youngs_modulus, Real poisson_ratio, Real density) {
    SimModel m;
    m.h = h;
    m.gravity = Vec3::Zero();
    m.elastic.youngs_modulus = youngs_modulus;
    m.elastic.poisson_ratio = poisson_ratio;
    m.elastic.density = density;
    m.checkpoint_every = 0;
    return m;
}

}  // namespace mudcrack::report
