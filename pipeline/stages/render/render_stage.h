#pragma once
/// The mc-render stage: headless preview renders (OSMesa). Reads DIR/surface/boundary.####.<ext>
/// and crack.####.<ext> (or, for a shot without surfacing, DIR/sim/particles.####.vdb) and writes
/// DIR/render/frame.####.png, turntable.####.png, contact_sheet.png, preview.mp4 and
/// turntable.mp4 (when ffmpeg is on PATH), and manifest.json last. A full run builds everything in
/// DIR/.render.partial/ and renames it on success, so a failed run leaves no half-written file.
/// A farm splits the same work in two: `--frames A-B` jobs render chunks of frames into
/// DIR/render/ (each PNG renamed into place), then one `--assemble` job makes the turntable, the
/// contact sheet, the movies and the manifest from those PNGs. Both ways give the same bytes: every
/// frame is framed from the bounds of all frames of the shot.
#include "pipeline/stages/stage_options.h"

namespace mudcrack {

/// What mc-render adds to the common stage flags.
struct RenderStageOptions {
    bool force_turntable = false;  // --turntable: also when the shot has no /render/turntable
    bool assemble = false;         // --assemble: the rest from the frame PNGs of --frames chunks
};

/// Runs the stage: a full run, a --frames chunk or an --assemble run. Returns the exit code (0).
/// @throws InputError for bad flags, or inputs that are missing, stale or malformed
int run_render_stage(const StageOptions& options, const RenderStageOptions& render_options);

}  // namespace mudcrack
