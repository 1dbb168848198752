// OpenVDB points caches: round trips, ordering, determinism, metadata, and bad files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>

#include "pipeline/io/points_io.h"
#include "scratch_dir.h"
#include "sim/core/error.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

using test::ScratchDir;

constexpr double kVoxel = 0.05;

// a seeded cloud with every attribute kind, ids shuffled so the reader must sort
PointCloud random_cloud(size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> pos(-2.f, 3.f), unit(0.f, 1.f);
    PointCloud c;
    c.P.resize(n);
    for (auto& p : c.P) p = Vec3f(pos(rng), pos(rng), pos(rng));
    c.id.resize(n);
    std::iota(c.id.begin(), c.id.end(), 0);
    std::shuffle(c.id.begin(), c.id.end(), rng);
    std::vector<float> theta(n), s(n);
    for (size_t i = 0; i < n; ++i) {
        theta[i] = 0.45f * unit(rng);
        s[i] = unit(rng);
    }
    c.floats = {{"theta", theta}, {"saturation", s}};
    std::vector<Vec3f> v(n);
    for (auto& x : v) x = Vec3f(unit(rng) - .5f, unit(rng) - .5f, -unit(rng));
    c.vec3s = {{"v", v}};
    std::vector<Mat3f> F(n);
    for (auto& m : F)
        for (int k = 0; k < 9; ++k)
            m.data()[k] = (k % 4 == 0 ? 1.f : 0.f) + 0.1f * (unit(rng) - .5f);
    c.mat3s = {{"Fe", F}};
    c.meta_string["mudcrack:stage"] = "init";
    c.meta_double["mudcrack:time"] = 0.125;
    c.meta_int["mudcrack:frame"] = 7;
    return c;
}

// index of each id in a cloud
std::vector<size_t> slot_of_id(const PointCloud& c) {
    std::vector<size_t> slot(c.id.size());
    for (size_t i = 0; i < c.id.size(); ++i) slot[size_t(c.id[i])] = i;
    return slot;
}

TEST(PointsIo, RoundTripSortedByIdAtFloatPrecision) {
    ScratchDir dir;
    const PointCloud in = random_cloud(5000, 1);
    write_points(dir / "p.vdb", in, kVoxel);
    const PointCloud out = read_points(dir / "p.vdb");
    ASSERT_EQ(out.P.size(), in.P.size());
    for (size_t i = 0; i < out.id.size(); ++i) ASSERT_EQ(out.id[i], int32_t(i));
    const auto slot = slot_of_id(in);
    const auto* theta = out.find_float("theta");
    const auto* sat = out.find_float("saturation");
    const auto* v = out.find_vec3("v");
    const auto* F = out.find_mat3("Fe");
    ASSERT_TRUE(theta && sat && v && F);
    double max_rel = 0;
    for (size_t id = 0; id < out.P.size(); ++id) {
        const size_t j = slot[id];
        const double scale = std::max<double>(in.P[j].norm(), kVoxel);
        max_rel = std::max(max_rel, double((out.P[id] - in.P[j]).norm()) / scale);
        // NullCodec attributes are stored bit-exactly
        ASSERT_EQ((*theta)[id], in.floats[0].second[j]);
        ASSERT_EQ((*sat)[id], in.floats[1].second[j]);
        ASSERT_EQ((*v)[id], in.vec3s[0].second[j]);
        ASSERT_EQ((*F)[id], in.mat3s[0].second[j]) << "id " << id;
    }
    EXPECT_LT(max_rel, 1e-6);
    // attribute order follows the writer's order
    EXPECT_EQ(out.floats[0].first, "theta");
    EXPECT_EQ(out.floats[1].first, "saturation");
    // metadata: the cloud's plus ours
    EXPECT_EQ(out.meta_string, in.meta_string);
    EXPECT_EQ(out.meta_double, in.meta_double);
    EXPECT_EQ(out.meta_int.at("mudcrack:frame"), 7);
    EXPECT_EQ(out.meta_int.at("mudcrack:format_version"), kPointsFormatVersion);
    EXPECT_EQ(out.meta_int.at("mudcrack:point_count"), 5000);
    EXPECT_EQ(out.meta_int.size(), 3u);
}

TEST(PointsIo, SameInputGivesIdenticalBytes) {
    ScratchDir dir;
    const PointCloud in = random_cloud(3000, 2);
    write_points(dir / "a.vdb", in, kVoxel);
    write_points(dir / "b.vdb", in, kVoxel);
    const std::string a = test::read_file(dir / "a.vdb"), b = test::read_file(dir / "b.vdb");
    ASSERT_GT(a.size(), 3000u * 12);
    EXPECT_TRUE(a == b) << "files differ";
    // a different cloud gives a different header UUID (it is derived from the content)
    PointCloud other = in;
    other.P[0].x() += 0.01f;
    write_points(dir / "c.vdb", other, kVoxel);
    EXPECT_NE(a.substr(21, 36), test::read_file(dir / "c.vdb").substr(21, 36));
    EXPECT_FALSE(std::filesystem::exists(dir / "a.vdb.tmp"));
}

TEST(PointsIo, MetadataOnly) {
    ScratchDir dir;
    write_points(dir / "p.vdb", random_cloud(100, 3), kVoxel);
    const PointCloud meta = read_points_metadata(dir / "p.vdb");
    EXPECT_TRUE(meta.P.empty());
    EXPECT_EQ(meta.meta_string.at("mudcrack:stage"), "init");
    EXPECT_EQ(meta.meta_int.at("mudcrack:point_count"), 100);
    EXPECT_EQ(meta.meta_double.at("mudcrack:time"), 0.125);
}

TEST(PointsIo, EmptyCloudAndImplicitIds) {
    ScratchDir dir;
    PointCloud empty;
    write_points(dir / "e.vdb", empty, kVoxel);
    EXPECT_TRUE(read_points(dir / "e.vdb").P.empty());
    PointCloud two;
    two.P = {Vec3f(1, 2, 3), Vec3f(-1, 0, 0.5f)};
    write_points(dir / "t.vdb", two, kVoxel);
    const PointCloud back = read_points(dir / "t.vdb");
    ASSERT_EQ(back.id, (std::vector<int32_t>{0, 1}));
    EXPECT_NEAR(back.P[0].z(), 3.0, 3 * tol::kFloat * 0.1);
    EXPECT_NEAR(back.P[1].x(), -1.0, tol::kFloat * 0.1);
}

TEST(PointsIo, FrameRoundTrip) {
    ScratchDir dir;
    ParticleFrame f;
    f.frame = 42;
    f.time = 1.75;
    f.substeps = 33;
    for (int i = 0; i < 50; ++i) {
        f.P.emplace_back(0.01f * i, 0.5f, -0.02f * i);
        f.v.emplace_back(0, -0.1f * i, 0);
        f.saturation.push_back(0.02f * i);
        f.Jw.push_back(1.f - 0.001f * i);
        f.Fe.push_back(Mat3f::Identity() * (1.f + 0.01f * i));
    }
    write_points(frame_path(dir.path(), "particles", f.frame, "vdb"), frame_to_points(f), kVoxel);
    const auto path = dir / "particles.0042.vdb";
    ASSERT_TRUE(std::filesystem::exists(path));
    const PointCloud cloud = read_points(path);
    EXPECT_EQ(cloud.meta_string.at("mudcrack:stage"), "sim");
    const ParticleFrame g = points_to_frame(cloud, path.string());
    EXPECT_EQ(g.frame, 42);
    EXPECT_EQ(g.substeps, 33);
    EXPECT_EQ(g.time, 1.75);
    ASSERT_EQ(g.size(), 50u);
    EXPECT_TRUE(g.theta.empty());
    EXPECT_TRUE(g.alpha.empty());
    EXPECT_EQ(g.saturation, f.saturation);
    EXPECT_EQ(g.Jw, f.Jw);
    EXPECT_EQ(g.v, f.v);
    EXPECT_EQ(g.Fe, f.Fe);
    // float positions of order 1, written and read back
    for (int i = 0; i < 50; ++i) EXPECT_NEAR((g.P[i] - f.P[i]).norm(), 0.0, tol::kFloat * 0.1);
}

TEST(PointsIo, PointsToFrameRejectsBadIds) {
    PointCloud c;
    c.P = {Vec3f::Zero(), Vec3f::Ones(), Vec3f::Ones()};
    c.id = {2, 0, 1};
    const ParticleFrame f = points_to_frame(c, "x.vdb");  // a permutation is fine
    EXPECT_EQ(f.P[0], Vec3f::Ones());
    EXPECT_EQ(f.P[1], Vec3f::Ones());
    EXPECT_EQ(f.P[2], Vec3f::Zero());
    c.id = {0, 1, 1};
    test::expect_input_error_naming([&] { points_to_frame(c, "dup.vdb"); }, "dup.vdb");
    c.id = {0, 1, 3};
    test::expect_input_error_naming([&] { points_to_frame(c, "range.vdb"); }, "range.vdb");
    c.id = {0, 1, 2};
    c.floats = {{"saturation", {0.5f}}};
    test::expect_input_error_naming([&] { points_to_frame(c, "size.vdb"); }, "saturation");
}

TEST(PointsIo, FramePath) {
    EXPECT_EQ(frame_path("out/sim", "particles", 7, "vdb"),
              std::filesystem::path("out/sim/particles.0007.vdb"));
    EXPECT_EQ(frame_path("d", "crack", 12345, ".glb"), std::filesystem::path("d/crack.12345.glb"));
}

// overwrites the int64 value that follows metadata entry `key` (name, type name, size, value)
void patch_int64_meta(std::string& bytes, const std::string& key, int64_t value) {
    const size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const size_t value_at = at + key.size() + 4 + 5 + 4;  // len + "int64" + size
    ASSERT_EQ(bytes.substr(at + key.size() + 4, 5), "int64");
    std::memcpy(&bytes[value_at], &value, 8);
}

TEST(PointsIo, BadFilesNameTheFile) {
    ScratchDir dir;
    test::expect_input_error_naming([&] { read_points(dir / "missing.vdb"); }, "missing.vdb");
    test::expect_input_error_naming([&] { read_points_metadata(dir / "missing.vdb"); },
                                    "missing.vdb");

    test::write_file(dir / "garbage.vdb", std::string(4096, '\x5a'));
    test::expect_input_error_naming([&] { read_points(dir / "garbage.vdb"); }, "garbage.vdb");

    write_points(dir / "good.vdb", random_cloud(2000, 4), kVoxel);
    const std::string good = test::read_file(dir / "good.vdb");
    for (size_t keep : {size_t(0), size_t(10), size_t(200), good.size() / 2, good.size() - 100,
                        good.size() - 1}) {
        const std::string name = "truncated_" + std::to_string(keep) + ".vdb";
        test::write_file(dir / name, good.substr(0, keep));
        test::expect_input_error_naming([&] { read_points(dir / name); }, name);
    }

    std::string v2 = good;
    patch_int64_meta(v2, "mudcrack:format_version", 2);
    test::write_file(dir / "v2.vdb", v2);
    test::expect_input_error_naming([&] { read_points(dir / "v2.vdb"); }, "v2.vdb");
    test::expect_input_error_naming([&] { read_points_metadata(dir / "v2.vdb"); },
                                    "format_version = 2");

    // a VDB whose grid is not ours
    std::string foreign = good;
    for (size_t at = foreign.find("particles"); at != std::string::npos;
         at = foreign.find("particles", at + 1))
        foreign[at] = 'q';
    test::write_file(dir / "foreign.vdb", foreign);
    test::expect_input_error_naming([&] { read_points(dir / "foreign.vdb"); }, "foreign.vdb");
}

// OpenVDB would load a root tile's active flag byte as a bool (undefined behaviour for a byte
// other than 0 or 1): such a file is refused before OpenVDB parses it. mudcrack writes no root
// tiles, so one is spliced into a written file, its grid's block and end offsets moved past it.
TEST(PointsIo, RootTileActiveFlagMustBeABool) {
    ScratchDir dir;
    write_points(dir / "good.vdb", random_cloud(200, 5), kVoxel);
    std::string bytes = test::read_file(dir / "good.vdb");
    const std::string tree_type = "Tree_ptdataidx32_5_4_3";
    const size_t descriptor = bytes.find(tree_type);
    ASSERT_NE(descriptor, std::string::npos);
    // the empty instance parent's length
    const size_t offsets_at = descriptor + tree_type.size() + 4;
    const std::string map_type = "UniformScaleMap";
    const size_t map = bytes.find(map_type);
    ASSERT_NE(map, std::string::npos);
    // map, buffer count, background
    const size_t tile_count_at = map + map_type.size() + 120 + 4 + 4;
    uint32_t tiles = 99;
    std::memcpy(&tiles, &bytes[tile_count_at], 4);
    ASSERT_EQ(tiles, 0u);
    tiles = 1;
    std::memcpy(&bytes[tile_count_at], &tiles, 4);
    const int32_t tile[4] = {1 << 15, 0, 0, 0};  // origin x, y, z and the value
    std::string spliced(reinterpret_cast<const char*>(tile), sizeof tile);
    spliced += '\x5a';
    bytes.insert(tile_count_at + 8, spliced);
    for (int k = 1; k <= 2; ++k) {
        int64_t offset = 0;
        std::memcpy(&offset, &bytes[offsets_at + 8 * size_t(k)], 8);
        offset += int64_t(spliced.size());
        std::memcpy(&bytes[offsets_at + 8 * size_t(k)], &offset, 8);
    }
    test::write_file(dir / "tile.vdb", bytes);
    test::expect_input_error_naming([&] { read_points(dir / "tile.vdb"); },
                                    "root tile 0 active flag is byte 90");
    test::expect_input_error_naming([&] { read_points_metadata(dir / "tile.vdb"); }, "tile.vdb");
}

}  // namespace
}  // namespace mudcrack
