// mc-surface: the particle-core surfacing stage (pipeline/stages/surface/surface_stage.h).
#include <string>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/stages/surface/surface_stage.h"
#include "surfacing/surface_params.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    SurfaceStageOptions surface_options;
    return run_stage(
        "mc-surface",
        "particle-core surfacing: boundary and crack meshes per frame from OUT/init/ and OUT/sim/ into OUT/surface/",
        argc, argv,
        [&](CLI::App& app) {
            app.add_option(
                   "--mode", surface_options.mode,
                   "ours (moisture-aware Eq. 13/14), wang2019 (the baseline) or plates (clean plates for "
                   "close-ups); default: the shot's")
                ->check(CLI::IsMember(surface_mode_names()));
            app.add_option("--format", surface_options.format,
                           "glb, obj, ply or dae (fbx is refused); default: the shot's");
        },
        [&](const StageOptions& options) { return run_surface_stage(options, surface_options); });
}
