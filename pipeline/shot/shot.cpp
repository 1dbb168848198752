// Loading a shot: parse (comments allowed, duplicate keys refused), check against the spec
// table, build the typed parameters, check across keys, then cut the canonical tree into
// per-stage slices.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "pipeline/io/checksum.h"
#include "pipeline/shot/build.h"
#include "pipeline/shot/shot.h"
#include "pipeline/shot/shot_json.h"
#include "pipeline/shot/spec.h"
#include "pipeline/shot/validate.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

using nlohmann::json;

/// The shot format major version this build reads.
constexpr std::int64_t kFormatVersion = 1;

// `tree` is the checked tree: a missing or mistyped version was reported already
void check_version(const json& tree, spec::Issues& issues) {
    if (!tree.contains("mudcrack")) return;
    if (tree["mudcrack"].get<std::int64_t>() != kFormatVersion)
        issues.add("/mudcrack", issues.value_of(tree, "/mudcrack"),
                   "unsupported shot format major version; this build reads " +
                       std::to_string(kFormatVersion));
}

// the top-level pointers each stage reads, in addition to those of the stages before it
const std::vector<std::vector<std::string>>& stage_pointers() {
    static const std::vector<std::vector<std::string>> pointers = {
        {"/mudcrack", "/source", "/init", "/sim/h"},
        {"/material", "/plasticity", "/moisture", "/sim", "/frames", "/colliders",
         "/derived/cache"},
        {"/surfacing"},
        {"/render"},
    };
    return pointers;
}

std::string slice_text(const json& canonical, Stage stage) {
    json slice = json::object();
    for (int s = 0; s <= static_cast<int>(stage); ++s) {
        for (const std::string& pointer : stage_pointers()[s]) {
            const json::json_pointer p(pointer);
            if (canonical.contains(p)) slice[p] = canonical.at(p);
        }
    }
    // nlohmann's object is a std::map: keys come out sorted, so the text is canonical
    return slice.dump(2) + "\n";
}

// /derived/cache: each by-physics attribute as true or false, an on-request one only when cached
json cache_json(const CacheAttributes& c) {
    json out = json::object();
    for (size_t i = 0; i < kCachedAttributeCount; ++i) {
        if (kCachedAttributes[i].policy == CachePolicy::ByPhysics || c[i])
            out[kCachedAttributes[i].shot_key] = c[i];
    }
    return out;
}

}  // namespace

const std::string& Shot::slice(Stage stage) const {
    switch (stage) {
        case Stage::Init: return slice_init;
        case Stage::Sim: return slice_sim;
        case Stage::Surface: return slice_surface;
        case Stage::Render: return slice_render;
    }
    return slice_render;
}

std::string Shot::slice_hash(Stage stage) const {
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, fnv1a64_of(slice(stage)));
    return hex;
}

Shot parse_shot(const std::string& text, const std::string& path) {
    // every duplicate key, per-key and cross-key problem is collected, then reported in one
    // InputError
    spec::Issues issues(path);
    const json root = spec::read_shot_json(text, issues);
    issues.set_written(root);
    json tree = spec::check_and_fill(root, issues);
    if (!root.is_object()) issues.throw_if_any();  // nothing else can be checked
    check_version(tree, issues);

    Shot shot;
    shot.path = path;
    shot.name = tree.contains("name") ? tree["name"].get<std::string>()
                                      : std::filesystem::path(path).stem().string();
    shot.reuse = spec::build_reuse(tree, path, issues);
    shot.init = spec::build_init(tree, path, issues);
    shot.sim = spec::build_sim(tree, issues);
    shot.surface = spec::build_surface(tree, issues);
    if (shot.surface) shot.surface->cell_size = shot.sim.h;
    shot.render = spec::build_render(tree);
    shot.sim.cache = spec::derive_cache(tree, shot.sim, shot.surface, issues);
    spec::check_across(tree, shot.init, shot.sim, shot.render, issues);
    spec::check_plausible(tree, shot.init, shot.sim, shot.render, issues);
    issues.throw_if_any();
    spec::warn_doubtful(shot.sim, shot.surface, path);

    // derived values the stages depend on are part of the slices
    tree["derived"]["cache"] = cache_json(shot.sim.cache);
    shot.slice_init = slice_text(tree, Stage::Init);
    shot.slice_sim = slice_text(tree, Stage::Sim);
    shot.slice_surface = slice_text(tree, Stage::Surface);
    shot.slice_render = slice_text(tree, Stage::Render);
    return shot;
}

Shot load_shot(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open the shot file");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path + ": cannot read the shot file");
    return parse_shot(text.str(), path);
}

std::string spec_table_text() {
    struct Row {
        std::string pointer, type, def, range, units, doc;
    };
    std::vector<Row> rows = {{"POINTER", "TYPE", "DEFAULT", "RANGE", "UNITS", "DOC"}};
    for (const spec::KeySpec& key : spec::table())
        rows.push_back({key.pointer, spec::type_text(key), spec::default_text(key),
                        spec::range_text(key), key.units, key.doc});
    size_t widths[5] = {0, 0, 0, 0, 0};
    for (const Row& r : rows) {
        const std::string* cells[5] = {&r.pointer, &r.type, &r.def, &r.range, &r.units};
        for (int c = 0; c < 5; ++c) widths[c] = std::max(widths[c], cells[c]->size());
    }
    std::string out;
    for (const Row& r : rows) {
        const std::string* cells[5] = {&r.pointer, &r.type, &r.def, &r.range, &r.units};
        for (int c = 0; c < 5; ++c)
            out += *cells[c] + std::string(widths[c] - cells[c]->size() + 2, ' ');
        out += r.doc + "\n";
    }
    return out;
}

}  // namespace mudcrack
