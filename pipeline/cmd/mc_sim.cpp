// mc-sim: the MPM simulation stage (pipeline/stages/sim/sim_stage.h). Reads DIR/init/, writes
// DIR/sim/.
#include "pipeline/cmd/stage_cli.h"
#include "pipeline/shot/shot.h"
#include "pipeline/stages/sim/sim_stage.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    SimStageOptions sim_options;
    std::string inject_text;
    return run_stage(
        "mc-sim", "MPM simulation of drying soil: writes per-frame particle caches to OUT/sim/",
        argc, argv,
        [&](CLI::App& app) {
            app.add_flag("--resume", sim_options.resume,
                         "continue from the last valid checkpoint in OUT/sim/ (bitwise identical "
                         "caches at the same thread count)");
            // a testing aid, hidden from --help (an empty group); read as text, since CLI11's
            // own conversion error would not name a hidden flag
            app.add_option("--inject-nan-at-frame", inject_text,
                           "testing: particle 0's velocity becomes NaN at the start of this frame")
                ->group("");
        },
        [&](const StageOptions& options) {
            if (!inject_text.empty())
                sim_options.inject_nan_at_frame =
                    parse_frame_number("--inject-nan-at-frame", inject_text);
            const Shot shot = load_shot(options.shot);
            return run_sim_stage(shot, options, sim_options);
        });
}
