#include "pipeline/io/mesh_io.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <regex>
#include <sstream>
#include <system_error>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/fragment_split.h"
#include "pipeline/io/glb_writer.h"
#include "pipeline/io/ply_lists.h"
#include "pipeline/io/tri_mesh_check.h"
#include "pipeline/io/vertex_color.h"
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
        if (world[c[0]] == world[c[1]] || world[c[1]] == world[c[2]] ||
            world[c[0]] == world[c[2]]) {
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

std::string lowercase_extension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

// OBJ and OFF are text. assimp 5.2.5 stops reading at a NUL byte and then aborts on its own
// assertion (a face count that no longer matches; found by tests/fuzz), so one is refused here.
void check_text_mesh(const fs::path& path) {
    const std::string ext = lowercase_extension(path);
    if (ext != ".obj" && ext != ".off") return;
    std::ifstream is(path, std::ios::binary);
    char buffer[65536];
    uint64_t offset = 0;
    while (is.read(buffer, sizeof buffer) || is.gcount() > 0) {
        const std::streamsize n = is.gcount();
        const char* nul = static_cast<const char*>(std::memchr(buffer, '\0', size_t(n)));
        if (nul)
            throw InputError(path.string() + ": byte " +
                             std::to_string(offset + uint64_t(nul - buffer)) + " is NUL: an " +
                             ext.substr(1) + " file is text (damaged or not a mesh?)");
        offset += uint64_t(n);
    }
}

// A NaN or infinite coordinate ("v nan 0 0", "1e999") would be reported further on as a
// degenerate or self-intersecting face, the vertex never named: it is refused first, with its
// index. An OBJ is read here, so the index is the file's own (1-based, as OBJ faces count);
// assimp numbers the vertices of other formats as it read them (mesh_vertices_finite below).
void check_obj_vertices_finite(const fs::path& path) {
    if (lowercase_extension(path) != ".obj") return;
    std::ifstream is(path, std::ios::binary);
    std::string line;
    int64_t vertex = 0, line_number = 0;
    while (std::getline(is, line)) {
        ++line_number;
        if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
        ++vertex;
        std::istringstream fields(line.substr(2));
        std::string word;
        for (int k = 0; k < 3 && fields >> word; ++k)
            if (!std::isfinite(std::strtod(word.c_str(), nullptr)))
                throw InputError(path.string() + ": vertex " + std::to_string(vertex) + " (line " +
                                 std::to_string(line_number) + ") has coordinate " +
                                 word.substr(0, 40) + ": not finite; expected finite numbers");
    }
}

void check_mesh_vertices_finite(const fs::path& path, const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        const aiMesh& mesh = *scene.mMeshes[m];
        for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
            const aiVector3D& v = mesh.mVertices[i];
            if (std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) continue;
            std::ostringstream where;
            where << "vertex " << i
                  << (scene.mNumMeshes > 1 ? " of mesh " + std::to_string(m) : std::string())
                  << " (0-based, as read) is (" << v.x << ", " << v.y << ", " << v.z << ")";
            throw InputError(path.string() + ": " + where.str() +
                             ": not finite; expected finite numbers");
        }
    }
}

// assimp 5.2.5 allocates what an OFF header's counts ask for (found by tests/fuzz: a face count
// of 10^28 asked for 14 GB): counts are checked against the file's size first, every vertex and
// face taking at least one byte.
void check_off_header(const fs::path& path) {
    const std::string ext = lowercase_extension(path);
    if (ext != ".off") return;
    std::ifstream is(path, std::ios::binary);
    std::string word;
    std::vector<std::string> counts;
    bool first = true;
    while (counts.size() < 2 && is >> word) {
        if (word[0] == '#') {
            std::string rest;
            std::getline(is, rest);
            continue;
        }
        const bool magic =
            first && word.size() >= 3 && word.compare(word.size() - 3, 3, "OFF") == 0;
        first = false;
        if (!magic) counts.push_back(word);  // the first word may be OFF, COFF, NOFF, ...
    }
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    uint64_t total = 0;
    for (const std::string& c : counts) {
        if (c.empty() || c.size() > 12 || c.find_first_not_of("0123456789") != std::string::npos)
            throw InputError(path.string() + ": OFF header count '" + c.substr(0, 40) +
                             "': expected a vertex and a face count (whole numbers)");
        total += std::stoull(c);
    }
    if (!ec && total > size)
        throw InputError(path.string() + ": OFF header declares " + std::to_string(total) +
                         " vertices and faces, more than the file's " + std::to_string(size) +
                         " bytes can hold");
}

// assimp 5.2.5's PLY reader runs past its buffer on a header without end_header or a binary body
// shorter than its header declares, and sizes a list by whatever count the body states (found by
// tests/fuzz): the header, then the body's list counts, are checked here first.
void check_ply_header(const fs::path& path) {
    std::ifstream is(path, std::ios::binary);
    std::string line;
    // assimp takes "ply" in any case as the magic (a "pLy" file without end_header hung its reader)
    const auto is_ply_magic = [](const std::string& first) {
        return first.size() >= 3 && std::tolower(static_cast<unsigned char>(first[0])) == 'p' &&
               std::tolower(static_cast<unsigned char>(first[1])) == 'l' &&
               std::tolower(static_cast<unsigned char>(first[2])) == 'y';
    };
    if (!std::getline(is, line) || !is_ply_magic(line)) return;  // not PLY: assimp decides
    const auto fail = [&](const std::string& why) {
        throw InputError(path.string() + ": malformed PLY header: " + why);
    };
    std::string format;
    uint64_t min_body = 0, element_count = 0;
    uint64_t count = 0;
    bool ended = false;
    std::vector<PlyElement> elements;
    for (int n = 0; n < 100000 && std::getline(is, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::string key;
        words >> key;
        if (key == "end_header") {
            ended = true;
            break;
        }
        if (key == "format") {
            words >> format;
        } else if (key == "element") {
            std::string name, number;
            words >> name >> number;
            if (number.empty() || number.size() > 10 ||
                number.find_first_not_of("0123456789") != std::string::npos)
                fail("element '" + name + "' count '" + number + "': expected a count below 10^10");
            count = std::stoull(number);
            element_count += count;
            elements.push_back(PlyElement{name, count, {}});
        } else if (key == "property") {
            std::string type;
            words >> type;
            size_t size = 0;
            if (type == "list") {
                std::string count_type, item_type;
                words >> count_type >> item_type;
                size = ply_type(count_type).bytes;
                if (size == 0 || ply_type(item_type).bytes == 0)
                    fail("property list " + count_type + " " + item_type + ": unknown type");
                if (!elements.empty())
                    elements.back().properties.push_back(PlyProperty{true, count_type, item_type});
            } else {
                size = ply_type(type).bytes;
                if (size == 0) fail("property type '" + type + "': unknown type");
                if (!elements.empty())
                    elements.back().properties.push_back(PlyProperty{false, "", type});
            }
            min_body += count * size;
        } else if (key != "comment" && key != "obj_info" && !key.empty()) {
            // assimp skips a line it does not know and misreads the body after it (an abort in
            // its triangulation, found by tests/fuzz)
            fail("line '" + line.substr(0, 60) +
                 "': expected format, element, property, comment, obj_info or end_header");
        }
    }
    if (!ended) fail("no end_header line");
    if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        fail("format '" + format + "': expected ascii, binary_little_endian or binary_big_endian");
    const std::streamoff body_start = is.tellg();
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    const uint64_t body = ec || body_start < 0 ? 0 : size - uint64_t(body_start);
    // ascii: every element takes at least one byte of text
    const uint64_t needed = format == "ascii" ? element_count : min_body;
    if (body < needed)
        fail("the header declares " + std::to_string(element_count) +
             " elements needing at least " + std::to_string(needed) + " bytes, the file holds " +
             std::to_string(body) +
             " after the header "
             "(truncated?)");
    check_ply_list_counts(path, uint64_t(body_start), format, elements);
}

// assimp 5.2.5's triangulation asserts (an abort, not an error) that a mesh flagged as holding
// polygons holds at least one face of more than 3 corners; a damaged PLY face list (a face of 0
// corners, which its validation lets through) leaves a mesh that breaks that (found by
// tests/fuzz). The scene is checked here between reading and triangulating.
void check_polygon_flags(const fs::path& path, const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        const aiMesh& mesh = *scene.mMeshes[m];
        if ((mesh.mPrimitiveTypes & aiPrimitiveType_POLYGON) == 0) continue;
        unsigned polygons = 0, empty = 0;
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            polygons += mesh.mFaces[f].mNumIndices > 3 ? 1 : 0;
            empty += mesh.mFaces[f].mNumIndices == 0 ? 1 : 0;
        }
        if (polygons == 0)
            throw InputError(path.string() + ": cannot read the mesh: mesh " + std::to_string(m) +
                             " is declared to hold polygons but its " +
                             std::to_string(mesh.mNumFaces) + " faces (" + std::to_string(empty) +
                             " with no corner) have at most 3 corners each (damaged file?)");
    }
}

// an importer that reads a file's meshes only: assimp's COLLADA reader otherwise makes a scene
// without meshes (an empty dae) one of pyramids drawing its node tree, which would read as soil
void read_meshes_only(Assimp::Importer& importer) {
    importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
}

}  // namespace

InputSurface load_input_surface(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw InputError(path.string() +
                         ": mesh file not found (expected a readable OBJ, PLY, STL, "
                         "OFF or glTF file)");
    }
    check_ply_header(path);
    check_text_mesh(path);
    check_obj_vertices_finite(path);
    check_off_header(path);
    Assimp::Importer importer;
    read_meshes_only(importer);
    // ValidateDataStructure runs before the other steps: assimp 5.2.5's readers can leave faces
    // whose indices leave the mesh or whose sizes contradict the mesh's primitive types, and its
    // triangulation then reads out of bounds or aborts (found by tests/fuzz); validated, such a
    // file is refused with assimp's reason. Validation alone does not catch every such
    // file, so read and validate first, check what the triangulation assumes, then post-process
    // (the same steps in the same order as one ReadFile with all three flags)
    const aiScene* scene = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure);
    if (scene == nullptr || scene->mRootNode == nullptr) {
        throw InputError(path.string() + ": cannot read the mesh: " + importer.GetErrorString());
    }
    check_mesh_vertices_finite(path, *scene);
    check_polygon_flags(path, *scene);
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
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

// ---- export / import of the surfacing's meshes ----

namespace mudcrack {

namespace {

struct MeshFormat {
    const char* name;       // what the shot and the CLI say
    const char* assimp_id;  // Assimp::Exporter format id; nullptr: glb_writer
};
constexpr MeshFormat kMeshFormats[] = {
    {"glb", nullptr}, {"obj", "obj"}, {"ply", "plyb"}, {"dae", "collada"}};

const MeshFormat* find_format(const std::string& format) {
    for (const MeshFormat& f : kMeshFormats)
        if (format == f.name) return &f;
    return nullptr;
}

aiVector3D to_ai(const Vec3f& v) { return aiVector3D(v.x(), v.y(), v.z()); }

aiMesh* make_ai_mesh(const fs::path& path, const TriMesh& mesh, unsigned material) {
    check_tri_mesh(path, mesh);
    const FragmentSplit split(mesh);
    const size_t n = size_t(split.vertex_count());
    auto* m = new aiMesh;
    m->mName = mesh.name;
    m->mMaterialIndex = material;
    m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m->mNumVertices = unsigned(n);
    m->mVertices = new aiVector3D[n];
    for (size_t i = 0; i < n; ++i) m->mVertices[i] = to_ai(mesh.positions[split.source(i)]);
    if (!mesh.normals.empty()) {
        m->mNormals = new aiVector3D[n];
        for (size_t i = 0; i < n; ++i) m->mNormals[i] = to_ai(mesh.normals[split.source(i)]);
    }
    // assimp's exporters stop at the first empty UV channel: a fragment channel gets a channel 0
    // of zeros when there are no UVs
    if (!mesh.uvs.empty() || split.has_fragments()) {
        m->mNumUVComponents[0] = 2;
        m->mTextureCoords[0] = new aiVector3D[n];
        for (size_t i = 0; i < n; ++i) {
            const Vec2f uv = mesh.uvs.empty() ? Vec2f::Zero() : mesh.uvs[split.source(i)];
            m->mTextureCoords[0][i] = aiVector3D(uv.x(), uv.y(), 0);
        }
    }
    if (!mesh.saturation.empty() || !mesh.alpha.empty()) {
        m->mColors[0] = new aiColor4D[n];
        for (size_t i = 0; i < n; ++i) {
            const int32_t v = split.source(i);
            const float s = mesh.saturation.empty() ? 0.f : mesh.saturation[v];
            const float g = alpha_to_color(mesh.alpha.empty() ? 0.f : mesh.alpha[v]);
            m->mColors[0][i] = aiColor4D(s, g, 0.f, 1.f);
        }
    }
    if (split.has_fragments()) {
        // UV channel 1 = (fragment id, 0): exact in float for ids below 2^24
        m->mNumUVComponents[1] = 2;
        m->mTextureCoords[1] = new aiVector3D[n];
        for (size_t i = 0; i < n; ++i)
            m->mTextureCoords[1][i] = aiVector3D(float(split.fragment(i)), 0, 0);
    }
    m->mNumFaces = unsigned(mesh.faces.size());
    m->mFaces = new aiFace[mesh.faces.size()];
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
        const Tri t = split.face(mesh, f);
        aiFace& face = m->mFaces[f];
        face.mNumIndices = 3;
        face.mIndices = new unsigned[3]{unsigned(t[0]), unsigned(t[1]), unsigned(t[2])};
    }
    return m;
}

/// One node per mesh under a root, one plain soil-coloured material per mesh.
std::unique_ptr<aiScene> make_scene(const fs::path& path, const std::vector<TriMesh>& meshes) {
    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = new aiNode("root");
    const unsigned count = unsigned(meshes.size());
    scene->mNumMeshes = count;
    scene->mMeshes = new aiMesh*[count]();
    scene->mNumMaterials = count;
    scene->mMaterials = new aiMaterial*[count]();
    scene->mRootNode->mNumChildren = count;
    scene->mRootNode->mChildren = new aiNode*[count]();
    for (unsigned i = 0; i < count; ++i) {
        auto* material = new aiMaterial;
        const aiString material_name(meshes[i].name + "_material");
        material->AddProperty(&material_name, AI_MATKEY_NAME);
        const aiColor4D soil(0.55f, 0.42f, 0.30f, 1.f);
        material->AddProperty(&soil, 1, AI_MATKEY_COLOR_DIFFUSE);
        scene->mMaterials[i] = material;
        scene->mMeshes[i] = make_ai_mesh(path, meshes[i], i);
        auto* node = new aiNode(meshes[i].name);
        node->mParent = scene->mRootNode;
        node->mNumMeshes = 1;
        node->mMeshes = new unsigned[1]{i};
        scene->mRootNode->mChildren[i] = node;
    }
    return scene;
}

std::string blob_text(const aiExportDataBlob& blob) {
    return std::string(static_cast<const char*>(blob.data), blob.size);
}

// makes the exporters' output depend on the meshes only, and readable by the DCCs we target
std::string post_process(const std::string& format, std::string bytes) {
    if (format == "dae") {
        // the COLLADA exporter stamps <created>/<modified> with the wall clock
        static const std::regex created("<created>[^<]*</created>"),
            modified("<modified>[^<]*</modified>");
        bytes = std::regex_replace(bytes, created, "<created>1970-01-01T00:00:00</created>");
        bytes = std::regex_replace(bytes, modified, "<modified>1970-01-01T00:00:00</modified>");
    } else if (format == "obj") {
        // Blender 3.4's OBJ importer splits objects on `o` lines, while assimp writes `g` groups
        std::string out;
        size_t begin = 0;
        while (begin < bytes.size()) {
            size_t end = bytes.find('\n', begin);
            end = end == std::string::npos ? bytes.size() : end + 1;
            if (bytes.compare(begin, 2, "g ") == 0)
                out += "o " + bytes.substr(begin + 2, end - begin - 2);
            out.append(bytes, begin, end - begin);
            begin = end;
        }
        bytes = std::move(out);
    }
    return bytes;
}

bool has_faces(const std::vector<TriMesh>& meshes) {
    return std::any_of(meshes.begin(), meshes.end(),
                       [](const TriMesh& m) { return !m.faces.empty(); });
}

// PLY with no vertex and no face, in the binary layout assimp writes: assimp 5.2.5's PLY exporter
// refuses a scene without faces (with no reason given), where glb and obj write an empty file
std::string empty_ply_text() {
    return "ply\nformat binary_little_endian 1.0\ncomment mudcrack: no faces\n"
           "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 0\nproperty list uchar int vertex_index\nend_header\n";
}

// a PLY file whose header declares every element with a count of 0 (empty_ply_text, or another
// writer's empty mesh): assimp 5.2.5's reader refuses it ("Unable to extract mesh data")
bool is_empty_ply(const fs::path& path) {
    std::ifstream is(path, std::ios::binary);
    std::string line;
    if (!std::getline(is, line) || line != "ply") return false;
    constexpr int kMaxHeaderLines = 1000;  // a header is a few dozen lines; a damaged one any
    for (int n = 0; n < kMaxHeaderLines && std::getline(is, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line == "end_header") return true;
        std::istringstream words(line);
        std::string key, name, count;
        words >> key >> name >> count;
        if (key == "element" && count != "0") return false;
    }
    return false;
}

}  // namespace

bool is_supported_mesh_format(const std::string& format) { return find_format(format) != nullptr; }

std::vector<std::string> mesh_format_names() {
    std::vector<std::string> names;
    for (const MeshFormat& f : kMeshFormats) names.emplace_back(f.name);
    return names;
}

std::string mesh_format_refusal(const std::string& format) {
    if (is_supported_mesh_format(format)) return "";
    if (format == "fbx") return std::string("fbx is not supported: ") + kFbxRefusal;
    return "unknown mesh format '" + format + "': expected glb, obj, ply or dae";
}

void export_meshes(const fs::path& path, const std::vector<TriMesh>& meshes,
                   const std::string& format) {
    const MeshFormat* f = find_format(format);
    if (f == nullptr) throw InputError(path.string() + ": " + mesh_format_refusal(format));
    if (f->assimp_id == nullptr) return write_glb(path, meshes);
    if (format == "ply" && !has_faces(meshes)) return write_text_atomically(path, empty_ply_text());
    // assimp 5.2.5's PLY exporter declares vertex colours as uchar but writes four floats, which
    // corrupts every face after them (no reader, assimp included, gets the faces back): PLY files
    // carry no colours
    std::vector<TriMesh> stripped;
    if (format == "ply") {
        stripped = meshes;
        for (TriMesh& m : stripped) {
            m.saturation.clear();
            m.alpha.clear();
        }
    }
    const auto scene = make_scene(path, format == "ply" ? stripped : meshes);
    Assimp::Exporter exporter;
    Assimp::ExportProperties properties;
    // obj: "mtllib <stem>.mtl"
    properties.SetPropertyString(AI_CONFIG_EXPORT_BLOB_NAME, path.stem().string());
    const aiExportDataBlob* blob =
        exporter.ExportToBlob(scene.get(), f->assimp_id, 0u, &properties);
    if (blob == nullptr) {
        throw RuntimeError(path.string() + ": assimp could not export " + format + ": " +
                           exporter.GetErrorString());
    }
    // side files first (obj's .mtl), then the main file, so the main file never points at nothing.
    // assimp names side blobs "<blob name up to its first dot>.<ext>" ("boundary.mtl" for
    // "boundary.0001.obj"), so frames would share one side file and race when written in
    // parallel: each side file is named after the main file instead, and references follow.
    std::string main_text = post_process(format, blob_text(*blob));
    for (const aiExportDataBlob* side = blob->next; side != nullptr; side = side->next) {
        const std::string side_name = side->name.C_Str();
        const std::string ext = side_name.find('.') != std::string::npos
                                    ? side_name.substr(side_name.rfind('.') + 1)
                                    : side_name;
        fs::path side_path = path;
        side_path.replace_extension(ext);
        const std::string own_name = side_path.filename().string();
        if (side_name.find('.') != std::string::npos && side_name != own_name) {
            for (size_t at = main_text.find(side_name); at != std::string::npos;
                 at = main_text.find(side_name, at + own_name.size()))
                main_text.replace(at, side_name.size(), own_name);
        }
        write_text_atomically(side_path, blob_text(*side));
    }
    write_text_atomically(path, main_text);
}

fs::path mesh_material_file(const fs::path& mesh_file) {
    if (mesh_file.extension() != ".obj") return {};
    fs::path material = mesh_file;
    material.replace_extension(".mtl");
    return material;
}

std::vector<TriMesh> import_meshes(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": mesh file not found");
    // assimp's OBJ, PLY and COLLADA readers make one vertex per face corner; corners are joined
    // back below by exact equality of every attribute (assimp 5.2.5's own join compares only
    // position, normal and UV 0, which would merge vertices told apart by colour or fragment).
    // glTF stores indexed vertices, which assimp keeps: a glb comes back vertex for vertex.
    const std::string ext = lowercase_extension(path);
    // no mesh, as an empty glb gives
    if (ext == ".ply" && is_empty_ply(path)) return {};
    const bool join_corners = ext != ".glb" && ext != ".gltf";
    Assimp::Importer importer;
    read_meshes_only(importer);
    const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate);
    if (scene == nullptr || scene->mRootNode == nullptr) {
        throw InputError(path.string() + ": cannot read the mesh: " + importer.GetErrorString());
    }
    std::vector<TriMesh> meshes;
    // depth-first over the nodes, so meshes come back in the order they were written
    std::function<void(const aiNode&, const aiMatrix4x4&)> visit = [&](const aiNode& node,
                                                                       const aiMatrix4x4& parent) {
        const aiMatrix4x4 world_from_node = parent * node.mTransformation;
        const aiMatrix3x3 normal_matrix = aiMatrix3x3(world_from_node).Inverse().Transpose();
        for (unsigned k = 0; k < node.mNumMeshes; ++k) {
            const aiMesh& m = *scene->mMeshes[node.mMeshes[k]];
            TriMesh corners;  // one vertex per assimp vertex
            corners.name = node.mName.length > 0 ? node.mName.C_Str() : m.mName.C_Str();
            // every attribute of each vertex, for joining (only where corners are joined)
            std::vector<std::array<float, 13>> keys(join_corners ? m.mNumVertices : 0);
            for (unsigned v = 0; v < m.mNumVertices; ++v) {
                const aiVector3D p = world_from_node * m.mVertices[v];
                corners.positions.emplace_back(p.x, p.y, p.z);
                std::array<float, 13> key{};
                key[0] = p.x, key[1] = p.y, key[2] = p.z;
                if (m.HasNormals()) {
                    aiVector3D nrm = normal_matrix * m.mNormals[v];
                    nrm.NormalizeSafe();
                    corners.normals.emplace_back(nrm.x, nrm.y, nrm.z);
                    key[3] = nrm.x, key[4] = nrm.y, key[5] = nrm.z;
                }
                if (m.HasTextureCoords(0)) {
                    corners.uvs.emplace_back(m.mTextureCoords[0][v].x, m.mTextureCoords[0][v].y);
                    key[6] = m.mTextureCoords[0][v].x, key[7] = m.mTextureCoords[0][v].y;
                }
                if (m.HasVertexColors(0)) {
                    const aiColor4D& c = m.mColors[0][v];
                    corners.saturation.push_back(c.r);
                    corners.alpha.push_back(color_to_alpha(c.g));
                    key[8] = c.r, key[9] = c.g, key[10] = c.b, key[11] = c.a;
                }
                if (m.HasTextureCoords(1)) key[12] = m.mTextureCoords[1][v].x;
                if (join_corners) keys[v] = key;
            }
            std::vector<int32_t> index_of(m.mNumVertices);
            TriMesh out;
            if (!join_corners) {
                std::iota(index_of.begin(), index_of.end(), 0);
                out = std::move(corners);
            } else {
                // join corners with identical attributes, in first-seen order
                std::map<std::array<float, 13>, int32_t> joined;
                out.name = corners.name;
                for (unsigned v = 0; v < m.mNumVertices; ++v) {
                    auto [it, inserted] = joined.emplace(keys[v], int32_t(out.positions.size()));
                    index_of[v] = it->second;
                    if (!inserted) continue;
                    out.positions.push_back(corners.positions[v]);
                    if (!corners.normals.empty()) out.normals.push_back(corners.normals[v]);
                    if (!corners.uvs.empty()) out.uvs.push_back(corners.uvs[v]);
                    if (!corners.saturation.empty())
                        out.saturation.push_back(corners.saturation[v]);
                    if (!corners.alpha.empty()) out.alpha.push_back(corners.alpha[v]);
                }
            }
            for (unsigned f = 0; f < m.mNumFaces; ++f) {
                const aiFace& face = m.mFaces[f];
                if (face.mNumIndices != 3) continue;
                const unsigned* c = face.mIndices;
                out.faces.push_back({index_of[c[0]], index_of[c[1]], index_of[c[2]]});
                if (m.HasTextureCoords(1))
                    out.face_fragment.push_back(int32_t(std::lround(m.mTextureCoords[1][c[0]].x)));
            }
            meshes.push_back(std::move(out));
        }
        for (unsigned c = 0; c < node.mNumChildren; ++c) visit(*node.mChildren[c], world_from_node);
    };
    visit(*scene->mRootNode, aiMatrix4x4());
    return meshes;
}

}  // namespace mudcrack
