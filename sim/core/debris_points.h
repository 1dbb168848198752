#pragma once
/// The particles that tore loose from the soil in the plates surfacing (docs/physics.md §5.7),
/// one entry each: what a TD instances pebbles on. Like TriMesh, a plain struct the surfacing
/// fills and pipeline/io writes (debris_io.h).
#include <cstdint>
#include <vector>

#include "sim/core/types.h"

namespace mudcrack {

struct DebrisPoints {
    std::vector<Vec3f> position;  // [m]
    std::vector<Vec3f> velocity;  // [m/s] (zero when the cache has none)
    std::vector<float> radius;    // [m] half the particle spacing, shrunk with Jw^(1/3) as it dried
    std::vector<int32_t> id;      // particle id: the same grain from frame to frame
    std::vector<int32_t> piece;   // the piece it tore from, or -1
    size_t size() const { return id.size(); }
};

}  // namespace mudcrack
