#pragma once
/// The mc-surface stage: particle-core surfacing (Tu et al. 2023 Section 6).
/// Reads DIR/init/tets.vtu and DIR/sim/particles.####.vdb, writes DIR/surface/boundary.####.<ext>,
/// crack.####.<ext>, edge_breaks.bin (the Eq. 14 break history) and manifest.json (last).
///
/// Frames are independent: the break history ("t <= n" in Eq. 14) is the first frame at which each
/// edge broke, computed once by a pass over all cached frames and kept in edge_breaks.bin, so any
/// frame range can be surfaced, in any order and in parallel, with identical files.
#include <string>

#include "pipeline/stages/stage_options.h"

namespace mudcrack {

/// What mc-surface adds to the common stage flags ("" = the shot's).
struct SurfaceStageOptions {
    std::string mode;    // --mode: "ours", "wang2019" or "plates"
    std::string format;  // --format: a mesh extension
};

/// Runs the stage: surfaces the frames of the sim cache (or --frames, updating an existing
/// surface folder of the same shot, mode and format in place). Returns the exit code (0).
/// @throws InputError when the init or sim outputs are missing, stale or malformed
int run_surface_stage(const StageOptions& options, const SurfaceStageOptions& surface_options);

}  // namespace mudcrack
