#pragma once
/// The mc-measure stage: what drying did to a shot, in numbers, so the figure claims are checked
/// on numbers and not only by eye. Reads DIR/init/tets.vtu, DIR/sim/particles.####.vdb and, when
/// the shot surfaces, DIR/surface/edge_breaks.bin; prints per frame the curl of the top surface,
/// the share of columns split horizontally or lifted off the ground
/// (pipeline/measure/shape_measures.h says how each is defined), and the broken edges and fragment
/// sizes of the surfacing. Writes nothing into DIR.
#include <string>

#include "pipeline/cmd/stage_cli.h"

namespace mudcrack {

/// Measures every cached frame (or --frames) and prints the table (unless --quiet).
/// Returns the exit code (0).
/// @param json_file when not empty, the table is also written there as JSON (atomically)
/// @throws InputError when an input stage's outputs are missing, stale or malformed
int run_measure_stage(const StageOptions& options, const std::string& json_file);

}  // namespace mudcrack
