#include "pipeline/io/mesh_io.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <map>
#include <system_error>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

namespace {

/// Welds vertices by exact (bitwise-equal after float->double) position, in first-seen order, so
/// the result does not depend on hashing or addresses.
class VertexWelder {
public:
    int32_t index_of(const Vec3& p) {
        const auto key = std::array<double, 3>{p.x(), p.y(), p.z()};
        auto [it, inserted] = m_index.emplace(key, static_cast<int32_t>(m_positions.size()));
        if (inserted) m_positions.push_back(p);
        return it->second;
    }
    std::vector<Vec3> take_positions() { return std::move(m_positions); }

private:
    std::map<std::array<double, 3>, int32_t> m_index;
    std::vector<Vec3> m_positions;
};

struct SurfaceBuilder {
    VertexWelder welder;
    std::vector<Tri> faces;
    std::vector<std::array<Vec2, 3>> face_uv;
    bool has_uv = false;
    size_t dropped_degenerate = 0;
};

// appends one assimp mesh, its vertices moved to world space by `world_from_mesh`
void append_mesh(const aiMesh& mesh, const aiMatrix4x4& world_from_mesh, SurfaceBuilder& out) {
    const aiVector3D* uv = mesh.HasTextureCoords(0) ? mesh.mTextureCoords[0] : nullptr;
    if (uv != nullptr && !out.has_uv) {
        // earlier meshes had no UVs: give their corners (0,0) so face_uv stays (n_faces)
        out.face_uv.assign(out.faces.size(), {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()});
        out.has_uv = true;
    }
    std::vector<Vec3> world(mesh.mNumVertices);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
        const aiVector3D p = world_from_mesh * mesh.mVertices[v];
        world[v] = Vec3(p.x, p.y, p.z);
    }
    // weld lazily, so vertices used by no kept triangle (points, lines) stay out of the surface
    std::vector<int32_t> welded(mesh.mNumVertices, -1);
    auto weld = [&](unsigned v) {
        if (welded[v] < 0) welded[v] = out.welder.index_of(world[v]);
        return welded[v];
    };
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
        const aiFace& face = mesh.mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines left by the triangulation
        const unsigned* c = face.mIndices;
        // a triangle whose corners weld together has no area and no orientation
        if (world[c[0]] == world[c[1]] || world[c[1]] == world[c[2]] || world[c[0]] == world[c[2]]) {
            ++out.dropped_degenerate;
            continue;
        }
        const Tri tri{weld(c[0]), weld(c[1]), weld(c[2])};
        out.faces.push_back(tri);
        if (out.has_uv) {
            std::array<Vec2, 3> corner_uv{Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};
            if (uv != nullptr) {
                for (int c = 0; c < 3; ++c) {
                    const aiVector3D& t = uv[face.mIndices[c]];
                    corner_uv[c] = Vec2(t.x, t.y);
                }
            }
            out.face_uv.push_back(corner_uv);
        }
    }
}

// depth-first over the node tree, composing parent transforms
void append_node(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                 SurfaceBuilder& out) {
    const aiMatrix4x4 world_from_node = parent * node.mTransformation;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) {
        append_mesh(*scene.mMeshes[node.mMeshes[i]], world_from_node, out);
    }
    for (unsigned i = 0; i < node.mNumChildren; ++i) {
        append_node(scene, *node.mChildren[i], world_from_node, out);
    }
}

}  // namespace

InputSurface load_input_surface(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw InputError(path.string() + ": mesh file not found (expected a readable OBJ, PLY, STL, "
                                         "OFF or glTF file)");
    }
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(
        path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
    if (scene == nullptr || scene->mRootNode == nullptr) {
        throw InputError(path.string() + ": cannot read the mesh: " + importer.GetErrorString());
    }
    SurfaceBuilder builder;
    append_node(*scene, *scene->mRootNode, aiMatrix4x4(), builder);
    if (builder.faces.empty()) {
        throw InputError(path.string() + ": the mesh has no triangles (" +
                         std::to_string(scene->mNumMeshes) + " meshes, " +
                         std::to_string(builder.dropped_degenerate) +
                         " degenerate triangles dropped); expected a triangle or polygon surface");
    }
    InputSurface surface;
    surface.positions = builder.welder.take_positions();
    surface.faces = std::move(builder.faces);
    surface.face_uv = std::move(builder.face_uv);
    return surface;
}

}  // namespace mudcrack
