#include "pipeline/init/init_params.h"

namespace mudcrack {

const char* source_type_name(SourceType type) {
    switch (type) {
        case SourceType::Mesh: return "mesh";
        case SourceType::Box: return "box";
        case SourceType::Heightfield: return "heightfield";
    }
    return "?";
}

}  // namespace mudcrack
