#include "pipeline/stages/shot/shot_tool.h"

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
#include <vector>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/manifest.h"
#include "sim/core/error.h"
#include "sim/core/log.h"

namespace mudcrack {
namespace {

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

}  // namespace

std::string shot_summary(const Shot& shot) {
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

namespace {

/// The file's text, or "" if it does not exist.
std::string read_if_exists(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return "";
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace

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

}  // namespace mudcrack
