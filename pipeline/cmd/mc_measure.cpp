// mc-measure: a shot's curl, horizontal splits and fragments, in numbers
// (pipeline/stages/measure/measure_stage.h).
#include <string>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/stages/measure/measure_stage.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    MeasureStageOptions measure_options;
    return run_stage(
        "mc-measure",
        "Measures a shot's curl, horizontal splits, fragments and surfacing meshes from its caches (writes nothing "
        "into --out)",
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("--json", measure_options.json_file,
                           "also write the table to this JSON file");
            app.add_flag(
                "--motion", measure_options.motion,
                "re-surface every frame: vertex jumps between frames beyond the particles' moves, and "
                "particles that change piece");
        },
        [&](const StageOptions& options) { return run_measure_stage(options, measure_options); },
        [](const StageOptions&) { return std::optional<LockMode>(); });  // writes no stage folder
}
