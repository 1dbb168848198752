#include "pipeline/io/glb_writer.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/io/atomic_output.h"
#include "pipeline/io/fragment_split.h"
#include "pipeline/io/tri_mesh_check.h"
#include "pipeline/io/vertex_color.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace mudcrack {
namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

/// One typed array of the binary chunk: `count` elements of `width` 4-byte components (float or
/// uint32), element i written by fill(i, out) when the chunk is streamed.
struct Stream {
    int64_t count = 0;
    int width = 0;
    std::function<void(int64_t i, unsigned char* out)> fill;
    int64_t bytes() const { return count * width * 4; }
};

/// Stores 4-byte values at `out` (memcpy: the buffer is bytes, the values floats or uint32).
template <class T, size_t N>
void store(unsigned char* out, const std::array<T, N>& values) {
    static_assert(sizeof(T) == 4, "glb components are 4 bytes");
    std::memcpy(out, values.data(), sizeof(T) * N);
}

void put_u32(std::ostream& os, uint32_t v) {
    const unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    os.write(reinterpret_cast<const char*>(b), 4);
}

/// Writes the stream's elements as 4-byte little-endian values (glb's order, and the machine's:
/// checked in write_glb) through a fixed buffer.
void write_stream(std::ostream& os, const Stream& s) {
    constexpr int64_t kBufferBytes = 1 << 16;
    std::vector<unsigned char> buffer(kBufferBytes);
    const int64_t element_bytes = 4 * s.width, per_chunk = kBufferBytes / element_bytes;
    for (int64_t begin = 0; begin < s.count; begin += per_chunk) {
        const int64_t end = std::min(s.count, begin + per_chunk);
        unsigned char* out = buffer.data();
        for (int64_t i = begin; i < end; ++i, out += element_bytes) s.fill(i, out);
        os.write(reinterpret_cast<const char*>(buffer.data()),
                 std::streamsize((end - begin) * element_bytes));
    }
}

// the glTF document's arrays and the binary chunk's streams, filled mesh by mesh
struct GlbBuilder {
    json accessors = json::array(), views = json::array(), gltf_meshes = json::array(),
         materials = json::array();
    json nodes = json::array({{{"name", "root"}, {"children", json::array()}}});
    std::vector<Stream> streams;
    int64_t offset = 0;  // the binary chunk's size so far

    // one accessor over one tightly packed buffer view per array
    size_t add_array(Stream s, int component, int target, json extra = json::object()) {
        static const char* const kType[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
        json view = {
            {"buffer", 0}, {"byteOffset", offset}, {"byteLength", s.bytes()}, {"target", target}};
        json accessor = {{"bufferView", views.size()},
                         {"componentType", component},
                         {"count", s.count},
                         {"type", kType[s.width]}};
        accessor.update(extra);
        offset += s.bytes();
        views.push_back(view);
        accessors.push_back(accessor);
        streams.push_back(std::move(s));
        return accessors.size() - 1;
    }

    // a node named as the mesh, with its primitive unless it has no faces; the streams read `m`
    // and `split` when written, so both outlive the builder
    void add_mesh(const TriMesh& m, const FragmentSplit& split) {
        json node = {{"name", m.name}};
        nodes[0]["children"].push_back(nodes.size());
        if (m.faces.empty()) {  // glTF has no empty mesh: the node alone keeps the name
            nodes.push_back(node);
            return;
        }
        const int64_t n = split.vertex_count();
        json attributes;
        Vec3f lo = Vec3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
        for (const Vec3f& p : m.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
        attributes["POSITION"] =
            add_array({n, 3,
                       [&m, &split](int64_t v, unsigned char* o) {
                           std::memcpy(o, m.positions[split.source(v)].data(), 12);
                       }},
                      kFloat, kArrayBuffer,
                      {{"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}});
        if (!m.normals.empty())
            attributes["NORMAL"] =
                add_array({n, 3,
                           [&m, &split](int64_t v, unsigned char* o) {
                               std::memcpy(o, m.normals[split.source(v)].data(), 12);
                           }},
                          kFloat, kArrayBuffer);
        // glTF's v points down the image; readers flip it back. A fragment channel needs a
        // channel 0 before it (importers number channels by position), zeros when there are no UVs.
        if (!m.uvs.empty() || split.has_fragments())
            attributes["TEXCOORD_0"] = add_array(
                {n, 2,
                 [&m, &split](int64_t v, unsigned char* o) {
                     const Vec2f uv = m.uvs.empty() ? Vec2f::Zero() : m.uvs[split.source(v)];
                     store(o, std::array<float, 2>{uv.x(), 1.f - uv.y()});
                 }},
                kFloat, kArrayBuffer);
        if (split.has_fragments())  // (fragment id, 0): exact in float for ids below 2^24
            attributes["TEXCOORD_1"] =
                add_array({n, 2,
                           [&split](int64_t v, unsigned char* o) {
                               store(o, std::array<float, 2>{float(split.fragment(v)), 1.f});
                           }},
                          kFloat, kArrayBuffer);
        if (!m.saturation.empty() || !m.alpha.empty())
            attributes["COLOR_0"] = add_array(
                {n, 4,
                 [&m, &split](int64_t v, unsigned char* o) {
                     const int32_t s = split.source(v);
                     const float saturation = m.saturation.empty() ? 0.f : m.saturation[s];
                     const float g = alpha_to_color(m.alpha.empty() ? 0.f : m.alpha[s]);
                     store(o, std::array<float, 4>{saturation, g, 0.f, 1.f});
                 }},
                kFloat, kArrayBuffer);
        // one face per stream element would make the accessor's count differ from the stream's:
        // indices stream corner by corner
        const size_t indices =
            add_array({3 * int64_t(m.faces.size()), 1,
                       [&m, &split](int64_t corner, unsigned char* o) {
                           const Tri t = split.face(m, size_t(corner / 3));
                           store(o, std::array<uint32_t, 1>{uint32_t(t[corner % 3])});
                       }},
                      kUnsignedInt, kElementArrayBuffer);
        gltf_meshes.push_back({{"name", m.name},
                               {"primitives", json::array({{{"attributes", attributes},
                                                            {"indices", indices},
                                                            {"material", materials.size()},
                                                            {"mode", 4}}})}});
        materials.push_back(
            {{"name", m.name + "_material"},
             {"pbrMetallicRoughness",
              {{"baseColorFactor", {0.55, 0.42, 0.30, 1.0}}, {"metallicFactor", 0.0}}}});
        node["mesh"] = gltf_meshes.size() - 1;
        nodes.push_back(node);
    }

    // the JSON chunk's text, padded with spaces to 4 bytes
    std::string json_chunk() const {
        json gltf = {{"asset", {{"version", "2.0"}, {"generator", "mudcrack"}}},
                     {"scene", 0},
                     {"scenes", json::array({{{"nodes", {0}}}})},
                     {"nodes", nodes}};
        if (!gltf_meshes.empty()) {
            gltf["meshes"] = gltf_meshes;
            gltf["materials"] = materials;
            gltf["accessors"] = accessors;
            gltf["bufferViews"] = views;
            gltf["buffers"] = json::array({{{"byteLength", offset}}});
        }
        std::string text = gltf.dump();
        // chunks are 4-byte aligned: JSON pads with spaces
        text.append((4 - text.size() % 4) % 4, ' ');
        return text;
    }
};

}  // namespace

void write_glb(const fs::path& path, const std::vector<TriMesh>& meshes) {
    static_assert(sizeof(float) == 4 && std::numeric_limits<float>::is_iec559,
                  "glb floats are IEEE 754 binary32");
    static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
                  "glb arrays are little-endian, written as in memory");
    for (const TriMesh& m : meshes) check_tri_mesh(path, m);

    std::vector<FragmentSplit> splits;
    splits.reserve(meshes.size());
    for (const TriMesh& m : meshes) splits.emplace_back(m);
    GlbBuilder glb;
    for (size_t k = 0; k < meshes.size(); ++k) glb.add_mesh(meshes[k], splits[k]);

    const std::string text = glb.json_chunk();
    const int64_t offset = glb.offset;
    const uint64_t total = 12 + 8 + text.size() + (offset > 0 ? 8 + uint64_t(offset) : 0);
    if (total > std::numeric_limits<uint32_t>::max())
        throw RuntimeError(
            path.string() + ": " + std::to_string(total) +
            " bytes: a glb holds at most 4 GiB (write obj, or surface fewer frames' cracks)");

    write_atomically(path, [&](const fs::path& tmp) {
        errno = 0;
        std::ofstream os(tmp, std::ios::binary);
        if (!os)
            throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
        put_u32(os, kGlbMagic);
        put_u32(os, 2);
        put_u32(os, uint32_t(total));
        put_u32(os, uint32_t(text.size()));
        put_u32(os, kChunkJson);
        os.write(text.data(), std::streamsize(text.size()));
        if (offset > 0) {
            put_u32(os, uint32_t(offset));  // every array is 4-byte components: no padding
            put_u32(os, kChunkBin);
            for (const Stream& s : glb.streams) write_stream(os, s);
        }
        os.close();  // the last buffer reaches the disk here: a full disk shows up at close
        if (!os) throw RuntimeError(tmp.string() + ": cannot write: " + write_error_reason());
    });
}

}  // namespace mudcrack
