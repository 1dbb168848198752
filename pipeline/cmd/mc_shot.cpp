// mc-shot: the shot file tool. `validate` checks a shot, `keys` prints the spec table, `slice`
// writes the part of a shot one stage reads, only when it changed, so make reruns a stage exactly
// when its inputs changed; `stages`, `reuse` and `summary` serve pipeline/shot.mk, `verify` the
// farm's scripts
// (pipeline/stages/shot/shot_tool.h). It has no --shot/--out, so it does not use run_stage, but
// follows the same exit codes: 0 ok, 1 bad input, 2 bad usage.
#include <exception>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/shot/shot.h"
#include "pipeline/stages/shot/shot_tool.h"
#include "sim/core/error.h"
#include "sim/core/log.h"

namespace {
constexpr const char* kProgram = "mc-shot";
}  // namespace

int main(int argc, char** argv) {
    using namespace mudcrack;
    log::set_program(kProgram);
    CLI::App app{"mudcrack shot files: check a shot, print the key spec, write a stage's slice",
                 kProgram};
    app.set_version_flag("--version", std::string(kProgram) + " (mudcrack) " MUDCRACK_VERSION);
    app.require_subcommand(1);
    std::string file, stage, out;

    CLI::App* validate =
        app.add_subcommand("validate", "check a shot; prints \"ok: FILE\" and what it turns on");
    validate->add_option("FILE", file, "shot file (JSON with comments)")->required();

    CLI::App* keys = app.add_subcommand(
        "keys", "print every shot key: pointer, type, default, range, units, doc");

    CLI::App* slice = app.add_subcommand(
        "slice",
        "print the canonical keys STAGE reads (with those of earlier stages), or write them to --out");
    slice->add_option("FILE", file, "shot file (JSON with comments)")->required();
    slice->add_option("STAGE", stage, "init|sim|surface|render")
        ->required()
        ->check(CLI::IsMember({"init", "sim", "surface", "render"}));
    slice->add_option("--out", out,
                      "write here, only if the content changed (keeps the mtime for make)");

    CLI::App* stages = app.add_subcommand("stages", "print the stages FILE turns on, in run order");
    stages->add_option("FILE", file, "shot file (JSON with comments)")->required();

    CLI::App* reuse =
        app.add_subcommand("reuse", "print the shot FILE's /reuse names (nothing when unset)");
    reuse->add_option("FILE", file, "shot file (JSON with comments)")->required();

    std::string out_dir;
    CLI::App* summary_cmd =
        app.add_subcommand("summary", "print what each stage wrote under OUT (from its manifest)");
    summary_cmd->add_option("OUT", out_dir, "a shot's output folder, e.g. out/demo")->required();
    bool summary_json = false;
    summary_cmd->add_flag("--json", summary_json,
                          "print one JSON object instead of the table (for scripts)");

    std::string manifest_file;
    CLI::App* verify = app.add_subcommand(
        "verify",
        "check every file a stage manifest records against its checksum (exit 1 naming a damaged one)");
    verify
        ->add_option("MANIFEST", manifest_file,
                     "a stage's manifest, e.g. out/demo/surface/manifest.json")
        ->required();

    try {
        app.parse(argc, argv);
        refuse_empty_values(app);
    } catch (const CLI::ParseError& e) {
        return parse_error_exit(app, e, kProgram);
    } catch (const UsageError& e) {
        log::error(e.what());
        return kExitUsage;
    }

    try {
        if (keys->parsed()) {
            std::cout << spec_table_text();
            return 0;
        }
        if (stages->parsed()) {
            std::cout << stage_list(load_shot(file)) << "\n";
            return 0;
        }
        if (reuse->parsed()) {
            const Shot shot = load_shot(file);
            if (!shot.reuse.empty()) std::cout << shot.reuse << "\n";
            return 0;
        }
        if (summary_cmd->parsed()) return run_summary(out_dir, summary_json);
        if (verify->parsed()) return run_verify(manifest_file);
        if (validate->parsed()) {
            const Shot shot = load_shot(file);
            std::cout << "ok: " << file << "\n" << shot_summary(shot) << "\n";
            log::summarize_warnings();
            return 0;
        }
        return run_slice(file, stage, out);
    } catch (const InputError& e) {
        report_error_lines(e.what());
    } catch (const RuntimeError& e) {
        report_error_lines(e.what());
    } catch (const std::exception& e) {
        report_error_lines(std::string("unexpected failure: ") + e.what());
    }
    return 1;
}
