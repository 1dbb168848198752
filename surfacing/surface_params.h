#pragma once
/// Settings of the particle-core surfacing (Tu et al. 2023 Section 6; docs/physics.md §5).
#include <string>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

enum class SurfaceMode {
    Ours,      // moisture-aware: Jw^(1/3) core scaling (Eq. 13), Jw-scaled threshold (Eq. 14)
    Wang2019,  // the baseline of Wang et al. 2019: no moisture factors
};

struct SurfaceParams {
    SurfaceMode mode = SurfaceMode::Ours;
    Real zeta = 2;                  // edge-stretch threshold of Eq. 14 [-]
    bool length_consistent = false; // threshold 0.5 (Jw_p^(1/3) + Jw_q^(1/3)) zeta (docs/physics.md §5.5)
    bool cracks = true;             // mesh crack surfaces (false: boundary only, no crack mesh)
    std::string format = "glb";     // glb | obj | ply | dae
    int min_fragment_particles = 1; // fragments smaller than this are culled as debris
};

}  // namespace mudcrack

namespace mudcrack {
/// "ours" | "wang2019".
const char* surface_mode_name(SurfaceMode mode);
}  // namespace mudcrack
