// G2P with a float state (SimStateFloat, /sim/precision "float"); the templates are in
// g2p_impl.h, instantiated here in a unit of their own (g2p_impl.h says why).
#include "sim/mpm/g2p_impl.h"

namespace mudcrack::mpm {

template G2PResult grid_to_particle(const SimModel&, SimStateOf<float>&, const SparseGrid&,
                                    const MoistureUpdate&, bool, Real,
                                    std::vector<std::vector<Real>>&, SymMat3*);

}  // namespace mudcrack::mpm
