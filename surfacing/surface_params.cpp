#include "surfacing/surface_params.h"

namespace mudcrack {

const char* surface_mode_name(SurfaceMode mode) {
    return mode == SurfaceMode::Ours ? "ours" : "wang2019";
}

}  // namespace mudcrack
