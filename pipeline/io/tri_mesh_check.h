#pragma once
/// The consistency every mesh writer needs before it trusts a TriMesh's arrays.
#include <filesystem>

#include "sim/core/tri_mesh.h"

namespace mudcrack {

/// Throws RuntimeError naming `file` and the mesh when an attribute array's size is neither 0
/// nor the vertex count, face_fragment is neither empty nor one per face, or a face names a
/// vertex that does not exist.
void check_tri_mesh(const std::filesystem::path& file, const TriMesh& mesh);

}  // namespace mudcrack
