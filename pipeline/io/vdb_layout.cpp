#include "pipeline/io/vdb_layout.h"

#include <fstream>
#include <utility>
#include <vector>

#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

namespace {

// OpenVDB's file layout (io/Archive.cc, OpenVDB 10): int64 magic, uint32 file version, two
// uint32 library versions, one byte "has grid offsets", a 36-character UUID; since file version
// 222 each grid stores its own compression flags.
constexpr int64_t kVdbMagic = 0x56444220;
constexpr uint32_t kOldestFileVersion = 222;
constexpr uint32_t kNewestFileVersion = 224;  // OpenVDB 10's own
constexpr int64_t kUuidLength = 36;
// a root tile: int32 x, y, z, the value, then the active flag as one raw bool byte
constexpr int64_t kTileCoordBytes = 12;
// io/Compression.h: a grid's compression flags and a node's value metadata
constexpr uint32_t kCompressZip = 0x1, kCompressActiveMask = 0x2, kCompressBlosc = 0x4;
constexpr uint8_t kNoMaskAndOneInactiveValue = 2, kMaskAndNoInactiveValues = 3,
                  kMaskAndOneInactiveValue = 4, kMaskAndTwoInactiveValues = 5,
                  kNoMaskAndAllValues = 6;
// the 5-4-3 tree of a points grid: two internal levels, then 8^3 leaves
constexpr uint32_t kInternalLog2Dims[2] = {5, 4};
constexpr uint32_t kLeafValues = 512;

// The standard metadata types OpenVDB registers and the bytes it reads for each: it reads a
// fixed-size value by its own size whatever byte count the file states, so a mismatch would make
// this walk and OpenVDB's part ways; "string" takes the stated count.
int64_t metadata_bytes(const std::string& type) {
    static const std::pair<const char*, int64_t> kTypes[] = {
        {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},  {"double", 8}, {"vec2i", 8},
        {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
        {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
    for (const auto& [name, bytes] : kTypes)
        if (type == name) return bytes;
    return -1;
}

class VdbWalker {
public:
    explicit VdbWalker(const fs::path& path) : m_path(path), m_is(path, std::ios::binary) {
        std::error_code ec;
        const auto size = fs::file_size(path, ec);
        m_size = ec ? 0 : int64_t(size);
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path.string() + ": truncated or damaged points file: " + what +
                         " (file has " + std::to_string(m_size) + " bytes)");
    }

    template <class T>
    T read(const char* what) {
        T v{};
        if (!m_is.read(reinterpret_cast<char*>(&v), sizeof v))
            fail(std::string(what) + " ends early");
        m_pos += int64_t(sizeof v);
        return v;
    }
    void skip(int64_t bytes, const std::string& what) {
        if (bytes < 0 || bytes > m_size - m_pos) fail(what + " runs past the end of the file");
        m_pos += bytes;
        m_is.seekg(m_pos);
    }
    void seek(int64_t pos, const std::string& what) {
        if (pos < m_pos || pos > m_size)
            fail(what + " at byte " + std::to_string(pos) +
                 " lies before what was read or past the end of the file");
        m_pos = pos;
        m_is.seekg(m_pos);
    }
    std::string string(const std::string& what) {
        const uint32_t n = read<uint32_t>(what.c_str());
        if (int64_t(n) > m_size - m_pos)
            fail(what + " of " + std::to_string(n) + " bytes runs past the end of the file");
        std::string s(n, '\0');
        if (!m_is.read(s.data(), std::streamsize(n))) fail(what + " ends early");
        m_pos += n;
        return s;
    }
    void bool_byte(const std::string& what) {
        const uint8_t b = read<uint8_t>(what.c_str());
        if (b > 1) fail(what + " is byte " + std::to_string(b) + ", expected 0 or 1");
    }
    // a metadata map (file or grid): count, then name, type name, byte count and value per entry
    void metadata(const std::string& owner) {
        const uint32_t count = read<uint32_t>((owner + " metadata count").c_str());
        for (uint32_t i = 0; i < count; ++i) {
            const std::string name = string(owner + " metadata name");
            const std::string type = string(owner + " metadata '" + name.substr(0, 40) + "' type");
            const std::string what =
                owner + " metadata '" + name.substr(0, 40) + "' (" + type.substr(0, 20) + ")";
            const uint32_t bytes = read<uint32_t>((what + " size").c_str());
            if (type == "string") {
                skip(bytes, what);
                continue;
            }
            const int64_t expected = metadata_bytes(type);
            if (expected < 0) fail(what + ": a metadata type mudcrack does not write");
            if (bytes != expected)
                fail(what + " states " + std::to_string(bytes) + " bytes, the type has " +
                     std::to_string(expected));
            if (type == "bool") {
                bool_byte(what);
            } else {
                skip(bytes, what);
            }
        }
    }
    // a node mask of `bits` bits, as words
    std::vector<uint64_t> mask(uint32_t bits, const std::string& what) {
        std::vector<uint64_t> words(bits / 64);
        const int64_t bytes = int64_t(words.size() * sizeof(uint64_t));
        if (bytes > m_size - m_pos) fail(what + " runs past the end of the file");
        m_is.read(reinterpret_cast<char*>(words.data()), std::streamsize(bytes));
        m_pos += bytes;
        return words;
    }
    // io::readData's value block: zip or blosc chunks carry an int64 byte count, positive for
    // compressed bytes, minus the raw byte count otherwise; OpenVDB allocates the first and reads
    // the second into a buffer of the node's size before comparing, so both are checked here
    void value_block(uint32_t compression, int64_t raw_bytes, const std::string& what) {
        if ((compression & (kCompressZip | kCompressBlosc)) == 0) {
            skip(raw_bytes, what);
            return;
        }
        const auto stated = read<int64_t>((what + " size").c_str());
        if (stated <= 0) {
            if (stated != -raw_bytes)
                fail(what + " holds " + std::to_string(-stated) +
                     " uncompressed bytes, the node has " + std::to_string(raw_bytes));
            skip(raw_bytes, what);
        } else {
            skip(stated, what + " of " + std::to_string(stated) + " compressed bytes");
        }
    }
    // an internal node's topology (tree/InternalNode.h readTopology, io/Compression.h
    // readCompressedValues): child and value masks, the compressed values, then each child
    void internal_node(uint32_t log2dim, uint32_t compression, uint32_t value_bytes,
                       const std::string& what) {
        const uint32_t values = 1u << (3 * log2dim);
        const std::vector<uint64_t> children = mask(values, what + " child mask");
        const std::vector<uint64_t> active = mask(values, what + " value mask");
        const uint8_t metadata = read<uint8_t>((what + " value metadata").c_str());
        if (metadata > kNoMaskAndAllValues)
            fail(what + " value metadata " + std::to_string(metadata) + ", expected 0 to 6");
        if (metadata == kNoMaskAndOneInactiveValue || metadata == kMaskAndOneInactiveValue ||
            metadata == kMaskAndTwoInactiveValues)
            skip(int64_t(value_bytes) * (metadata == kMaskAndTwoInactiveValues ? 2 : 1),
                 what + " inactive values");
        if (metadata == kMaskAndNoInactiveValues || metadata == kMaskAndOneInactiveValue ||
            metadata == kMaskAndTwoInactiveValues)
            mask(values, what + " selection mask");
        int64_t stored = values;
        if ((compression & kCompressActiveMask) != 0 && metadata != kNoMaskAndAllValues) {
            stored = 0;
            for (uint64_t w : active) stored += __builtin_popcountll(w);
        }
        value_block(compression, stored * value_bytes, what + " values");
        uint32_t child = 0;
        for (size_t w = 0; w < children.size(); ++w) {
            for (int b = 0; b < 64; ++b) {
                if (((children[w] >> b) & 1u) == 0) continue;
                const std::string name = what + " child " + std::to_string(child++);
                if (log2dim > kInternalLog2Dims[1]) {
                    internal_node(kInternalLog2Dims[1], compression, value_bytes, name);
                } else {
                    mask(kLeafValues, name + " value mask");  // a leaf's topology
                }
            }
        }
    }

private:
    fs::path m_path;
    std::ifstream m_is;
    int64_t m_size = 0;
    int64_t m_pos = 0;
};

}  // namespace

void check_vdb_layout(const fs::path& path, const VdbLayoutExpectation& expected) {
    VdbWalker in(path);
    if (in.read<int64_t>("header") != kVdbMagic)
        in.fail("no OpenVDB magic number (not an OpenVDB file?)");
    const uint32_t version = in.read<uint32_t>("header");
    if (version < kOldestFileVersion || version > kNewestFileVersion)
        in.fail("OpenVDB file version " + std::to_string(version) + ", expected " +
                std::to_string(kOldestFileVersion) + " to " + std::to_string(kNewestFileVersion));
    in.read<uint32_t>("header");  // library major version
    in.read<uint32_t>("header");  // library minor version
    if (in.read<uint8_t>("header") != 1)
        in.fail(
            "the header says the grids have no offsets (a streamed file; mudcrack writes seekable ones)");
    in.skip(kUuidLength, "header UUID");
    in.metadata("file");
    const uint32_t grid_count = in.read<uint32_t>("grid count");
    for (uint32_t g = 0; g < grid_count; ++g) {
        const std::string grid = "grid " + std::to_string(g);
        in.string(grid + " name");
        const std::string tree_type = in.string(grid + " type");
        if (tree_type != expected.tree_type)
            in.fail(grid + " is a '" + tree_type.substr(0, 40) + "', expected a '" +
                    expected.tree_type + "'");
        if (!in.string(grid + " instance parent").empty())
            in.fail(grid + " is an instance of another grid (mudcrack writes none)");
        const auto grid_pos = in.read<int64_t>("grid descriptor");
        in.read<int64_t>("grid descriptor");  // where the leaf buffers start
        const auto end_pos = in.read<int64_t>("grid descriptor");
        if (end_pos < grid_pos)
            in.fail(grid + " ends at byte " + std::to_string(end_pos) + ", before it starts");
        in.seek(grid_pos, grid + " data");
        const auto compression = in.read<uint32_t>((grid + " compression").c_str());
        in.metadata(grid);
        const std::string map_type = in.string(grid + " transform type");
        if (map_type != expected.map_type)
            in.fail(grid + " transform is a '" + map_type.substr(0, 40) + "', expected a '" +
                    expected.map_type + "'");
        in.skip(expected.map_bytes, grid + " transform");
        in.read<uint32_t>((grid + " buffer count").c_str());
        in.skip(expected.root_value_bytes, grid + " background");
        const uint32_t tiles = in.read<uint32_t>((grid + " root tile count").c_str());
        const uint32_t children = in.read<uint32_t>((grid + " root child count").c_str());
        for (uint32_t t = 0; t < tiles; ++t) {
            in.skip(kTileCoordBytes + expected.root_value_bytes,
                    grid + " root tile " + std::to_string(t));
            in.bool_byte(grid + " root tile " + std::to_string(t) + " active flag");
        }
        for (uint32_t c = 0; c < children; ++c) {
            const std::string child = grid + " root child " + std::to_string(c);
            in.skip(kTileCoordBytes, child + " origin");
            in.internal_node(kInternalLog2Dims[0], compression, expected.root_value_bytes, child);
        }
        in.seek(end_pos, grid + " end");
    }
}

}  // namespace mudcrack
