// mc-surface end to end on synthetic init/sim outputs: files, frame-order independence
// (byte-identical files), assimp round trip, and bad input (exit 1, file named, nothing written).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "pipeline/io/manifest.h"
#include "pipeline/io/mesh_io.h"
#include "pipeline/io/points_io.h"
#include "pipeline/io/tet_mesh_io.h"
#include "pipeline/shot/shot.h"
#include "surfacing/lattice_mesh.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

constexpr int kFrames = 4;

const char* kShot = R"({
  "mudcrack": 1,
  "name": "surface_cli",
  "source": { "type": "box", "box": { "min": [0, 0, 0], "max": [0.4, 0.1, 0.15], "spacing": 0.05 } },
  "material": { "density": 1, "youngs_modulus": 2000, "poisson_ratio": 0.35 },
  "moisture": { "eta": 0.4, "k_r": 1, "eps": 1, "D": 0.01, "lambda": 0.1, "theta0": 0 },
  "sim": { "h": 0.05 },
  "frames": { "start": 1, "end": 4, "fps": 24 },
  "surfacing": { "mode": "ours", "zeta": 1.5, "format": "glb" }
})";

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

struct CliRun {
    int code;
    std::string out, err;
};

class McSurfaceCli : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() /
                ("mudcrack_mc_surface_" + std::to_string(::getpid()) + "_" +
                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
        m_shot_path = m_dir / "shot.json";
        std::ofstream(m_shot_path) << kShot;
        m_shot = load_shot(m_shot_path.string());
        m_mesh = test::box_lattice(8, 2, 3, 0.05);
    }
    void TearDown() override { fs::remove_all(m_dir); }

    /// DIR/init and DIR/sim as mc-init and mc-sim would leave them: a slab that stretches
    /// along x more every frame and dries on its left half.
    void write_inputs(const fs::path& out) const {
        fs::create_directories(out / "init");
        fs::create_directories(out / "sim");
        write_tet_mesh_vtu(out / "init" / "tets.vtu", m_mesh);
        nlohmann::json init = make_manifest("init", m_shot.path, m_shot.slice_hash(Stage::Init));
        init["outputs"] = {file_record(out / "init" / "tets.vtu")};
        write_manifest(out / "init", init);
        for (int n = 1; n <= kFrames; ++n)
            write_points(cache(out, n), frame_to_points(frame(n)), 0.05);
        json_manifest(out);
    }
    /// The sim manifest, recording the checksums of the caches there are now.
    void json_manifest(const fs::path& out) const {
        nlohmann::json m = make_manifest("sim", m_shot.path, m_shot.slice_hash(Stage::Sim));
        m["frames"] = {{"first", 1}, {"last", kFrames}, {"count", kFrames}};
        m["caches"] = nlohmann::json::array();
        for (int n = 1; n <= kFrames; ++n)
            if (fs::exists(cache(out, n))) m["caches"].push_back(file_record(cache(out, n)));
        write_manifest(out / "sim", m);
    }
    ParticleFrame frame(int n) const {
        ParticleFrame f;
        f.frame = n;
        const double length = 0.4, k = 4 * M_PI / length, stretch = 0.25 * n;
        for (const Vec3& X : m_mesh.X) {
            f.P.push_back(
                Vec3(X.x() + stretch / k * std::sin(k * X.x()), X.y(), X.z()).cast<float>());
            f.Jw.push_back(X.x() < length / 2 ? 1.f - 0.08f * n : 1.f);
            f.saturation.push_back(X.x() < length / 2 ? 1.f - 0.2f * n : 1.f);
            f.alpha.push_back(-0.01f * n);
            f.Fe.push_back(Eigen::AngleAxis<Real>(0.1 * n * X.y(), Vec3(0, 0, 1))
                               .toRotationMatrix()
                               .cast<float>());
        }
        return f;
    }
    static fs::path cache(const fs::path& out, int n) {
        return frame_path(out / "sim", "particles", n, "vdb");
    }

    CliRun mc_surface(const fs::path& out, const std::string& args = "") const {
        const fs::path o = m_dir / "stdout.txt", e = m_dir / "stderr.txt";
        const std::string cmd = std::string(MUDCRACK_BIN_DIR) + "/mc-surface --shot " +
                                m_shot_path.string() + " --out " + out.string() + " " + args +
                                " >" + o.string() + " 2>" + e.string();
        const int status = std::system(cmd.c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_bytes(o), read_bytes(e)};
    }

    fs::path m_dir, m_shot_path;
    Shot m_shot;
    TetMesh m_mesh;
};

TEST_F(McSurfaceCli, NoArgumentsIsBadUsage) {
    const int status =
        std::system((std::string(MUDCRACK_BIN_DIR) + "/mc-surface >/dev/null 2>&1").c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2);
}

TEST_F(McSurfaceCli, FramesInAnyOrderGiveByteIdenticalFilesThatRoundTrip) {
    const fs::path in_order = m_dir / "a", reversed = m_dir / "b";
    write_inputs(in_order);
    write_inputs(reversed);
    const CliRun all = mc_surface(in_order);
    ASSERT_EQ(all.code, 0) << all.err;
    for (int n = kFrames; n >= 1; --n) {
        const CliRun one = mc_surface(reversed, "--frames " + std::to_string(n));
        ASSERT_EQ(one.code, 0) << one.err;
    }
    const nlohmann::json manifest = read_manifest(in_order / "surface");
    const nlohmann::json merged = read_manifest(reversed / "surface");
    EXPECT_EQ(merged["frames"]["count"], kFrames);
    EXPECT_EQ(merged["break_history"]["reused"], true);  // the last --frames run reused the history
    EXPECT_EQ(manifest["per_frame"].size(), size_t(kFrames));
    int64_t previous_broken = -1;
    for (int n = 1; n <= kFrames; ++n) {
        const nlohmann::json& entry = manifest["per_frame"][n - 1];
        EXPECT_EQ(entry["broken_edges"], merged["per_frame"][n - 1]["broken_edges"]);
        EXPECT_GE(entry["broken_edges"].get<int64_t>(), previous_broken);  // breaks are permanent
        previous_broken = entry["broken_edges"].get<int64_t>();
        for (const char* stem : {"boundary", "crack"}) {
            const fs::path a = frame_path(in_order / "surface", stem, n, "glb");
            const fs::path b = frame_path(reversed / "surface", stem, n, "glb");
            if (entry[stem]["faces"] == 0) {  // no cracks yet: no crack file
                EXPECT_TRUE(entry[stem]["file"].is_null());
                EXPECT_FALSE(fs::exists(a)) << a;
                EXPECT_FALSE(fs::exists(b)) << b;
                continue;
            }
            ASSERT_TRUE(fs::exists(a)) << a;
            EXPECT_EQ(read_bytes(a), read_bytes(b)) << a << " vs " << b;
            // round trip through assimp: same counts and a UV channel
            const std::vector<TriMesh> back = import_meshes(a);
            ASSERT_EQ(back.size(), 1u) << a;
            EXPECT_EQ(back[0].faces.size(), entry[stem]["faces"].get<size_t>()) << a;
            EXPECT_EQ(back[0].positions.size(), entry[stem]["vertices"].get<size_t>()) << a;
            if (!back[0].faces.empty()) {
                EXPECT_EQ(back[0].uvs.size(), back[0].positions.size()) << a;
            }
        }
    }
    EXPECT_GT(previous_broken, 0);
    EXPECT_GT(manifest["per_frame"][kFrames - 1]["crack"]["faces"].get<int64_t>(), 0);
    EXPECT_GT(manifest["tets_per_second"].get<double>(), 0.0);
    EXPECT_TRUE(fs::exists(in_order / "surface" / "edge_breaks.bin"));
    EXPECT_FALSE(fs::exists(in_order / ".surface.partial"));
}

TEST_F(McSurfaceCli, AFailedUpdateInPlaceKeepsThePreviousFiles) {
    const fs::path out = m_dir / "out";
    write_inputs(out);
    ASSERT_EQ(mc_surface(out).code, 0);
    const fs::path surface = out / "surface";
    std::map<std::string, std::string> before;
    for (const auto& e : fs::directory_iterator(surface))
        before[e.path().filename().string()] = read_bytes(e.path());
    // --frames over the finished folder updates it in place. A disk that fills between a frame's
    // boundary mesh and its (larger) crack mesh: files limited to whole 512-byte blocks (ulimit
    // -f), SIGXFSZ ignored so the write fails with EFBIG
    int frame = 0;
    size_t blocks = 0;
    for (int n = 1; n <= kFrames && frame == 0; ++n) {
        const std::string crack = frame_path({}, "crack", n, "glb").string();
        const std::string boundary = frame_path({}, "boundary", n, "glb").string();
        if (!before.count(crack) || before[crack].empty()) continue;
        blocks = (before[crack].size() - 1) / 512;
        if (before[boundary].size() <= blocks * 512) frame = n;
    }
    ASSERT_NE(frame, 0)
        << "no frame has a crack file larger than its boundary mesh by a 512-byte block";
    const fs::path e = m_dir / "stderr.txt";
    const std::string cmd = "trap '' XFSZ; ulimit -f " + std::to_string(blocks) + "; " +
                            std::string(MUDCRACK_BIN_DIR) + "/mc-surface --threads 1 --shot " +
                            m_shot_path.string() + " --out " + out.string() + " --frames " +
                            std::to_string(frame) + " >/dev/null 2>" + e.string();
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1) << read_bytes(e);
    EXPECT_NE(read_bytes(e).find("File too large"), std::string::npos) << read_bytes(e);
    // every file of the folder is as it was (crack meshes included), and nothing was added
    std::map<std::string, std::string> after;
    for (const auto& f : fs::directory_iterator(surface))
        after[f.path().filename().string()] = read_bytes(f.path());
    EXPECT_EQ(after.size(), before.size());
    for (const auto& [name, bytes] : before) {
        ASSERT_TRUE(after.count(name)) << name << " was lost";
        EXPECT_TRUE(after[name] == bytes) << name << " changed";
    }
    EXPECT_FALSE(fs::exists(out / ".surface.partial"));
}

TEST_F(McSurfaceCli, ObjAndWang2019Work) {
    const fs::path out = m_dir / "out";
    write_inputs(out);
    const CliRun ours = mc_surface(out, "--format obj");
    ASSERT_EQ(ours.code, 0) << ours.err;
    const int64_t ours_broken =
        read_manifest(out / "surface")["per_frame"][kFrames - 1]["broken_edges"];
    const std::vector<TriMesh> back =
        import_meshes(frame_path(out / "surface", "boundary", 2, "obj"));
    ASSERT_EQ(back.size(), 1u);
    EXPECT_FALSE(back[0].uvs.empty());
    const CliRun wang = mc_surface(out, "--mode wang2019");
    ASSERT_EQ(wang.code, 0) << wang.err;
    const nlohmann::json m = read_manifest(out / "surface");
    EXPECT_EQ(m["mode"], "wang2019");
    // the dry half breaks under Eq. 14 but not under the constant threshold
    EXPECT_LT(m["per_frame"][kFrames - 1]["broken_edges"].get<int64_t>(), ours_broken);
}

// mc-render frames a shot from the manifest's per-frame bounds instead of reading every frame's
// meshes: they must be the bounds of what a reader of the files gets, to the float, in every
// format (glb keeps the vertex arrays; obj readers rebuild vertices from face corners)
TEST_F(McSurfaceCli, ManifestBoundsAreTheBoundsOfTheFilesVertices) {
    for (const char* format : {"glb", "obj"}) {
        SCOPED_TRACE(format);
        const fs::path out = m_dir / format;
        write_inputs(out);
        const CliRun run = mc_surface(out, std::string("--format ") + format);
        ASSERT_EQ(run.code, 0) << run.err;
        const nlohmann::json manifest = read_manifest(out / "surface");
        ASSERT_EQ(manifest["per_frame"].size(), size_t(kFrames));
        for (const nlohmann::json& entry : manifest["per_frame"]) {
            const int n = entry["frame"].get<int>();
            Vec3f lo = Vec3f::Constant(INFINITY), hi = Vec3f::Constant(-INFINITY);
            for (const char* stem : {"boundary", "crack"}) {
                if (entry[stem]["file"].is_null()) continue;
                for (const TriMesh& m : import_meshes(frame_path(out / "surface", stem, n, format)))
                    for (const Vec3f& p : m.positions) {
                        lo = lo.cwiseMin(p);
                        hi = hi.cwiseMax(p);
                    }
            }
            ASSERT_TRUE(entry.contains("bounds")) << "frame " << n;
            ASSERT_TRUE(entry["bounds"].is_object()) << "frame " << n;
            for (int k = 0; k < 3; ++k) {
                EXPECT_EQ(entry["bounds"]["min"][k].get<float>(), lo[k])
                    << "frame " << n << " axis " << k;
                EXPECT_EQ(entry["bounds"]["max"][k].get<float>(), hi[k])
                    << "frame " << n << " axis " << k;
            }
        }
    }
}

TEST_F(McSurfaceCli, BadInputFailsNamingTheFileAndWritesNothing) {
    const fs::path out = m_dir / "out";
    write_inputs(out);
    // a truncated cache
    const std::string bytes = read_bytes(cache(out, 3));
    std::ofstream(cache(out, 3), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    CliRun r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("particles.0003.vdb: damaged"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));
    EXPECT_FALSE(fs::exists(out / ".surface.partial"));
    // the same, truncated by a writer that recorded it so: the reader's own checks name it
    json_manifest(out);
    r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("particles.0003.vdb"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));

    // a cache from another shot: other particle count
    ParticleFrame other = frame(3);
    other.P.resize(other.P.size() - 5);
    other.Jw.resize(other.P.size());
    other.saturation.resize(other.P.size());
    other.alpha.resize(other.P.size());
    other.Fe.resize(other.P.size());
    write_points(cache(out, 3), frame_to_points(other), 0.05);
    json_manifest(out);
    r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("particles.0003.vdb"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("the tet mesh has"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));

    // a missing cache
    fs::remove(cache(out, 3));
    r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("particles.0003.vdb"), std::string::npos) << r.err;

    // fbx is refused with the reason, as a flag's bad value: a usage error
    r = mc_surface(out, "--format fbx");
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("fbx"), std::string::npos) << r.err;

    // frames outside the cache
    r = mc_surface(out, "--frames 2-9");
    EXPECT_EQ(r.code, 2);  // a usage error
    EXPECT_NE(r.err.find("--frames"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));
}

/// kShot with its /surfacing section replaced.
std::string shot_with_surfacing(const std::string& surfacing) {
    std::string shot = kShot;
    const size_t at = shot.find("\"surfacing\"");
    return shot.substr(0, at) + "\"surfacing\": " + surfacing + "\n}";
}

TEST_F(McSurfaceCli, PlatesFramesInAnyOrderGiveByteIdenticalClosedPiecesAndDebris) {
    std::ofstream(m_shot_path) << shot_with_surfacing(
        R"({ "mode": "plates", "zeta": 1.5, "format": "glb", "min_piece_size": 1, "debris": "points" })");
    const fs::path in_order = m_dir / "a", chunked = m_dir / "b";
    write_inputs(in_order);
    write_inputs(chunked);
    const CliRun all = mc_surface(in_order);
    ASSERT_EQ(all.code, 0) << all.err;
    for (const char* chunk : {"3-4", "1-2"}) {
        const CliRun one = mc_surface(chunked, std::string("--frames ") + chunk);
        ASSERT_EQ(one.code, 0) << one.err;
    }
    const nlohmann::json m = read_manifest(in_order / "surface");
    EXPECT_EQ(m["mode"], "plates");
    for (int n = 1; n <= kFrames; ++n) {
        const nlohmann::json& entry = m["per_frame"][n - 1];
        EXPECT_GE(entry["pieces"].get<int>(), 1);
        for (const char* stem : {"boundary", "crack"}) {
            if (entry[stem]["file"].is_null()) continue;
            const fs::path a = frame_path(in_order / "surface", stem, n, "glb");
            EXPECT_EQ(read_bytes(a), read_bytes(frame_path(chunked / "surface", stem, n, "glb")))
                << a;
        }
        const fs::path debris = frame_path(in_order / "surface", "debris", n, "ply");
        ASSERT_TRUE(fs::exists(debris)) << debris;
        EXPECT_EQ(read_bytes(debris),
                  read_bytes(frame_path(chunked / "surface", "debris", n, "ply")));
        EXPECT_EQ(entry["debris"]["points"], entry["debris_particles"]);
    }
    EXPECT_GT(m["per_frame"][kFrames - 1]["crack"]["faces"].get<int64_t>(), 0);
}

// a piece size just under the soil's width (0.2 m) leaves every piece too narrow once the slab
// cracks: frames whose soil is all debris have an empty boundary mesh, which every format writes as
// a file of its kind with no faces (assimp's PLY exporter refused it: "could not export ply")
TEST_F(McSurfaceCli, PlatesFramesOfOnlyDebrisWriteEmptyMeshesInEveryFormat) {
    for (const std::string format : {"ply", "obj", "dae", "glb"}) {
        std::ofstream(m_shot_path) << shot_with_surfacing(
            R"({ "mode": "plates", "zeta": 1.5, "min_piece_size": 3.9, "format": ")" + format +
            "\" }");
        const fs::path out = m_dir / format;
        write_inputs(out);
        const CliRun r = mc_surface(out);
        ASSERT_EQ(r.code, 0) << format << ": " << r.err;
        int empty_frames = 0;
        const nlohmann::json manifest = read_manifest(out / "surface");
        for (const nlohmann::json& entry : manifest["per_frame"]) {
            const fs::path file = out / "surface" / entry["boundary"]["file"].get<std::string>();
            size_t faces = 0;
            for (const TriMesh& mesh : import_meshes(file)) faces += mesh.faces.size();
            EXPECT_EQ(faces, entry["boundary"]["faces"].get<size_t>()) << file;
            empty_frames += faces == 0 ? 1 : 0;
        }
        EXPECT_GT(empty_frames, 0) << format << ": no frame of only debris to test";
    }
}

TEST_F(McSurfaceCli, PlatesBadInputNamesTheKeyAndWritesNothing) {
    const fs::path out = m_dir / "out";
    write_inputs(out);
    // a piece size wider than the soil (0.4 x 0.1 x 0.15 m; 100 cells of 0.05 m = 5 m)
    std::ofstream(m_shot_path) << shot_with_surfacing(
        R"({ "mode": "plates", "min_piece_size": 100 })");
    CliRun r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("/surfacing/min_piece_size = 100"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("wider than the soil"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));
    EXPECT_FALSE(fs::exists(out / ".surface.partial"));
    // debris asked of a mode that has none: the shot, and --mode over a plates shot
    std::ofstream(m_shot_path) << shot_with_surfacing(R"({ "mode": "ours", "debris": "points" })");
    r = mc_surface(out);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("/surfacing/debris = \"points\": needs /surfacing/mode = \"plates\""),
              std::string::npos)
        << r.err;
    std::ofstream(m_shot_path) << shot_with_surfacing(
        R"({ "mode": "plates", "debris": "points" })");
    r = mc_surface(out, "--mode wang2019");
    EXPECT_EQ(r.code, 2);  // the flag is refused for this shot, as --frames past it is
    EXPECT_NE(r.err.find("--mode wang2019"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("/surfacing/debris"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "surface"));
}

}  // namespace
}  // namespace mudcrack
