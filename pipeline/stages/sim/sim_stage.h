#pragma once
/// The mc-sim stage: reads DIR/init/, runs the shot's frames, and writes
/// DIR/sim/particles.####.vdb per frame (each atomically), checkpoint.####.bin every
/// model.checkpoint_every frames (the last two kept), and manifest.json last.
#include "pipeline/shot/shot.h"
#include "pipeline/stages/stage_options.h"

namespace mudcrack {

/// What mc-sim adds to the common stage flags.
struct SimStageOptions {
    bool resume = false;  // --resume: continue from the last valid checkpoint
    /// Testing aid (hidden flag --inject-nan-at-frame K): particle 0's velocity becomes NaN at the
    /// start of frame K, so tests can exercise the failure path (stop, keep earlier frames, no
    /// manifest, exit 1) at a chosen frame. 0: off; a frame outside the ones the run simulates is
    /// a usage error (exit 2), as --frames is.
    int inject_nan_at_frame = 0;
};

/// Runs the stage for a loaded shot. Frames are written straight into DIR/sim/ (not a .partial
/// folder) so that a failed or killed run keeps what it finished and --resume can continue it;
/// the manifest is removed at the start and written only on success, so make re-runs an
/// incomplete stage. Returns the exit code (0).
/// @throws InputError when the init outputs are missing or stale for this shot
/// @throws RuntimeError when the simulation fails (frame, substep, particle id and state)
int run_sim_stage(const Shot& shot, const StageOptions& options,
                  const SimStageOptions& sim_options);

}  // namespace mudcrack
