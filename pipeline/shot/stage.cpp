#include "pipeline/shot/shot.h"

namespace mudcrack {

const char* stage_name(Stage stage) {
    switch (stage) {
        case Stage::Init: return "init";
        case Stage::Sim: return "sim";
        case Stage::Surface: return "surface";
        case Stage::Render: return "render";
    }
    return "?";
}

}  // namespace mudcrack
