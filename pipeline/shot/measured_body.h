#pragma once
/// The body of a mesh source against the shot's keys, once a stage has measured it. The loader
/// knows a box's and a heightfield's bounds and refuses /sim/h and /colliders/ground/height
/// against them (check_plausible); a mesh's bounds are known only once its file is read.
#include <string>

#include "pipeline/shot/shot.h"
#include "sim/core/types.h"

namespace mudcrack {

/// A body's axis-aligned bounds as a stage measured them, and on what.
struct MeasuredBody {
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // [m]
    std::string what;  // what was measured, for messages: "<mesh file> as placed by /source/mesh"
};

/// A mesh source's body: the bounds of its surface as /source/mesh scales and places it.
MeasuredBody placed_mesh_body(const std::string& mesh_path, const Vec3& lo, const Vec3& hi);

/// The refusals the loader makes against a box or a heightfield, made against `body`: /sim/h
/// larger than its thinnest side; /colliders/ground/height at or above its top, or further below
/// its bottom than the body moves in the shot. Throws InputError as "<shot file>: <key> = <value>:
/// <expectation>", naming the body's extent.
void check_measured_body(const Shot& shot, const MeasuredBody& body);

}  // namespace mudcrack
