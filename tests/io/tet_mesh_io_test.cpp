// The init tet mesh as .vtu: exact round trip, the VTK layout ParaView expects, damaged files.
#include <gtest/gtest.h>

#include <cstring>

#include "pipeline/io/tet_mesh_io.h"
#include "scratch_dir.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

using test::ScratchDir;

// a unit cube split into 5 tets, with its 12 boundary triangles and per-corner UVs
TetMesh cube_mesh() {
    TetMesh m;
    for (int i = 0; i < 8; ++i) m.X.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
    m.X[7] += Vec3(1.0 / 3.0, 1e-17, -0.1);  // values that need double precision
    m.tets = {{0, 1, 2, 4}, {1, 3, 2, 7}, {1, 4, 5, 7}, {2, 7, 6, 4}, {1, 2, 4, 7}};
    m.boundary = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                  {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (size_t f = 0; f < m.boundary.size(); ++f) {
        m.boundary_uv.push_back({Vec2(0.125 * f, 0.5), Vec2(0.25, 0.0625 * f), Vec2(1, 0.75)});
    }
    return m;
}

TEST(TetMeshVtu, RoundTrip) {
    ScratchDir dir;
    const TetMesh in = cube_mesh();
    write_tet_mesh_vtu(dir / "tets.vtu", in);
    const TetMesh out = read_tet_mesh_vtu(dir / "tets.vtu");
    ASSERT_EQ(out.X.size(), in.X.size());
    // Float64: exact
    for (size_t i = 0; i < in.X.size(); ++i) EXPECT_EQ(out.X[i], in.X[i]) << "point " << i;
    EXPECT_EQ(out.tets, in.tets);
    EXPECT_EQ(out.boundary, in.boundary);
    ASSERT_EQ(out.boundary_uv.size(), in.boundary_uv.size());
    for (size_t f = 0; f < in.boundary_uv.size(); ++f)
        // exact in float
        for (int c = 0; c < 3; ++c) EXPECT_EQ(out.boundary_uv[f][c], in.boundary_uv[f][c]);
    // identical content, identical bytes
    write_tet_mesh_vtu(dir / "again.vtu", in);
    EXPECT_TRUE(test::read_file(dir / "tets.vtu") == test::read_file(dir / "again.vtu"));
}

TEST(TetMeshVtu, HeaderIsWhatParaViewReads) {
    ScratchDir dir;
    write_tet_mesh_vtu(dir / "tets.vtu", cube_mesh());
    const std::string text = test::read_file(dir / "tets.vtu");
    const std::string header = text.substr(0, text.find("<AppendedData"));
    for (const char* expected :
         {"type=\"UnstructuredGrid\"", "byte_order=\"LittleEndian\"", "header_type=\"UInt64\"",
          "NumberOfPoints=\"8\" NumberOfCells=\"17\"", "type=\"Int32\" Name=\"id\"",
          "type=\"Float32\" Name=\"uv\" NumberOfComponents=\"6\"", "type=\"UInt8\" Name=\"kind\"",
          "type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"",
          "type=\"Int64\" Name=\"connectivity\"", "type=\"Int64\" Name=\"offsets\"",
          "type=\"UInt8\" Name=\"types\""}) {
        EXPECT_NE(header.find(expected), std::string::npos) << expected;
    }
    // the first appended block is "id": UInt64 byte count 8*4, then ids 0..7
    const size_t data = text.find('_', text.find("<AppendedData")) + 1;
    uint64_t bytes = 0;
    std::memcpy(&bytes, text.data() + data, 8);
    EXPECT_EQ(bytes, 32u);
    EXPECT_EQ(text.substr(text.size() - 11), "</VTKFile>\n");
}

TEST(TetMeshVtu, WithoutUVs) {
    ScratchDir dir;
    TetMesh in = cube_mesh();
    in.boundary_uv.clear();
    write_tet_mesh_vtu(dir / "tets.vtu", in);
    const TetMesh out = read_tet_mesh_vtu(dir / "tets.vtu");
    EXPECT_EQ(out.boundary, in.boundary);
    EXPECT_TRUE(out.boundary_uv.empty());
}

TEST(TetMeshVtu, DamagedFilesNameTheFile) {
    ScratchDir dir;
    test::expect_input_error_naming([&] { read_tet_mesh_vtu(dir / "missing.vtu"); }, "missing.vtu");
    test::write_file(dir / "garbage.vtu", "\x89PNG garbage");
    test::expect_input_error_naming([&] { read_tet_mesh_vtu(dir / "garbage.vtu"); }, "garbage.vtu");
    write_tet_mesh_vtu(dir / "good.vtu", cube_mesh());
    const std::string good = test::read_file(dir / "good.vtu");
    for (size_t keep :
         {size_t(0), size_t(100), good.find('_', good.find("<AppendedData")) + 5, good.size() / 2,
          good.size() - 20, good.size() - 2}) {  // -1 drops only the final newline
        const std::string name = "cut" + std::to_string(keep) + ".vtu";
        test::write_file(dir / name, good.substr(0, keep));
        test::expect_input_error_naming([&] { read_tet_mesh_vtu(dir / name); }, name);
    }
    // a file in another encoding (e.g. re-saved as base64 by ParaView) is refused with the reason
    std::string base64 = good;
    base64.replace(base64.find("encoding=\"raw\""), 14, "encoding=\"b64\"");
    test::write_file(dir / "b64.vtu", base64);
    test::expect_input_error_naming([&] { read_tet_mesh_vtu(dir / "b64.vtu"); },
                                    "raw appended data");
    // a point reference out of range
    TetMesh bad = cube_mesh();
    bad.tets[0][3] = 99;
    write_tet_mesh_vtu(dir / "range.vtu", bad);
    test::expect_input_error_naming([&] { read_tet_mesh_vtu(dir / "range.vtu"); },
                                    "references point 99");
}

}  // namespace
}  // namespace mudcrack
