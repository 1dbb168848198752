// G2P with a double state (SimState); the templates are in g2p_impl.h.
#include "sim/mpm/g2p_impl.h"

namespace mudcrack::mpm {

template G2PResult grid_to_particle(const SimModel&, SimStateOf<double>&, const SparseGrid&,
                                    const MoistureUpdate&, bool, Real,
                                    std::vector<std::vector<Real>>&, SymMat3*);

}  // namespace mudcrack::mpm
