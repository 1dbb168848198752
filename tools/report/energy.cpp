#include "tools/report/energy.h"

#include "sim/material/neo_hookean.h"

namespace mudcrack::report {

template <class S>
EnergyBreakdown state_energy(const SimModel& model, const SimStateOf<S>& state) {
    EnergyBreakdown e;
    const LameParams lame = lame_params(model.elastic);
    const Real ref_y = model.ground ? model.ground->height : 0;
    for (size_t p = 0; p < state.size(); ++p) {
        const Real m = state.mass[p];
        e.kinetic += Real(0.5) * m * state.v[p].template cast<Real>().squaredNorm();
        Vec3 rel = state.x[p].template cast<Real>();
        rel.y() -= ref_y;
        e.gravitational -= m * model.gravity.dot(rel);
        e.elastic += state.V0[p] * neo_hookean_energy(state.Fe[p].template cast<Real>(), lame);
    }
    return e;
}

template EnergyBreakdown state_energy(const SimModel&, const SimStateOf<double>&);
template EnergyBreakdown state_energy(const SimModel&, const SimStateOf<float>&);

}  // namespace mudcrack::report
