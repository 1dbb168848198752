#pragma once
/// The mc-init stage: tetrahedral initialization. Reads the shot's /source and /init, builds the
/// particle tet mesh (box or heightfield lattice, or a checked surface filled by CGAL Mesh_3), and
/// writes DIR/init/particles.vdb (P, id, volume0), DIR/init/tets.vtu (tets, boundary faces with
/// UVs) and DIR/init/manifest.json (last). A failed run leaves nothing.
#include "pipeline/stages/stage_options.h"

namespace mudcrack {

/// Runs the stage. Returns the exit code (0).
/// @param parallel_mesh mesh sources: run CGAL Mesh_3 on all threads (not bit-identical reruns)
/// @throws InputError naming the shot file and key of a bad source
int run_init_stage(const StageOptions& options, bool parallel_mesh);

}  // namespace mudcrack
