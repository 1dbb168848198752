// mc-measure: a shot's curl, horizontal splits and fragments, in numbers
// (pipeline/stages/measure/measure_stage.h).
#include <string>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/stages/measure/measure_stage.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    std::string json_file;
    return run_stage(
        "mc-measure",
        "Measures a shot's curl, horizontal splits and fragments from its caches (writes nothing into --out)",
        argc, argv, [&](CLI::App& app) { app.add_option("--json", json_file, "also write the table to this JSON file"); },
        [&](const StageOptions& options) { return run_measure_stage(options, json_file); });
}
