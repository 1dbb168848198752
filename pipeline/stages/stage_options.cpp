#include "pipeline/stages/stage_options.h"

#include "sim/core/error.h"

namespace mudcrack {

FrameRange frames_to_process(const StageOptions& options, const FrameRange& available,
                             const std::string& where) {
    if (!options.frame_range.is_set()) return available;
    const FrameRange& asked = options.frame_range;
    if (asked.first < available.first || asked.last > available.last)
        throw UsageError("--frames " + options.frames + ": outside the frames " +
                         std::to_string(available.first) + "-" + std::to_string(available.last) +
                         " of " + where);
    return asked;
}

}  // namespace mudcrack
