#pragma once
/// Binary glTF 2.0 (.glb) of the surfacing's meshes, streamed from the TriMeshes to the file.
///
/// Why not assimp's glb2 exporter: it copies the scene, expands it to one vertex per face corner
/// and joins the corners back (Assimp::Exporter enforces aiProcess_JoinIdenticalVertices for
/// glb2), and builds the file in memory, about 1 KB per triangle at peak; the join also merges
/// vertices that differ only in colour or fragment id. Nor tinygltf (Debian's 2.7.0): its writer
/// copies the whole binary buffer once more before writing. A .glb is a 12-byte header, a JSON
/// chunk and a binary chunk, so this writer sizes every array first, writes the JSON, then
/// streams each attribute through a small buffer: its memory is that buffer plus the fragment
/// split's copies (none for the surfacing's meshes), never a copy of the mesh.
#include <filesystem>
#include <vector>

#include "sim/core/tri_mesh.h"

namespace mudcrack {

/// Writes the meshes as one glb scene, atomically: a root node with one child node per mesh
/// (named by TriMesh::name) and one soil-coloured material per mesh. Attributes, all float32:
/// POSITION (with min/max), NORMAL, TEXCOORD_0 (v flipped to glTF's v-down), TEXCOORD_1 =
/// (fragment id, 1 - 0) when face_fragment is set (vertices shared by faces of different
/// fragments are split first), COLOR_0 = (saturation, logistic(alpha), 0, 1) when either is set;
/// uint32 indices. A mesh without faces gets its node but no mesh (glTF has no empty mesh).
/// Throws RuntimeError naming the file when attribute sizes disagree, a face names a missing
/// vertex, the file would pass glb's 4 GiB limit, or the write fails.
void write_glb(const std::filesystem::path& path, const std::vector<TriMesh>& meshes);

}  // namespace mudcrack
