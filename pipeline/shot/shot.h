#pragma once
/// A validated shot (docs/architecture.md §4): the typed parameters of every stage, built from one
/// JSON file by the spec table in spec.cpp. Past pipeline/shot no code touches JSON.
#include <optional>
#include <string>
#include <vector>

#include "pipeline/init/init_params.h"
#include "render/render_params.h"
#include "sim/model.h"
#include "surfacing/surface_params.h"

namespace mudcrack {

enum class Stage { Init, Sim, Surface, Render };
const char* stage_name(Stage stage);  // "init", "sim", "surface", "render"

struct Shot {
    std::string path;   // the shot file as given
    std::string name;   // /name, default: the file's stem
    std::string reuse;  // /reuse: a shot of this folder whose matching stages make shares, or ""
    InitParams init;    // /source, /init
    SimModel sim;       // /material, /plasticity, /moisture, /sim, /frames, /colliders
    std::optional<SurfaceParams> surface;  // /surfacing; nullopt: no surfacing stage
    std::optional<RenderParams> render;    // /render; nullopt: no render stage
    /// Canonical JSON (defaults filled in) of the keys each stage reads, including those of the
    /// stages before it; its hash goes in the manifest and `mc-shot slice` writes it for make.
    std::string slice_init, slice_sim, slice_surface, slice_render;
    const std::string& slice(Stage stage) const;
    /// Hex digest of slice(stage).
    std::string slice_hash(Stage stage) const;
};

/// Loads, fills defaults, and validates a shot. Throws InputError listing ALL problems, one per
/// line, each as "<file>: <json pointer> = <value>: <expectation>".
Shot load_shot(const std::string& path);

/// Same, from text (tests); `path` names it in messages and resolves relative paths.
Shot parse_shot(const std::string& text, const std::string& path);

/// The documented spec as a table (pointer, type, default, range, units, doc), for `mc-shot keys`.
std::string spec_table_text();

}  // namespace mudcrack
