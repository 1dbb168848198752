#pragma once
/// The init tet mesh on disk as VTK XML UnstructuredGrid (.vtu, ParaView opens it): tets (VTK
/// type 10) followed by the boundary triangles (type 5), raw appended binary. Point data "id";
/// cell data "uv" (6 floats: the three corner UVs of a boundary triangle; zero on tets) and
/// "kind" (0 tet, 1 boundary triangle).
#include <filesystem>

#include "sim/core/tet_mesh.h"

namespace mudcrack {

/// Atomic write (temporary name + rename).
void write_tet_mesh_vtu(const std::filesystem::path& path, const TetMesh& mesh);

/// Reads a file written by write_tet_mesh_vtu. Throws InputError naming the file on any problem.
TetMesh read_tet_mesh_vtu(const std::filesystem::path& path);

}  // namespace mudcrack
