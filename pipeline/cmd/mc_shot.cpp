// mc-shot: the shot file tool (style.md 9). `validate` checks a shot, `keys` prints the spec
// table, `slice` writes the part of a shot one stage reads, only when it changed, so make reruns
// a stage exactly when its inputs changed; `stages`, `reuse` and `summary` serve pipeline/shot.mk. It has no --shot/--out, so it does not use run_stage,
// but follows the same exit codes: 0 ok, 1 bad input, 2 bad usage.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "pipeline/cmd/stage_cli.h"
#include "pipeline/io/atomic_output.h"
#include "pipeline/io/manifest.h"
#include "pipeline/shot/shot.h"
#include "sim/core/error.h"
#include "sim/core/log.h"

namespace mudcrack {
namespace {

constexpr const char* kProgram = "mc-shot";

Stage parse_stage(const std::string& name) {
    if (name == "init") return Stage::Init;
    if (name == "sim") return Stage::Sim;
    if (name == "surface") return Stage::Surface;
    return Stage::Render;
}

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

const char* collider_mode_name(ColliderMode mode) {
    switch (mode) {
        case ColliderMode::Sticky: return "sticky";
        case ColliderMode::Slip: return "slip";
        case ColliderMode::Separate: return "separate";
    }
    return "?";
}

/// One line saying which stages and features the shot turns on.
std::string summary(const Shot& shot) {
    const SimModel& sim = shot.sim;
    std::string s = shot.name + ": stages init sim";
    if (shot.surface) s += " surface";
    if (shot.render) s += " render";
    s += "; source " + std::string(source_type_name(shot.init.type));
    s += "; plasticity " + std::string(sim.nacc ? "on" : "off");
    s += "; moisture " + std::string(sim.moisture ? "on" : "off");
    s += sim.ground ? "; ground " + std::string(collider_mode_name(sim.ground->mode)) + " at y=" +
                          number(sim.ground->height)
                    : "; no ground";
    s += sim.domain.is_auto ? "; domain auto" : "; domain fixed";
    s += "; h " + number(sim.h) + " m";
    s += "; frames " + std::to_string(sim.time.frame_start) + "-" + std::to_string(sim.time.frame_end) +
         " at " + number(sim.time.fps) + " fps";
    s += sim.time.dt_fixed > 0 ? "; dt fixed " + number(sim.time.dt_fixed) + " s"
                               : "; dt adaptive <= " + number(sim.time.dt_max) + " s";
    if (shot.surface) s += "; surfacing " + std::string(surface_mode_name(shot.surface->mode));
    if (shot.render) {
        s += "; render " + std::to_string(shot.render->width) + "x" + std::to_string(shot.render->height) +
             " " + color_mode_name(shot.render->color_mode);
        if (shot.render->turntable) s += " + turntable";
    }
    return s;
}

/// The file's text, or "" if it does not exist.
std::string read_if_exists(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return "";
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

int run_slice(const std::string& file, const std::string& stage_name, const std::string& out) {
    const Shot shot = load_shot(file);
    const std::string& text = shot.slice(parse_stage(stage_name));
    if (out.empty()) {
        std::cout << text;
        return 0;
    }
    // rewrite only on change: make compares mtimes, and an unchanged slice must not rerun a stage
    if (read_if_exists(out) == text) {
        log::info(out + ": unchanged");
        return 0;
    }
    const std::filesystem::path parent = std::filesystem::path(out).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    write_text_atomically(out, text);
    log::info(out + ": written");
    return 0;
}

/// The stages a shot turns on, in run order, e.g. "init sim surface render" (for make).
std::string stage_list(const Shot& shot) {
    std::string s = "init sim";
    if (shot.surface) s += " surface";
    if (shot.render) s += " render";
    return s;
}

namespace {
/// The first number found at one of the JSON pointers, or NaN.
double first_number(const nlohmann::json& m, std::initializer_list<const char*> pointers) {
    for (const char* p : pointers) {
        const nlohmann::json::json_pointer ptr(p);
        if (m.contains(ptr) && m[ptr].is_number()) return m[ptr].get<double>();
    }
    return std::nan("");
}
}  // namespace

/// The table `make shot` ends with: per stage output folder under `out`, the frames, wall time,
/// throughput, peak memory and outputs, as the stage's manifest recorded them.
int run_summary(const std::string& out) {
    namespace fs = std::filesystem;
    struct Throughput { const char* pointer; const char* unit; };
    const std::map<std::string, std::vector<Throughput>> throughput = {
        {"init", {{"/rates/particles_per_s", "particles/s"}}},
        {"sim", {{"/particle_steps_per_second", "particle-steps/s"}}},
        {"surface", {{"/tets_per_second", "tets/s"}}},
        {"render", {{"/seconds_per_frame", "s/frame"}}},
    };
    std::printf("%-8s %-10s %9s %26s %10s  %s\n", "stage", "frames", "wall [s]", "throughput", "peak MiB",
                "outputs");
    int stages_found = 0;
    for (const char* stage : {"init", "sim", "surface", "render"}) {
        const fs::path dir = fs::path(out) / stage;
        std::error_code ec;
        if (!fs::is_regular_file(dir / "manifest.json", ec)) continue;
        const nlohmann::json m = read_manifest(dir);
        int files = 0;
        std::uintmax_t bytes = 0;
        for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
            if (!e.is_regular_file()) continue;
            ++files;
            bytes += e.file_size();
        }
        std::string frames = "-";
        const double first = first_number(m, {"/frames/first"}), last = first_number(m, {"/frames/last"});
        if (!std::isnan(first) && !std::isnan(last))
            frames = std::to_string(int(first)) + "-" + std::to_string(int(last));
        const double wall = first_number(m, {"/wall_seconds", "/wall_time_seconds"});
        const double peak = first_number(m, {"/peak_memory_bytes", "/peak_rss_bytes"});
        std::string rate = "-";
        for (const Throughput& t : throughput.at(stage)) {
            const double v = first_number(m, {t.pointer});
            if (!std::isnan(v)) rate = number(v) + " " + t.unit;
        }
        char outputs[64];
        std::snprintf(outputs, sizeof outputs, "%d files, %.1f MiB", files, static_cast<double>(bytes) / 1048576.0);
        std::printf("%-8s %-10s %9.2f %26s %10.1f  %s in %s\n", stage, frames.c_str(), wall, rate.c_str(),
                    peak / 1048576.0, outputs, dir.string().c_str());
        ++stages_found;
    }
    if (stages_found == 0) throw InputError(out + ": no stage outputs (no <stage>/manifest.json)");
    return 0;
}


}  // namespace
}  // namespace mudcrack

int main(int argc, char** argv) {
    using namespace mudcrack;
    log::set_program(kProgram);
    CLI::App app{"mudcrack shot files: check a shot, print the key spec, write a stage's slice", kProgram};
    app.set_version_flag("--version", std::string(kProgram) + " (mudcrack) " MUDCRACK_VERSION);
    app.require_subcommand(1);
    std::string file, stage, out;

    CLI::App* validate =
        app.add_subcommand("validate", "check a shot; prints \"ok: FILE\" and what it turns on");
    validate->add_option("FILE", file, "shot file (JSON with comments)")->required();

    CLI::App* keys =
        app.add_subcommand("keys", "print every shot key: pointer, type, default, range, units, doc");

    CLI::App* slice = app.add_subcommand(
        "slice",
        "print the canonical keys STAGE reads (with those of earlier stages), or write them to --out");
    slice->add_option("FILE", file, "shot file (JSON with comments)")->required();
    slice->add_option("STAGE", stage, "init|sim|surface|render")
        ->required()
        ->check(CLI::IsMember({"init", "sim", "surface", "render"}));
    slice->add_option("--out", out, "write here, only if the content changed (keeps the mtime for make)");

    CLI::App* stages = app.add_subcommand("stages", "print the stages FILE turns on, in run order");
    stages->add_option("FILE", file, "shot file (JSON with comments)")->required();

    CLI::App* reuse = app.add_subcommand("reuse", "print the shot FILE's /reuse names (nothing when unset)");
    reuse->add_option("FILE", file, "shot file (JSON with comments)")->required();

    std::string out_dir;
    CLI::App* summary_cmd =
        app.add_subcommand("summary", "print what each stage wrote under OUT (from its manifest)");
    summary_cmd->add_option("OUT", out_dir, "a shot's output folder, e.g. out/demo")->required();

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
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
        if (summary_cmd->parsed()) return run_summary(out_dir);
        if (validate->parsed()) {
            const Shot shot = load_shot(file);
            std::cout << "ok: " << file << "\n" << summary(shot) << "\n";
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
