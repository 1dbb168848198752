#pragma once
/// Triangle meshes through assimp: loading artists' input meshes (OBJ, PLY, STL, OFF, glTF, ...)
/// and exporting the surfacing's meshes with UVs (glb default, obj, ply, dae).
#include <filesystem>
#include <string>
#include <vector>

#include "sim/core/tri_mesh.h"
#include "sim/core/types.h"

namespace mudcrack {

/// An input surface, all of its meshes merged, vertices welded by exact position.
struct InputSurface {
    std::vector<Vec3> positions;               // [m]
    std::vector<Tri> faces;                    // triangles (polygons are triangulated)
    std::vector<std::array<Vec2, 3>> face_uv;  // per-corner UVs, (n_faces) or empty if none
};

/// Loads a triangle mesh with assimp. Throws InputError naming the file if it is missing,
/// unreadable, or has no triangles.
/// @note Node transforms are applied. Points, lines, and triangles with two corners at the same
/// position (zero area after welding) are dropped; vertices used by no kept triangle are left out.
InputSurface load_input_surface(const std::filesystem::path& path);

/// Why "fbx" is refused, for export_meshes and the shot's /surfacing/format alike.
constexpr const char* kFbxRefusal =
    "assimp 5.2.5 (Debian 12) writes binary FBX that no reader accepts, not even assimp itself "
    "(upstream bug assimp/assimp#4686, fixed after 5.2.5); use glb, obj, ply or dae";

/// The export formats: "glb", "obj", "ply", "dae". "fbx" is refused (kFbxRefusal).
bool is_supported_mesh_format(const std::string& format);
/// The export formats' names, in the order the shot spec lists them.
std::vector<std::string> mesh_format_names();
/// Why a format is not supported (empty when it is).
std::string mesh_format_refusal(const std::string& format);

/// Writes the meshes as one scene (one node/object per mesh, named by TriMesh::name), with
/// normals, UV channel 0, and saturation/alpha as vertex colors (r = saturation, g = alpha
/// remapped, b = 0) when present. Atomic. Throws InputError for an unsupported format.
/// @note g = 1 / (1 + exp(-alpha)) (vertex_color.h). Fragment ids travel in UV channel 1 as
/// (fragment id, 0); vertices shared by faces of different fragments are split first
/// (fragment_split.h). glb is written by glb_writer.h, streamed, in memory bounded by a small
/// buffer; obj, ply and dae go through assimp's exporters, which hold the whole file and a
/// copy of the scene in memory. ply holds one merged mesh without colours (assimp 5.2.5's PLY
/// exporter corrupts files with colours); obj carries no fragment ids. obj gets `o <name>`
/// lines for Blender 3.4; dae timestamps are fixed to 1970-01-01 so identical meshes give
/// identical bytes.
void export_meshes(const std::filesystem::path& path, const std::vector<TriMesh>& meshes,
                   const std::string& format);

/// The material file an obj mesh comes with, <stem>.mtl beside it (export_meshes writes it, and
/// every obj reader loads it with the mesh); an empty path for the other formats.
std::filesystem::path mesh_material_file(const std::filesystem::path& mesh_file);

/// Reads a file written by export_meshes back (tests, the renderer): one TriMesh per mesh in
/// the file, with positions, normals, UVs and faces as stored (plus saturation/alpha from the
/// colours and face_fragment from UV channel 1 when present). Throws InputError naming the file.
std::vector<TriMesh> import_meshes(const std::filesystem::path& path);

}  // namespace mudcrack
