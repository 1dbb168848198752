#include "pipeline/io/tet_mesh_io.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <system_error>

#include "pipeline/io/atomic_output.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

namespace {

// raw appended data is copied to and from memory as is: VTU files say byte_order="LittleEndian"
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "tet_mesh_io writes host-order bytes");

constexpr uint8_t kVtkTriangle = 5;
constexpr uint8_t kVtkTetra = 10;
constexpr uint8_t kKindTet = 0;
constexpr uint8_t kKindBoundary = 1;

/// One DataArray: its XML attributes and its bytes in the appended block.
struct Array {
    std::string section;  // PointData, CellData, Points or Cells
    std::string name, type;
    int components = 1;
    std::string bytes;
};

template <class T>
std::string as_bytes(const std::vector<T>& values) {
    return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

void write_vtu(const fs::path& tmp, const TetMesh& mesh) {
    const size_t n_points = mesh.X.size();
    const size_t n_tets = mesh.tets.size(), n_tris = mesh.boundary.size();
    const size_t n_cells = n_tets + n_tris;
    const bool has_uv = !mesh.boundary_uv.empty();

    // the arrays, in file order
    std::vector<int32_t> id(n_points);
    for (size_t i = 0; i < n_points; ++i) id[i] = int32_t(i);
    std::vector<double> points(3 * n_points);
    for (size_t i = 0; i < n_points; ++i)
        for (int k = 0; k < 3; ++k) points[3 * i + k] = mesh.X[i][k];
    std::vector<int64_t> connectivity, offsets;
    connectivity.reserve(4 * n_tets + 3 * n_tris);
    offsets.reserve(n_cells);
    std::vector<uint8_t> types, kind;
    types.reserve(n_cells);
    kind.reserve(n_cells);
    std::vector<float> uv(has_uv ? 6 * n_cells : 0, 0.f);
    for (const Tet& t : mesh.tets) {
        connectivity.insert(connectivity.end(), t.begin(), t.end());
        offsets.push_back(int64_t(connectivity.size()));
        types.push_back(kVtkTetra);
        kind.push_back(kKindTet);
    }
    for (size_t f = 0; f < n_tris; ++f) {
        connectivity.insert(connectivity.end(), mesh.boundary[f].begin(), mesh.boundary[f].end());
        offsets.push_back(int64_t(connectivity.size()));
        types.push_back(kVtkTriangle);
        kind.push_back(kKindBoundary);
        if (has_uv) {
            for (int c = 0; c < 3; ++c) {
                uv[6 * (n_tets + f) + 2 * c] = float(mesh.boundary_uv[f][c].x());
                uv[6 * (n_tets + f) + 2 * c + 1] = float(mesh.boundary_uv[f][c].y());
            }
        }
    }
    std::vector<Array> arrays;
    arrays.push_back({"PointData", "id", "Int32", 1, as_bytes(id)});
    if (has_uv) arrays.push_back({"CellData", "uv", "Float32", 6, as_bytes(uv)});
    arrays.push_back({"CellData", "kind", "UInt8", 1, as_bytes(kind)});
    arrays.push_back({"Points", "Points", "Float64", 3, as_bytes(points)});
    arrays.push_back({"Cells", "connectivity", "Int64", 1, as_bytes(connectivity)});
    arrays.push_back({"Cells", "offsets", "Int64", 1, as_bytes(offsets)});
    arrays.push_back({"Cells", "types", "UInt8", 1, as_bytes(types)});

    // XML header: each block in the appended data is a UInt64 byte count followed by the bytes
    std::ostringstream xml;
    xml << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
           "header_type=\"UInt64\">\n"
        << "  <UnstructuredGrid>\n"
        << "    <Piece NumberOfPoints=\"" << n_points << "\" NumberOfCells=\"" << n_cells
        << "\">\n";
    uint64_t offset = 0;
    std::string section;
    for (const Array& a : arrays) {
        if (a.section != section) {
            if (!section.empty()) xml << "      </" << section << ">\n";
            section = a.section;
            xml << "      <" << section << (section == "PointData" ? " Scalars=\"id\"" : "")
                << ">\n";
        }
        xml << "        <DataArray type=\"" << a.type << "\" Name=\"" << a.name << "\"";
        if (a.components != 1) xml << " NumberOfComponents=\"" << a.components << "\"";
        xml << " format=\"appended\" offset=\"" << offset << "\"/>\n";
        offset += sizeof(uint64_t) + a.bytes.size();
    }
    xml << "      </" << section << ">\n"
        << "    </Piece>\n"
        << "  </UnstructuredGrid>\n"
        << "  <AppendedData encoding=\"raw\">\n   _";

    errno = 0;
    std::ofstream os(tmp, std::ios::binary);
    if (!os)
        throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
    os << xml.str();
    for (const Array& a : arrays) {
        const uint64_t size = a.bytes.size();
        os.write(reinterpret_cast<const char*>(&size), sizeof size);
        os.write(a.bytes.data(), std::streamsize(a.bytes.size()));
    }
    os << "\n  </AppendedData>\n</VTKFile>\n";
    os.close();
    if (!os) throw RuntimeError(tmp.string() + ": cannot write: " + write_error_reason());
}

/// The value of attribute `key` inside one XML tag's text, or "" when absent.
std::string xml_attribute(const std::string& tag, const std::string& key) {
    const std::string pattern = " " + key + "=\"";
    const size_t at = tag.find(pattern);
    if (at == std::string::npos) return "";
    const size_t begin = at + pattern.size();
    const size_t end = tag.find('"', begin);
    return end == std::string::npos ? "" : tag.substr(begin, end - begin);
}

/// A minimal reader for the files write_vtu makes: the XML header is scanned for its tags, then
/// each DataArray's block is cut out of the raw appended data.
class VtuReader {
public:
    explicit VtuReader(const fs::path& path) : m_path(path) {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) fail("tet mesh file not found (run mc-init first?)");
        std::ifstream is(path, std::ios::binary);
        m_bytes.assign(std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>());
        const size_t appended = m_bytes.find("<AppendedData");
        if (m_bytes.compare(0, 5, "<?xml") != 0 || m_bytes.find("<VTKFile") == std::string::npos ||
            appended == std::string::npos) {
            fail("not a VTK XML file with appended data");
        }
        const size_t underscore = m_bytes.find('_', appended);
        if (underscore == std::string::npos) fail("no '_' starts the appended data");
        m_data_begin = underscore + 1;
        m_header = m_bytes.substr(0, underscore);
        const std::string vtkfile = tag_text("<VTKFile");
        if (xml_attribute(vtkfile, "type") != "UnstructuredGrid")
            fail("VTKFile type is not UnstructuredGrid");
        if (xml_attribute(vtkfile, "byte_order") != "LittleEndian" ||
            xml_attribute(vtkfile, "header_type") != "UInt64" ||
            xml_attribute(tag_text("<AppendedData"), "encoding") != "raw") {
            fail(
                "expected byte_order=\"LittleEndian\", header_type=\"UInt64\" and raw appended data "
                "(as mc-init writes; files re-saved by other tools are not supported)");
        }
        const std::string piece = tag_text("<Piece");
        m_points = parse_count(xml_attribute(piece, "NumberOfPoints"), "NumberOfPoints");
        m_cells = parse_count(xml_attribute(piece, "NumberOfCells"), "NumberOfCells");
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path.string() + ": " + what);
    }
    size_t n_points() const { return m_points; }
    size_t n_cells() const { return m_cells; }
    bool has_array(const std::string& name) const { return !find_tag(name).empty(); }

    /// The named DataArray, checked for its type and element count.
    template <class T>
    std::vector<T> array(const std::string& name, const std::string& type, size_t count) const {
        const std::string tag = find_tag(name);
        if (tag.empty()) fail("no DataArray named '" + name + "'");
        if (xml_attribute(tag, "type") != type) {
            fail("DataArray '" + name + "' has type " + xml_attribute(tag, "type") + ", expected " +
                 type);
        }
        if (xml_attribute(tag, "format") != "appended")
            fail("DataArray '" + name + "' is not in the appended data");
        const size_t at =
            m_data_begin + parse_count(xml_attribute(tag, "offset"), name + " offset");
        uint64_t size = 0;
        if (at + sizeof size > m_bytes.size())
            fail("truncated: DataArray '" + name + "' starts past the end");
        std::memcpy(&size, m_bytes.data() + at, sizeof size);
        if (size != count * sizeof(T)) {
            fail("DataArray '" + name + "' holds " + std::to_string(size) + " bytes, expected " +
                 std::to_string(count * sizeof(T)));
        }
        if (at + sizeof size + size > m_bytes.size())
            fail("truncated: DataArray '" + name + "' ends past the end");
        std::vector<T> values(count);
        std::memcpy(values.data(), m_bytes.data() + at + sizeof size, size);
        return values;
    }

    /// Must close the file: the writer's trailer after the last block.
    void expect_trailer(size_t last_block_end) const {
        if (m_bytes.find("</VTKFile>", last_block_end) == std::string::npos)
            fail("truncated: no </VTKFile> at the end");
    }
    size_t block_end(const std::string& name) const {
        const size_t at =
            m_data_begin + parse_count(xml_attribute(find_tag(name), "offset"), name + " offset");
        uint64_t size = 0;
        std::memcpy(&size, m_bytes.data() + at, sizeof size);
        return at + sizeof size + size;
    }

private:
    std::string tag_text(const std::string& open) const {
        const size_t at = m_header.find(open);
        if (at == std::string::npos) fail("no " + open.substr(1) + " element");
        return m_header.substr(at, m_header.find('>', at) - at);
    }
    std::string find_tag(const std::string& name) const {
        for (size_t at = m_header.find("<DataArray"); at != std::string::npos;
             at = m_header.find("<DataArray", at + 1)) {
            const std::string tag = m_header.substr(at, m_header.find('>', at) - at);
            if (xml_attribute(tag, "Name") == name) return tag;
        }
        return "";
    }
    size_t parse_count(const std::string& text, const std::string& what) const {
        if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
            fail(what + " = \"" + text + "\": expected a non-negative integer");
        }
        return size_t(std::stoull(text));
    }

    fs::path m_path;
    std::string m_bytes, m_header;
    size_t m_data_begin = 0, m_points = 0, m_cells = 0;
};

}  // namespace

void write_tet_mesh_vtu(const fs::path& path, const TetMesh& mesh) {
    if (!mesh.boundary_uv.empty() && mesh.boundary_uv.size() != mesh.boundary.size()) {
        throw RuntimeError(path.string() + ": " + std::to_string(mesh.boundary_uv.size()) +
                           " boundary UV triples for " + std::to_string(mesh.boundary.size()) +
                           " boundary triangles");
    }
    write_atomically(path, [&](const fs::path& tmp) { write_vtu(tmp, mesh); });
}

TetMesh read_tet_mesh_vtu(const fs::path& path) {
    const VtuReader vtu(path);
    const size_t n_points = vtu.n_points(), n_cells = vtu.n_cells();
    const auto id = vtu.array<int32_t>("id", "Int32", n_points);
    const auto points = vtu.array<double>("Points", "Float64", 3 * n_points);
    const auto offsets = vtu.array<int64_t>("offsets", "Int64", n_cells);
    const auto types = vtu.array<uint8_t>("types", "UInt8", n_cells);
    const auto kind = vtu.array<uint8_t>("kind", "UInt8", n_cells);
    const size_t n_connectivity = n_cells == 0 ? 0 : size_t(std::max<int64_t>(offsets.back(), 0));
    if (n_connectivity > 4 * n_cells) {
        vtu.fail("the last cell offset is " + std::to_string(offsets.back()) +
                 ": expected at most 4 corners per cell");
    }
    const auto connectivity = vtu.array<int64_t>("connectivity", "Int64", n_connectivity);
    const bool has_uv = vtu.has_array("uv");
    const auto uv = has_uv ? vtu.array<float>("uv", "Float32", 6 * n_cells) : std::vector<float>();
    vtu.expect_trailer(vtu.block_end("types"));

    TetMesh mesh;
    mesh.X.resize(n_points);
    for (size_t i = 0; i < n_points; ++i) {
        if (id[i] != int32_t(i)) {
            vtu.fail("point " + std::to_string(i) + " has id " + std::to_string(id[i]) +
                     ": expected the ids 0..n-1 in order");
        }
        mesh.X[i] = Vec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    }
    int64_t begin = 0;
    for (size_t c = 0; c < n_cells; ++c) {
        const int64_t end = offsets[c];
        const int64_t corners = types[c] == kVtkTetra ? 4 : types[c] == kVtkTriangle ? 3 : -1;
        if (corners < 0 || end - begin != corners) {
            vtu.fail("cell " + std::to_string(c) + " has VTK type " +
                     std::to_string(int(types[c])) + " and " + std::to_string(end - begin) +
                     " corners: expected tetrahedra (10) and triangles (5)");
        }
        const uint8_t expected_kind = corners == 4 ? kKindTet : kKindBoundary;
        if (kind[c] != expected_kind) {
            vtu.fail("cell " + std::to_string(c) + " has kind " + std::to_string(int(kind[c])) +
                     ", expected " + std::to_string(int(expected_kind)) + " for its VTK type");
        }
        int32_t v[4] = {0, 0, 0, 0};
        for (int64_t k = 0; k < corners; ++k) {
            const int64_t p = connectivity[size_t(begin + k)];
            if (p < 0 || size_t(p) >= n_points) {
                vtu.fail("cell " + std::to_string(c) + " references point " + std::to_string(p) +
                         " of " + std::to_string(n_points));
            }
            v[k] = int32_t(p);
        }
        if (corners == 4) {
            mesh.tets.push_back({v[0], v[1], v[2], v[3]});
        } else {
            mesh.boundary.push_back({v[0], v[1], v[2]});
            if (has_uv) {
                const float* t = uv.data() + 6 * c;
                mesh.boundary_uv.push_back({Vec2(t[0], t[1]), Vec2(t[2], t[3]), Vec2(t[4], t[5])});
            }
        }
        begin = end;
    }
    return mesh;
}

}  // namespace mudcrack
