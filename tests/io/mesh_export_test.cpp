// export_meshes / import_meshes: every supported format round-trips counts and UVs, bytes are
// deterministic, fbx is refused with its reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "pipeline/io/mesh_io.h"
#include "scratch_dir.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

// tolerances, named by what they bound
constexpr double kStoredFloat = 1e-6;  // a float value written and read back by a mesh format
// a value through the vertex colour's mapping (logistic alpha, normals)
constexpr double kColourMapped = 1e-5;

using test::ScratchDir;

// two disjoint tetrahedra-shaped fragments (ids 3 and 8) with every attribute
TriMesh boundary_mesh() {
    TriMesh m;
    m.name = "boundary";
    const Vec3f corners[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const Tri faces[4] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (int piece = 0; piece < 2; ++piece) {
        const int32_t base = int32_t(m.positions.size());
        for (int c = 0; c < 4; ++c) {
            m.positions.push_back(corners[c] + Vec3f(2.f * piece, 0, 0));
            m.normals.push_back((corners[c] - Vec3f(0.25f, 0.25f, 0.25f)).normalized());
            m.uvs.emplace_back(0.125f * c + 0.5f * piece, 0.25f * c);
            m.saturation.push_back(0.1f * c + 0.3f * piece);
            m.alpha.push_back(-1.5f + 0.75f * c + piece);
        }
        for (const Tri& f : faces) {
            m.faces.push_back({base + f[0], base + f[1], base + f[2]});
            m.face_fragment.push_back(piece == 0 ? 3 : 8);
        }
    }
    return m;
}

TriMesh crack_mesh() {
    TriMesh m;
    m.name = "crack";
    m.positions = {{0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.faces = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// the corners of all faces as (position, uv) tuples, sorted: independent of vertex order
using Corner = std::tuple<float, float, float, float, float>;
std::vector<Corner> corners(const TriMesh& m) {
    std::vector<Corner> out;
    for (const Tri& f : m.faces) {
        for (int32_t v : f) {
            const Vec2f uv = m.uvs.empty() ? Vec2f::Zero() : m.uvs[v];
            out.emplace_back(m.positions[v].x(), m.positions[v].y(), m.positions[v].z(), uv.x(),
                             uv.y());
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

void expect_same_corners(const TriMesh& a, const TriMesh& b, const std::string& what) {
    const auto ca = corners(a), cb = corners(b);
    ASSERT_EQ(ca.size(), cb.size()) << what;
    for (size_t i = 0; i < ca.size(); ++i) {
        EXPECT_NEAR(std::get<0>(ca[i]), std::get<0>(cb[i]), kStoredFloat) << what;
        EXPECT_NEAR(std::get<1>(ca[i]), std::get<1>(cb[i]), kStoredFloat) << what;
        EXPECT_NEAR(std::get<2>(ca[i]), std::get<2>(cb[i]), kStoredFloat) << what;
        EXPECT_NEAR(std::get<3>(ca[i]), std::get<3>(cb[i]), kStoredFloat) << what << " u";
        EXPECT_NEAR(std::get<4>(ca[i]), std::get<4>(cb[i]), kStoredFloat) << what << " v";
    }
}

const std::vector<TriMesh> kMeshes = {boundary_mesh(), crack_mesh()};

TEST(MeshExport, EveryFormatRoundTripsCountsAndUVs) {
    ScratchDir dir;
    for (const std::string format : {"glb", "obj", "dae"}) {
        const auto path = dir / ("scene." + format);
        export_meshes(path, kMeshes, format);
        const auto back = import_meshes(path);
        ASSERT_EQ(back.size(), 2u) << format;
        for (size_t i = 0; i < 2; ++i) {
            const std::string what = format + " mesh " + kMeshes[i].name;
            EXPECT_EQ(back[i].name, kMeshes[i].name) << what;
            EXPECT_EQ(back[i].positions.size(), kMeshes[i].positions.size()) << what;
            EXPECT_EQ(back[i].faces.size(), kMeshes[i].faces.size()) << what;
            expect_same_corners(kMeshes[i], back[i], what);
        }
    }
    // ply holds one mesh: the two are merged
    export_meshes(dir / "scene.ply", kMeshes, "ply");
    const auto ply = import_meshes(dir / "scene.ply");
    ASSERT_EQ(ply.size(), 1u);
    EXPECT_EQ(ply[0].positions.size(), 12u);
    EXPECT_EQ(ply[0].faces.size(), 10u);
    TriMesh merged = kMeshes[0];
    for (const Tri& f : kMeshes[1].faces) merged.faces.push_back({f[0] + 8, f[1] + 8, f[2] + 8});
    merged.positions.insert(merged.positions.end(), kMeshes[1].positions.begin(),
                            kMeshes[1].positions.end());
    merged.uvs.insert(merged.uvs.end(), kMeshes[1].uvs.begin(), kMeshes[1].uvs.end());
    expect_same_corners(merged, ply[0], "ply");
}

TEST(MeshExport, GlbAndDaeCarryNormalsColorsAndFragments) {
    ScratchDir dir;
    for (const std::string format : {"glb", "dae"}) {
        const auto path = dir / ("scene." + format);
        export_meshes(path, kMeshes, format);
        const TriMesh b = import_meshes(path)[0];
        const TriMesh& a = kMeshes[0];
        ASSERT_EQ(b.positions.size(), a.positions.size()) << format;
        ASSERT_EQ(b.saturation.size(), a.positions.size()) << format;
        ASSERT_EQ(b.normals.size(), a.positions.size()) << format;
        ASSERT_EQ(b.face_fragment.size(), a.faces.size()) << format;
        // match vertices by position (both pieces have distinct corners)
        for (size_t i = 0; i < a.positions.size(); ++i) {
            size_t j = 0;
            while (j < b.positions.size() && (b.positions[j] - a.positions[i]).norm() > 1e-6f) ++j;
            ASSERT_LT(j, b.positions.size());
            EXPECT_NEAR(b.saturation[j], a.saturation[i], kStoredFloat) << format;
            EXPECT_NEAR(b.alpha[j], a.alpha[i], kColourMapped)
                << format << " (logistic colour mapping)";
            EXPECT_NEAR((b.normals[j] - a.normals[i]).norm(), 0.f, kColourMapped) << format;
        }
        std::vector<int32_t> fragments = b.face_fragment;
        std::sort(fragments.begin(), fragments.end());
        EXPECT_EQ(fragments, (std::vector<int32_t>{3, 3, 3, 3, 8, 8, 8, 8})) << format;
        // the crack mesh had no colours or fragments, and gets none back
        const TriMesh c = import_meshes(path)[1];
        EXPECT_TRUE(c.saturation.empty()) << format;
        EXPECT_TRUE(c.face_fragment.empty()) << format;
    }
}

TEST(MeshExport, SharedVerticesAreSplitPerFragment) {
    ScratchDir dir;
    TriMesh m = crack_mesh();
    m.face_fragment = {0, 1};  // the two triangles share the diagonal 0-2
    for (const std::string format : {"glb", "dae"}) {
        export_meshes(dir / ("split." + format), {m}, format);
        const TriMesh b = import_meshes(dir / ("split." + format))[0];
        EXPECT_EQ(b.positions.size(), 6u) << format;
        EXPECT_EQ(b.faces.size(), 2u) << format;
        ASSERT_EQ(b.face_fragment.size(), 2u) << format;
        EXPECT_NE(b.face_fragment[0], b.face_fragment[1]) << format;
        expect_same_corners(m, b, format);
    }
}

TEST(MeshExport, GlbKeepsVerticesThatDifferOnlyInColour) {
    // assimp's glb2 exporter joined vertices equal in position, normal and UV 0; the streamed
    // writer keeps every vertex, so colours survive where a crack's two sides meet
    ScratchDir dir;
    TriMesh m = crack_mesh();
    m.positions.push_back(m.positions[0]);
    m.uvs.push_back(m.uvs[0]);
    m.saturation = {0.1f, 0.2f, 0.3f, 0.4f, 0.9f};
    m.faces.push_back({4, 1, 3});
    export_meshes(dir / "colour.glb", {m}, "glb");
    const TriMesh b = import_meshes(dir / "colour.glb")[0];
    EXPECT_EQ(b.positions.size(), 5u);
    ASSERT_EQ(b.saturation.size(), 5u);
    std::vector<float> s = b.saturation;
    std::sort(s.begin(), s.end());
    EXPECT_FLOAT_EQ(s.front(), 0.1f);
    EXPECT_FLOAT_EQ(s.back(), 0.9f);
    // a glb comes back vertex for vertex, even two vertices equal in every attribute (the
    // Blender add-on reads the stored arrays, and the counts must agree); corner-per-vertex
    // formats are joined on import
    m.saturation.back() = m.saturation[0];
    for (const std::string format : {"glb", "dae"}) {
        export_meshes(dir / ("twin." + format), {m}, format);
        EXPECT_EQ(import_meshes(dir / ("twin." + format))[0].positions.size(),
                  format == "glb" ? 5u : 4u)
            << format;
    }
}

TEST(MeshExport, GlbLayoutIsValidBinaryGltf) {
    // the container by hand: header, a JSON chunk padded with spaces, a BIN chunk of the
    // declared length; a mesh without faces keeps its node and gets no glTF mesh
    ScratchDir dir;
    TriMesh empty;
    empty.name = "crack";
    export_meshes(dir / "layout.glb", {boundary_mesh(), empty}, "glb");
    const std::string bytes = test::read_file(dir / "layout.glb");
    auto u32 = [&](size_t at) {
        uint32_t v = 0;
        for (int k = 3; k >= 0; --k) v = (v << 8) | uint8_t(bytes[at + k]);
        return v;
    };
    ASSERT_GE(bytes.size(), 28u);
    EXPECT_EQ(bytes.substr(0, 4), "glTF");
    EXPECT_EQ(u32(4), 2u);
    EXPECT_EQ(u32(8), bytes.size());
    const uint32_t json_length = u32(12);
    EXPECT_EQ(json_length % 4, 0u);
    EXPECT_EQ(bytes.substr(16, 4), "JSON");
    const size_t bin = 20 + json_length;
    EXPECT_EQ(bytes.substr(bin + 4, 4), std::string("BIN\0", 4));
    EXPECT_EQ(bin + 8 + u32(bin), bytes.size());
    const std::string text = bytes.substr(20, json_length);
    EXPECT_NE(text.find("\"name\":\"crack\""), std::string::npos)
        << "the empty mesh's node is kept";
    EXPECT_EQ(text.find("crack_material"), std::string::npos) << "no glTF mesh for an empty mesh";
    const std::vector<TriMesh> back = import_meshes(dir / "layout.glb");
    ASSERT_EQ(back.size(), 1u);
    EXPECT_EQ(back[0].faces.size(), 8u);
}

// a frame whose soil is all debris (the plates mode) has an empty boundary mesh: every format
// writes it as a file its readers open, with no faces (ply's exporter used to refuse it)
TEST(MeshExport, EmptyMeshIsAValidEmptyFileInEveryFormat) {
    ScratchDir dir;
    TriMesh empty;
    empty.name = "boundary";
    for (const std::string format : {"glb", "obj", "ply", "dae"}) {
        const auto path = dir / ("empty." + format);
        ASSERT_NO_THROW(export_meshes(path, {empty}, format)) << format;
        size_t faces = 0;
        for (const TriMesh& m : import_meshes(path)) faces += m.faces.size();
        EXPECT_EQ(faces, 0u) << format;
        export_meshes(dir / ("again." + format), {empty}, format);
        EXPECT_EQ(test::read_file(path).size(), test::read_file(dir / ("again." + format)).size())
            << format;
    }
    // assimp's COLLADA reader turned a scene without meshes into pyramids drawing its nodes (8
    // faces here): as a mesh source, the empty dae has no triangles
    test::expect_input_error_naming([&] { load_input_surface(dir / "empty.dae"); },
                                    "the mesh has no triangles");
}

TEST(MeshExport, InconsistentMeshesAreRefusedNamingTheFile) {
    ScratchDir dir;
    for (const std::string format : {"glb", "obj"}) {
        TriMesh bad_face = crack_mesh();
        bad_face.faces.push_back({0, 1, 7});
        EXPECT_THROW(
            {
                try {
                    export_meshes(dir / ("bad." + format), {bad_face}, format);
                } catch (const RuntimeError& e) {
                    EXPECT_NE(
                        std::string(e.what()).find(
                            "bad." + format + ": mesh 'crack' face 2 references vertex 7 of 4"),
                        std::string::npos)
                        << e.what();
                    throw;
                }
            },
            RuntimeError);
        TriMesh bad_uvs = crack_mesh();
        bad_uvs.uvs.pop_back();
        EXPECT_THROW(export_meshes(dir / ("uvs." + format), {bad_uvs}, format), RuntimeError)
            << format;
        EXPECT_FALSE(std::filesystem::exists(dir / ("bad." + format))) << "no partial file";
    }
}

TEST(MeshExport, DeterministicBytesAndDccFriendlyText) {
    ScratchDir dir;
    for (const std::string format : {"glb", "obj", "ply", "dae"}) {
        export_meshes(dir / ("a." + format), kMeshes, format);
        export_meshes(dir / ("b." + format), kMeshes, format);
        const std::string a = test::read_file(dir / ("a." + format));
        std::string b = test::read_file(dir / ("b." + format));
        if (format == "obj") {
            // the files name their own material library
            EXPECT_NE(a.find("mtllib a.mtl"), std::string::npos);
            EXPECT_TRUE(std::filesystem::exists(dir / "a.mtl"));
            b.replace(b.find("mtllib b.mtl"), 12, "mtllib a.mtl");
        }
        EXPECT_GT(a.size(), 100u) << format;
        EXPECT_TRUE(a == b) << format << " output differs between two identical exports";
        EXPECT_FALSE(std::filesystem::exists(dir / ("a." + format + ".tmp")));
    }
    const std::string obj = test::read_file(dir / "a.obj");
    EXPECT_NE(obj.find("o boundary\ng boundary"), std::string::npos)
        << "Blender 3.4 needs `o` lines";
    EXPECT_NE(obj.find("o crack\ng crack"), std::string::npos);
    const std::string dae = test::read_file(dir / "a.dae");
    EXPECT_NE(dae.find("<created>1970-01-01T00:00:00</created>"), std::string::npos);
    // a glb from export_meshes is also a valid input surface (binary glTF loads)
    const InputSurface s = load_input_surface(dir / "a.glb");
    EXPECT_EQ(s.faces.size(), 10u);
    EXPECT_EQ(s.positions.size(), 12u);
    EXPECT_EQ(s.face_uv.size(), 10u);
}

TEST(MeshExport, FormatsAndRefusals) {
    EXPECT_TRUE(is_supported_mesh_format("glb"));
    EXPECT_TRUE(is_supported_mesh_format("obj"));
    EXPECT_TRUE(is_supported_mesh_format("ply"));
    EXPECT_TRUE(is_supported_mesh_format("dae"));
    EXPECT_FALSE(is_supported_mesh_format("fbx"));
    EXPECT_FALSE(is_supported_mesh_format("abc"));
    EXPECT_EQ(mesh_format_refusal("glb"), "");
    EXPECT_NE(mesh_format_refusal("fbx").find("4686"), std::string::npos);
    EXPECT_NE(mesh_format_refusal("usd").find("expected glb, obj, ply or dae"), std::string::npos);
    ScratchDir dir;
    test::expect_input_error_naming([&] { export_meshes(dir / "x.fbx", kMeshes, "fbx"); },
                                    "x.fbx: fbx is not supported");
    EXPECT_FALSE(std::filesystem::exists(dir / "x.fbx"));
    test::expect_input_error_naming([&] { import_meshes(dir / "missing.glb"); }, "missing.glb");
    test::write_file(dir / "garbage.glb", "glTF\x02garbage-garbage-garbage");
    test::expect_input_error_naming([&] { import_meshes(dir / "garbage.glb"); }, "garbage.glb");
}

}  // namespace
}  // namespace mudcrack
