#include "surfacing/surface_params.h"

#include <array>
#include <utility>

namespace mudcrack {
namespace {

constexpr std::array<std::pair<SurfaceMode, const char*>, 3> kModeNames = {
    {{SurfaceMode::Ours, "ours"},
     {SurfaceMode::Wang2019, "wang2019"},
     {SurfaceMode::Plates, "plates"}}};

}  // namespace

const char* surface_mode_name(SurfaceMode mode) {
    for (const auto& [m, name] : kModeNames)
        if (m == mode) return name;
    return "ours";
}

std::optional<SurfaceMode> parse_surface_mode(const std::string& name) {
    for (const auto& [m, text] : kModeNames)
        if (name == text) return m;
    return std::nullopt;
}

bool debris_needs_plates(const SurfaceParams& params) {
    return params.debris != DebrisOutput::None && params.mode != SurfaceMode::Plates;
}

std::vector<std::string> surface_mode_names() {
    std::vector<std::string> names;
    for (const auto& entry : kModeNames) names.emplace_back(entry.second);
    return names;
}

}  // namespace mudcrack
