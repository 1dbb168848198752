#pragma once
/// Settings of the particle-core surfacing (Tu et al. 2023 Section 6; docs/physics.md §5).
#include <optional>
#include <string>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

enum class SurfaceMode {
    Ours,      // moisture-aware: Jw^(1/3) core scaling (Eq. 13), Jw-scaled threshold (Eq. 14)
    Wang2019,  // the baseline of Wang et al. 2019: no moisture factors
    Plates,    // Eq. 14's breaks made into plates with clean walls (docs/physics.md §5.7)
};

/// What the plates mode writes for the particles that tore loose.
enum class DebrisOutput {
    None,    // nothing: they leave the meshes
    Points,  // debris.####.ply per frame: position, velocity, radius, id, piece
};

struct SurfaceParams;
/// True when the params ask for debris outside the plates mode, the only mode that tells debris
/// from the pieces (the shot loader and mc-surface --mode refuse it, each naming its input).
bool debris_needs_plates(const SurfaceParams& params);

struct SurfaceParams {
    SurfaceMode mode = SurfaceMode::Ours;
    Real zeta = 2;  // edge-stretch threshold of Eq. 14 [-]
    // threshold 0.5 (Jw_p^(1/3) + Jw_q^(1/3)) zeta (docs/physics.md §5.5)
    bool length_consistent = false;
    bool cracks = true;              // mesh crack surfaces (false: boundary only, no crack mesh)
    std::string format = "glb";      // glb | obj | ply | dae
    int min_fragment_particles = 1;  // fragments smaller than this are culled as debris
    // plates mode (docs/physics.md §5.7)
    Real min_piece_size = 2;  // [cells of /sim/h] a fragment this wide across is a plate
    // [particle spacings] band particles that every path to a plate opens more than this are debris
    Real debris_gap = 0.5;
    // [particle spacings] walls closer than this meet (no hairline gaps)
    Real close_gaps = 0.25;
    // [particle spacings per frame] how fast a fresh crack whose particles parted before it was
    // cut parts its sides (FrameCores::opening); 0: every crack shows as open as its particles
    Real open_speed = 0.2;
    // Taubin steps of the crack walls, in rest space and where they are (0: off)
    int wall_smoothing = 25;
    DebrisOutput debris = DebrisOutput::None;
    // [m] the shot's /sim/h (set by load_shot): min_piece_size's unit
    Real cell_size = 0;
};

/// "ours" | "wang2019" | "plates".
const char* surface_mode_name(SurfaceMode mode);
/// The mode named `name`, or nullopt for an unknown name: the one parser of mode names.
std::optional<SurfaceMode> parse_surface_mode(const std::string& name);
/// Every mode name, for the shot spec and the command line.
std::vector<std::string> surface_mode_names();

}  // namespace mudcrack
