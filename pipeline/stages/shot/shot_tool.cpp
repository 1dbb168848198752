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
    s += sim.ground ? "; ground " + std::string(collider_mode_name(sim.ground->mode)) +
                          " at y=" + number(sim.ground->height)
                    : "; no ground";
    s += sim.domain.is_auto ? "; domain auto" : "; domain fixed";
    s += "; h " + number(sim.h) + " m";
    if (sim.precision == StatePrecision::Float) s += "; state float";
    s += "; frames " + std::to_string(sim.time.frame_start) + "-" +
         std::to_string(sim.time.frame_end) + " at " + number(sim.time.fps) + " fps";
    s += sim.time.dt_fixed > 0 ? "; dt fixed " + number(sim.time.dt_fixed) + " s"
                               : "; dt adaptive <= " + number(sim.time.dt_max) + " s";
    if (shot.surface) s += "; surfacing " + std::string(surface_mode_name(shot.surface->mode));
    if (shot.render) {
        s += "; render " + std::to_string(shot.render->width) + "x" +
             std::to_string(shot.render->height) + " " + color_mode_name(shot.render->color_mode);
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

/// What one stage's manifest and output folder say, for `mc-shot summary`.
struct StageSummary {
    std::string stage, dir, shot;  // shot: the shot file that ran the stage ("" if unrecorded)
    int first = 0, last = 0;       // frames; both 0 when the stage has none (init)
    int resumed_from_frame = 0;    // a sim that resumed from its checkpoint at this frame; else 0
    double wall_seconds = std::nan(""), peak_memory_bytes = std::nan("");
    double rate = std::nan("");  // the stage's throughput, in rate_unit
    std::string rate_unit;
    int files = 0;
    std::uintmax_t bytes = 0;
};

std::vector<StageSummary> read_stage_summaries(const std::string& out) {
    namespace fs = std::filesystem;
    struct Throughput {
        const char* pointer;
        const char* unit;
    };
    const std::map<std::string, Throughput> throughput = {
        {"init", {"/rates/particles_per_s", "particles/s"}},
        {"sim", {"/particle_steps_per_second", "particle-steps/s"}},
        {"surface", {"/tets_per_second", "tets/s"}},
        {"render", {"/seconds_per_frame", "s/frame"}},
    };
    std::vector<StageSummary> rows;
    for (const char* stage : {"init", "sim", "surface", "render"}) {
        const fs::path dir = fs::path(out) / stage;
        std::error_code ec;
        if (!fs::is_regular_file(dir / "manifest.json", ec)) continue;
        const nlohmann::json m = read_manifest(dir);
        StageSummary r;
        r.stage = stage;
        r.dir = dir.string();
        if (m.contains("shot") && m["shot"].is_string()) r.shot = m["shot"].get<std::string>();
        for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
            if (!e.is_regular_file()) continue;
            ++r.files;
            r.bytes += e.file_size();
        }
        const double first = first_number(m, {"/frames/first"}),
                     last = first_number(m, {"/frames/last"});
        if (!std::isnan(first) && !std::isnan(last)) {
            r.first = int(first);
            r.last = int(last);
        }
        const double resumed = first_number(m, {"/resumed_from_frame"});
        if (!std::isnan(resumed)) r.resumed_from_frame = int(resumed);
        r.wall_seconds = first_number(m, {"/wall_seconds"});
        // render manifests written before 2026-11-25 name the peak peak_rss_bytes
        r.peak_memory_bytes = first_number(m, {"/peak_memory_bytes", "/peak_rss_bytes"});
        const Throughput& t = throughput.at(stage);
        r.rate = first_number(m, {t.pointer});
        r.rate_unit = t.unit;
        rows.push_back(std::move(r));
    }
    if (rows.empty()) throw InputError(out + ": no stage outputs (no <stage>/manifest.json)");
    return rows;
}

/// A number, or null when the manifest did not have it.
nlohmann::json number_or_null(double v) {
    return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
}
/// A byte count, or null when the manifest did not have it.
nlohmann::json bytes_or_null(double v) {
    return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(static_cast<std::int64_t>(v));
}
}  // namespace

int run_summary(const std::string& out, bool as_json) {
    const std::vector<StageSummary> rows = read_stage_summaries(out);
    if (as_json) {
        nlohmann::json doc = {{"out", out}, {"stages", nlohmann::json::array()}};
        for (const StageSummary& r : rows) {
            nlohmann::json j = {
                {"stage", r.stage},
                {"dir", r.dir},
                {"shot", r.shot.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.shot)},
                {"frames", r.last > 0 ? nlohmann::json{{"first", r.first}, {"last", r.last}}
                                      : nlohmann::json(nullptr)},
                {"resumed_from_frame", r.resumed_from_frame > 0
                                           ? nlohmann::json(r.resumed_from_frame)
                                           : nlohmann::json(nullptr)},
                {"wall_seconds", number_or_null(r.wall_seconds)},
                {"peak_memory_bytes", bytes_or_null(r.peak_memory_bytes)},
                {"throughput", {{"value", number_or_null(r.rate)}, {"unit", r.rate_unit}}},
                {"files", r.files},
                {"bytes", r.bytes}};
            doc["stages"].push_back(std::move(j));
        }
        std::cout << doc.dump(2) << "\n";
        return 0;
    }
    std::printf("%-8s %-12s %9s %26s %10s  %s\n", "stage", "frames", "wall [s]", "throughput",
                "peak MiB", "outputs");
    for (const StageSummary& r : rows) {
        // a resumed sim's wall time and throughput cover only the frames after its checkpoint
        std::string frames =
            r.last > 0 ? std::to_string(r.first) + "-" + std::to_string(r.last) : "-";
        if (r.resumed_from_frame > 0) frames += " from " + std::to_string(r.resumed_from_frame);
        const std::string rate = std::isnan(r.rate) ? "-" : number(r.rate) + " " + r.rate_unit;
        char outputs[64];
        std::snprintf(outputs, sizeof outputs, "%d files, %.1f MiB", r.files,
                      static_cast<double>(r.bytes) / 1048576.0);
        std::printf("%-8s %-12s %9.2f %26s %10.1f  %s in %s\n", r.stage.c_str(), frames.c_str(),
                    r.wall_seconds, rate.c_str(), r.peak_memory_bytes / 1048576.0, outputs,
                    r.dir.c_str());
    }
    return 0;
}

int run_verify(const std::string& manifest_file) {
    const std::filesystem::path path(manifest_file);
    std::ifstream is(path);
    if (!is) throw InputError(manifest_file + ": cannot read");
    const nlohmann::json manifest = nlohmann::json::parse(is, nullptr, /*allow_exceptions=*/false);
    if (!manifest.is_object())
        throw InputError(manifest_file + ": malformed manifest: expected a JSON object");
    const RecordedChecksums records(manifest, path);
    if (records.size() == 0)
        throw InputError(manifest_file + ": records no file checksums: nothing to verify");
    records.verify_all(path.parent_path().empty() ? std::filesystem::path(".")
                                                  : path.parent_path());
    std::cout << "ok: " << records.size() << " files verified against " << manifest_file << "\n";
    return 0;
}

}  // namespace mudcrack
