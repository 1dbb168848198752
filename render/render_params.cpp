#include "render/render_params.h"

#include <array>
#include <cctype>
#include <utility>

namespace mudcrack {
namespace {

constexpr std::array<std::pair<ColorMode, const char*>, 3> kColorModes = {
    {{ColorMode::Moisture, "moisture"},
     {ColorMode::Hardening, "hardening"},
     {ColorMode::Plain, "plain"}}};

}  // namespace

const char* color_mode_name(ColorMode mode) {
    for (const auto& [m, name] : kColorModes)
        if (m == mode) return name;
    return "?";
}

std::optional<ColorMode> parse_color_mode(const std::string& name) {
    for (const auto& [m, text] : kColorModes)
        if (name == text) return m;
    return std::nullopt;
}

std::vector<std::string> color_mode_names() {
    std::vector<std::string> names;
    for (const auto& entry : kColorModes) names.emplace_back(entry.second);
    return names;
}

std::string color_mode_glsl_defines() {
    std::string lines;
    for (const auto& [m, name] : kColorModes) {
        std::string upper = name;
        for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
        lines +=
            "#define MC_COLOR_MODE_" + upper + " " + std::to_string(static_cast<int>(m)) + "\n";
    }
    return lines;
}

}  // namespace mudcrack
