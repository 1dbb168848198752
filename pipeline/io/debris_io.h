#pragma once
/// Debris point files (docs/physics.md §5.7): `debris.####.ply`, one vertex per grain that tore
/// loose, binary little-endian PLY with no faces, which Houdini's File SOP, Blender's add-on
/// (tools/blender) and any PLY reader load as points. Vertex properties, in this order:
///   float x y z       position [m]
///   float vx vy vz    velocity [m/s]
///   float pscale      radius [m] (Houdini's instancing scale attribute)
///   int id            particle id: the same grain in every frame
///   int piece         the piece it tore from (the boundary and crack meshes' fragment id), or -1
#include <filesystem>

#include "sim/core/debris_points.h"

namespace mudcrack {

/// Writes `debris` atomically (a temporary name, then rename). Throws RuntimeError naming the
/// file when the write fails.
void write_debris_ply(const std::filesystem::path& path, const DebrisPoints& debris);

/// Reads a file write_debris_ply wrote. Throws InputError naming the file when it is missing,
/// truncated or has another layout.
DebrisPoints read_debris_ply(const std::filesystem::path& path);

}  // namespace mudcrack
