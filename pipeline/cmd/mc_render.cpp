// mc-render: headless preview renders of a shot's surfaced meshes or particle caches
// (pipeline/stages/render/render_stage.h says what a run writes, and how a farm splits it).
#include "pipeline/cmd/stage_cli.h"
#include "pipeline/stages/render/render_stage.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    RenderStageOptions render_options;
    return run_stage(
        "mc-render",
        "Headless preview renders (OSMesa): DIR/render/frame.####.png, turntable.####.png, "
        "contact_sheet.png, preview.mp4 and turntable.mp4 (with ffmpeg); --frames A-B renders only those "
        "frame PNGs (a farm chunk), --assemble makes the rest from them",
        argc, argv,
        [&](CLI::App& app) {
            app.add_flag(
                "--turntable", render_options.force_turntable,
                "also render the turntable when the shot has no /render/turntable section");
            app.add_flag(
                "--assemble", render_options.assemble,
                "from the frame PNGs already in DIR/render/ (rendered by --frames chunks), render the "
                "turntable and write contact_sheet.png, the movies and manifest.json");
        },
        [&](const StageOptions& options) { return run_render_stage(options, render_options); },
        // --frames chunks of one shot write their own frames into one folder side by side
        [&](const StageOptions& options) {
            return std::optional<LockMode>(options.frame_range.is_set() && !render_options.assemble
                                               ? LockMode::Shared
                                               : LockMode::Exclusive);
        });
}
