#include "render/render_params.h"

namespace mudcrack {

const char* color_mode_name(ColorMode mode) {
    switch (mode) {
        case ColorMode::Moisture: return "moisture";
        case ColorMode::Hardening: return "hardening";
        case ColorMode::Plain: return "plain";
    }
    return "?";
}

}  // namespace mudcrack
