// load_input_surface: the formats artists hand us, node transforms, welding, UVs, bad files.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cstring>
#include <string>
#include <vector>

#include "pipeline/io/mesh_io.h"
#include "scratch_dir.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

using test::ScratchDir;
using test::write_file;

// the unit cube as 8 corners and 6 outward quads (1-based for OBJ, 0-based otherwise)
const double kCube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                            {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kQuads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                          {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};

std::string cube_off() {
    std::string s = "OFF\n8 6 0\n";
    for (auto& p : kCube)
        s += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    for (auto& q : kQuads)
        s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
             " " + std::to_string(q[3]) + "\n";
    return s;
}

std::string cube_obj_with_uv() {
    std::string s = "o cube\n";
    for (auto& p : kCube)
        s += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) +
             "\n";
    s += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    for (auto& q : kQuads) {
        s += "f";
        for (int c = 0; c < 4; ++c)
            s += " " + std::to_string(q[c] + 1) + "/" + std::to_string(c + 1);
        s += "\n";
    }
    return s;
}

std::string cube_ply() {
    std::string s =
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
        "property float z\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n";
    for (auto& p : kCube)
        s += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    for (auto& q : kQuads)
        s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
             " " + std::to_string(q[3]) + "\n";
    return s;
}

// STL repeats the corners of every triangle: welding must bring them back to 8
std::string cube_stl() {
    std::string s = "solid cube\n";
    auto vtx = [](int i) {
        return "    vertex " + std::to_string(kCube[i][0]) + " " + std::to_string(kCube[i][1]) +
               " " + std::to_string(kCube[i][2]) + "\n";
    };
    for (auto& q : kQuads) {
        for (int t = 0; t < 2; ++t) {
            s += "  facet normal 0 0 0\n   outer loop\n";
            s += vtx(q[0]) + vtx(q[1 + t]) + vtx(q[2 + t]);
            s += "   endloop\n  endfacet\n";
        }
    }
    return s + "endsolid cube\n";
}

std::string base64(const std::vector<unsigned char>& bytes) {
    static const char* kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t n = uint32_t(bytes[i]) << 16;
        if (i + 1 < bytes.size()) n |= uint32_t(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size()) n |= uint32_t(bytes[i + 2]);
        out += kAlphabet[(n >> 18) & 63];
        out += kAlphabet[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
    }
    return out;
}

// a unit quad (2 triangles) under a parent node scaled by 2 and a child translated by (1,0,0)
std::string quad_gltf() {
    const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    std::vector<unsigned char> buf(sizeof(pos) + sizeof(idx));
    std::memcpy(buf.data(), pos, sizeof(pos));
    std::memcpy(buf.data() + sizeof(pos), idx, sizeof(idx));
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
 "nodes":[{"scale":[2,2,2],"children":[1]},{"translation":[1,0,0],"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
 "buffers":[{"byteLength":)" +
           std::to_string(buf.size()) + R"(,"uri":"data:application/octet-stream;base64,)" +
           base64(buf) + R"("}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
              {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]})";
}

// every triangle of a closed cube: 12 faces over 8 welded corners, all inside [0,1]^3
void expect_cube(const InputSurface& s, const std::string& what) {
    EXPECT_EQ(s.positions.size(), 8u) << what;
    EXPECT_EQ(s.faces.size(), 12u) << what;
    for (const Vec3& p : s.positions) {
        EXPECT_GE(p.minCoeff(), 0.0) << what;
        EXPECT_LE(p.maxCoeff(), 1.0) << what;
    }
    // closed and consistently oriented: signed volume (divergence theorem) = +1
    double volume = 0;
    for (const Tri& f : s.faces) {
        volume += s.positions[f[0]].dot(s.positions[f[1]].cross(s.positions[f[2]])) / 6.0;
    }
    EXPECT_NEAR(volume, 1.0, tol::kRoundoff) << what;
}

TEST(LoadInputSurface, CubeInEveryTextFormat) {
    ScratchDir dir;
    const std::pair<std::string, std::string> files[] = {{"cube.off", cube_off()},
                                                         {"cube.obj", cube_obj_with_uv()},
                                                         {"cube.ply", cube_ply()},
                                                         {"cube.stl", cube_stl()}};
    for (const auto& [name, text] : files) {
        write_file(dir / name, text);
        expect_cube(load_input_surface(dir / name), name);
    }
}

TEST(LoadInputSurface, ObjCornerUVs) {
    ScratchDir dir;
    write_file(dir / "cube.obj", cube_obj_with_uv());
    const InputSurface s = load_input_surface(dir / "cube.obj");
    ASSERT_EQ(s.face_uv.size(), s.faces.size());
    // quad corners carry vt 1..4 = (0,0),(1,0),(1,1),(0,1); triangulation keeps corner 0 in each
    for (const auto& uv : s.face_uv) {
        for (const Vec2& t : uv) {
            EXPECT_TRUE(t.x() == 0.0 || t.x() == 1.0) << t.transpose();
            EXPECT_TRUE(t.y() == 0.0 || t.y() == 1.0) << t.transpose();
        }
        EXPECT_NE(uv[0], uv[1]);
        EXPECT_NE(uv[1], uv[2]);
    }
    // OFF has no UVs
    write_file(dir / "cube.off", cube_off());
    EXPECT_TRUE(load_input_surface(dir / "cube.off").face_uv.empty());
}

TEST(LoadInputSurface, GltfNodeTransformsAreApplied) {
    ScratchDir dir;
    write_file(dir / "quad.gltf", quad_gltf());
    const InputSurface s = load_input_surface(dir / "quad.gltf");
    ASSERT_EQ(s.positions.size(), 4u);
    ASSERT_EQ(s.faces.size(), 2u);
    // world = scale 2 * (p + (1,0,0)): x in {2, 4}, y in {0, 2}
    for (const Vec3& p : s.positions) {
        EXPECT_TRUE(p.x() == 2.0 || p.x() == 4.0) << p.transpose();
        EXPECT_TRUE(p.y() == 0.0 || p.y() == 2.0) << p.transpose();
        EXPECT_EQ(p.z(), 0.0);
    }
}

TEST(LoadInputSurface, MeshesAreMergedAndWelded) {
    ScratchDir dir;
    // two objects sharing an edge (1,0,0)-(0,1,0): 4 distinct corners after welding
    write_file(dir / "two.obj",
               "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
               "o b\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 4 5 6\n");
    const InputSurface s = load_input_surface(dir / "two.obj");
    EXPECT_EQ(s.faces.size(), 2u);
    EXPECT_EQ(s.positions.size(), 4u);
}

TEST(LoadInputSurface, DegenerateTrianglesAreDropped) {
    ScratchDir dir;
    write_file(dir / "degen.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nf 1 2 3\nf 1 2 4\n");
    const InputSurface s = load_input_surface(dir / "degen.obj");
    EXPECT_EQ(s.faces.size(), 1u);
    EXPECT_EQ(s.positions.size(), 3u);
}

TEST(LoadInputSurface, BadFilesNameTheFile) {
    ScratchDir dir;
    test::expect_input_error_naming([&] { load_input_surface(dir / "missing.obj"); },
                                    "missing.obj");
    write_file(dir / "garbage.ply", std::string("\x01\x02garbage\xff\xfe not a mesh", 22));
    test::expect_input_error_naming([&] { load_input_surface(dir / "garbage.ply"); },
                                    "garbage.ply");
    write_file(dir / "lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
    test::expect_input_error_naming([&] { load_input_surface(dir / "lines.obj"); }, "lines.obj");
    write_file(dir / "empty.off", "");
    test::expect_input_error_naming([&] { load_input_surface(dir / "empty.off"); }, "empty.off");
    // a PLY face of no corner leaves a mesh flagged as polygons without one, on which assimp's
    // triangulation would abort the process
    write_file(
        dir / "empty_face.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n0\n");
    test::expect_input_error_naming(
        [&] { load_input_surface(dir / "empty_face.ply"); },
        "empty_face.ply: cannot read the mesh: mesh 0 is declared to hold polygons");
    // list counts assimp would size a list by: beyond the count's type (ASCII), beyond the file
    // (binary)
    const std::string header =
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    write_file(dir / "big_count.ply",
               "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n666666667 0 1 2\n");
    test::expect_input_error_naming(
        [&] { load_input_surface(dir / "big_count.ply"); },
        "big_count.ply: malformed PLY body: element 'face' 0: list count 666666667");
    std::string binary = "ply\nformat binary_little_endian 1.0\n" + header + std::string(36, '\0');
    binary += '\xff';  // 255 corners, 3 bytes of them in the file
    binary += std::string(3, '\0');
    write_file(dir / "short_list.ply", binary);
    test::expect_input_error_naming(
        [&] { load_input_surface(dir / "short_list.ply"); },
        "short_list.ply: malformed PLY body: element 'face' 0: list count 255");
    // assimp reads "pLy" as PLY too (and hung on this one without end_header)
    write_file(dir / "mixed_case.ply",
               "pLy\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
    test::expect_input_error_naming([&] { load_input_surface(dir / "mixed_case.ply"); },
                                    "mixed_case.ply: malformed PLY header: no end_header");
}

}  // namespace
}  // namespace mudcrack
