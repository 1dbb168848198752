#pragma once
/// The mc-measure stage: what drying did to a shot, in numbers, so the figure claims are checked
/// on numbers and not only by eye. Reads DIR/init/tets.vtu, DIR/sim/particles.####.vdb and, when
/// the shot surfaces, DIR/surface/edge_breaks.bin; prints per frame the curl of the top surface,
/// the share of columns split horizontally or lifted off the ground
/// (pipeline/measure/shape_measures.h says how each is defined), and the broken edges and fragment
/// sizes of the surfacing. Writes nothing into DIR.
#include <string>

#include "pipeline/stages/stage_options.h"

namespace mudcrack {

/// What mc-measure adds to the common stage flags.
struct MeasureStageOptions {
    std::string json_file;  // --json: also write the table there as JSON (atomically)
    // --motion: re-surface each frame and measure vertex jumps and piece changes
    bool motion = false;
};

/// Measures every cached frame (or --frames) and prints the table (unless --quiet). When the
/// surface folder holds meshes, a second table measures them (pipeline/measure/mesh_measures.h).
/// Returns the exit code (0).
/// @throws InputError when an input stage's outputs are missing, stale or malformed
int run_measure_stage(const StageOptions& options, const MeasureStageOptions& measure_options);

}  // namespace mudcrack
