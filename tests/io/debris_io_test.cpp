// Debris point files (pipeline/io/debris_io.h): round trip, layout, and refusals that name the
// file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline/io/debris_io.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

namespace fs = std::filesystem;

class DebrisIo : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("mudcrack_debris_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
    fs::path dir;
};

DebrisPoints two_grains() {
    DebrisPoints d;
    d.position = {Vec3f(0.1f, 0.2f, 0.3f), Vec3f(-1, 2, -3)};
    d.velocity = {Vec3f(0, 1, 0), Vec3f(4, 5, 6)};
    d.radius = {0.0075f, 0.006f};
    d.id = {17, 45000};
    d.piece = {0, -1};
    return d;
}

TEST_F(DebrisIo, RoundTripsEveryFieldBitForBit) {
    const fs::path path = dir / "debris.0001.ply";
    write_debris_ply(path, two_grains());
    const DebrisPoints back = read_debris_ply(path);
    const DebrisPoints want = two_grains();
    EXPECT_EQ(back.position, want.position);
    EXPECT_EQ(back.velocity, want.velocity);
    EXPECT_EQ(back.radius, want.radius);
    EXPECT_EQ(back.id, want.id);
    EXPECT_EQ(back.piece, want.piece);
    // 9 properties of 4 bytes per point after the header: what any PLY reader expects
    std::ifstream in(path, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t body = text.find("end_header\n") + 11;
    EXPECT_EQ(text.size() - body, 2u * 36u);
    EXPECT_NE(text.find("element vertex 2\n"), std::string::npos);
    EXPECT_NE(text.find("property float pscale\n"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir / "debris.0001.ply.tmp"));
}

TEST_F(DebrisIo, AnEmptyFrameIsAValidFile) {
    write_debris_ply(dir / "e.ply", DebrisPoints());
    EXPECT_EQ(read_debris_ply(dir / "e.ply").size(), 0u);
}

TEST_F(DebrisIo, TruncatedForeignAndMissingFilesAreRefusedByName) {
    const fs::path path = dir / "d.ply";
    write_debris_ply(path, two_grains());
    fs::resize_file(path, fs::file_size(path) - 3);
    try {
        read_debris_ply(path);
        FAIL() << "a truncated file was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
    std::ofstream(dir / "foreign.ply")
        << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n";
    EXPECT_THROW(read_debris_ply(dir / "foreign.ply"), InputError);
    std::ofstream(dir / "count.ply")
        << "ply\nformat binary_little_endian 1.0\nelement vertex x\nend_header\n";
    EXPECT_THROW(read_debris_ply(dir / "count.ply"), InputError);
    EXPECT_THROW(read_debris_ply(dir / "missing.ply"), InputError);
}

}  // namespace
}  // namespace mudcrack
