#include "tools/report/energy.h"

#include "sim/material/neo_hookean.h"

namespace mudcrack::report {

EnergyBreakdown state_energy(const SimModel& model, const SimState& state) {
    EnergyBreakdown e;
    const LameParams lame = lame_params(model.elastic);
    const Real ref_y = model.ground ? model.ground->height : 0;
    for (size_t p = 0; p < state.size(); ++p) {
        const Real m = state.mass[p];
        e.kinetic += Real(0.5) * m * state.v[p].squaredNorm();
        Vec3 rel = state.x[p];
        rel.y() -= ref_y;
        e.gravitational -= m * model.gravity.dot(rel);
        e.elastic += state.V0[p] * neo_hookean_energy(state.Fe[p], lame);
    }
    return e;
}

}  // namespace mudcrack::report
