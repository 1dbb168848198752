// manifest.json: common fields, atomic pretty write, the "run mc-<stage> first" message, and the
// file records (CRC-32) readers verify files against.
#include <gtest/gtest.h>

#include <zlib.h>

#include <fstream>
#include <random>
#include <regex>
#include <vector>

#include "pipeline/io/checksum.h"
#include "pipeline/io/manifest.h"
#include "scratch_dir.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

using test::ScratchDir;

TEST(Manifest, CommonFields) {
    const nlohmann::json m = make_manifest("sim", "shots/demo.json", "abc123");
    EXPECT_EQ(m.at("stage"), "sim");
    EXPECT_EQ(m.at("version"), MUDCRACK_VERSION);
    EXPECT_EQ(m.at("shot"), "shots/demo.json");
    EXPECT_EQ(m.at("shot_slice_hash"), "abc123");
    const std::string time = m.at("created_utc");
    EXPECT_TRUE(
        std::regex_match(time, std::regex(R"(20\d\d-[01]\d-[0-3]\dT[0-2]\d:[0-5]\d:[0-6]\dZ)")))
        << time;
    EXPECT_FALSE(m.at("host").get<std::string>().empty());
    EXPECT_GE(m.at("threads").get<int>(), 1);
    EXPECT_GE(m.at("host_threads").get<int>(), 1);
}

TEST(Manifest, WriteReadRoundTrip) {
    ScratchDir dir;
    nlohmann::json m = make_manifest("init", "s.json", "h");
    m["frames"] = {{"first", 1}, {"last", 24}};
    m["rates"] = {{"tets_per_s", 66500.5}};
    write_manifest(dir.path(), m);
    EXPECT_EQ(read_manifest(dir.path()), m);
    EXPECT_FALSE(std::filesystem::exists(dir / "manifest.json.tmp"));
    const std::string text = test::read_file(dir / "manifest.json");
    EXPECT_NE(text.find("\n  \"frames\": {\n"), std::string::npos)
        << "pretty-printed with 2 spaces";
}

TEST(Manifest, MissingOrMalformed) {
    ScratchDir dir;
    std::filesystem::create_directories(dir / "init");
    test::expect_input_error_naming([&] { read_manifest(dir / "init"); },
                                    "init/manifest.json: missing: run mc-init first");
    test::expect_input_error_naming([&] { read_manifest(dir / "sim"); }, "run mc-sim first");
    test::write_file(dir / "init" / "manifest.json", "{ \"stage\": ");
    test::expect_input_error_naming([&] { read_manifest(dir / "init"); },
                                    "init/manifest.json: malformed");
    test::write_file(dir / "init" / "manifest.json", "[1, 2]");
    test::expect_input_error_naming([&] { read_manifest(dir / "init"); }, "expected a JSON object");
}

// the one check every stage makes of the manifest it reads: each refusal names the file, the key
// and the value, and the stage to re-run
TEST(Manifest, CurrentManifestIsChecked) {
    ScratchDir dir;
    const std::filesystem::path sim = dir / "sim";
    std::filesystem::create_directories(sim);
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); },
                                    "sim/manifest.json: missing: run mc-sim first");
    test::write_file(sim / "manifest.json", "{ \"stage\": ");
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); },
                                    "sim/manifest.json: malformed");

    nlohmann::json m = make_manifest("sim", "s.json", "abc");
    m.erase("shot_slice_hash");
    write_manifest(sim, m);
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); },
                                    "sim/manifest.json: /shot_slice_hash: missing");
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); }, "re-run mc-sim");
    m["shot_slice_hash"] = 42;
    write_manifest(sim, m);
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); },
                                    "sim/manifest.json: /shot_slice_hash = 42: not a slice hash");
    m["shot_slice_hash"] = "old";
    write_manifest(sim, m);
    test::expect_input_error_naming(
        [&] { read_current_manifest(sim, "abc"); },
        "sim/manifest.json: /shot_slice_hash = \"old\": stale for this shot "
        "(expected \"abc\"): re-run mc-sim");

    m["shot_slice_hash"] = "abc";
    write_manifest(sim, m);
    EXPECT_EQ(read_current_manifest(sim, "abc"), m);
}

TEST(FileChecksum, IsZlibsCrc32) {
    ScratchDir dir;
    std::ofstream(dir / "a.txt", std::ios::binary) << "123456789";  // CRC-32's check value
    EXPECT_EQ(file_crc32(dir / "a.txt"), "cbf43926");
    std::ofstream(dir / "empty", std::ios::binary).close();
    EXPECT_EQ(file_crc32(dir / "empty"), "00000000");
    EXPECT_THROW(file_crc32(dir / "missing"), InputError);
}

// the carry-less folding and zlib's tables agree on every length (below, at and past the 64 bytes
// folding starts at, and not a multiple of 16), whole or continued in two pieces
TEST(FileChecksum, FoldingMatchesZlibAtEveryLength) {
    std::mt19937 rng(7);
    std::vector<unsigned char> bytes(4099);
    for (unsigned char& b : bytes) b = static_cast<unsigned char>(rng());
    for (size_t n = 0; n <= bytes.size(); n += (n < 300 ? 1 : 37)) {
        const uint32_t expected = uint32_t(crc32(0, bytes.data(), uInt(n)));
        EXPECT_EQ(crc32_update(0, bytes.data(), n), expected) << n << " bytes";
        const size_t half = n / 3;
        EXPECT_EQ(crc32_update(crc32_update(0, bytes.data(), half), bytes.data() + half, n - half),
                  expected)
            << n << " bytes in two pieces";
    }
}

TEST(RecordedChecksums, FindsRecordsAnywhereAndCatchesEveryFlippedByte) {
    ScratchDir dir;
    const std::string bytes(300, 'x');
    std::ofstream(dir / "boundary.0001.glb", std::ios::binary) << bytes;
    std::ofstream(dir / "other.bin", std::ios::binary) << "other";
    nlohmann::json m = make_manifest("surface", "s.json", "h");
    m["per_frame"] = {{{"frame", 1}, {"boundary", file_record(dir / "boundary.0001.glb")}}};
    const RecordedChecksums records(m, dir / "manifest.json");
    EXPECT_EQ(records.size(), 1u);
    EXPECT_TRUE(records.has("boundary.0001.glb"));
    EXPECT_NO_THROW(records.verify(dir / "boundary.0001.glb"));
    for (size_t offset = 0; offset < bytes.size(); ++offset) {
        std::string damaged = bytes;
        damaged[offset] = char(damaged[offset] ^ 0x01);
        std::ofstream(dir / "boundary.0001.glb", std::ios::binary | std::ios::trunc) << damaged;
        try {
            RecordedChecksums(m, dir / "manifest.json").verify(dir / "boundary.0001.glb");
            ADD_FAILURE() << "byte " << offset << " flipped, not caught";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("boundary.0001.glb: damaged"), std::string::npos)
                << e.what();
            EXPECT_NE(std::string(e.what()).find("re-run mc-"), std::string::npos) << e.what();
        }
    }
    try {
        records.verify(dir / "other.bin");
        ADD_FAILURE() << "a file without a record passed";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("other.bin: no checksum recorded"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(records.verify(dir / "boundary.0002.glb"), InputError);
    // a file is read once per reader: verified before it was damaged, it is not read again
    EXPECT_NO_THROW(records.verify(dir / "boundary.0001.glb"));
}

}  // namespace
}  // namespace mudcrack
