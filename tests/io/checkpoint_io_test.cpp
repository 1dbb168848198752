// Checkpoints: exact round trip, deterministic bytes, and every kind of damaged file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "pipeline/io/checkpoint_io.h"
#include "scratch_dir.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

using test::ScratchDir;

Checkpoint sample_checkpoint() {
    Checkpoint c;
    std::vector<double> x(3000);
    for (size_t i = 0; i < x.size(); ++i) x[i] = std::sin(double(i)) * 1e-3 + 1.0 / 3.0;
    x[7] = std::numeric_limits<double>::denorm_min();
    x[8] = -0.0;
    c.f64["x"] = x;
    c.f64["empty"] = {};
    c.i32["id"] = {0, 1, 2, -5, std::numeric_limits<int32_t>::max()};
    c.i64["cells"] = {int64_t(1) << 40, -1};
    c.meta_string["stage"] = "sim";
    c.meta_string["note"] = std::string("with\0nul", 8);
    c.meta_double["time"] = 0.1 + 0.2;
    c.meta_int["frame"] = 12;
    return c;
}

TEST(CheckpointIo, RoundTripIsBitExact) {
    ScratchDir dir;
    const Checkpoint in = sample_checkpoint();
    write_checkpoint(dir / "s.ckpt", in);
    const Checkpoint out = read_checkpoint(dir / "s.ckpt");
    ASSERT_EQ(out.f64.size(), 2u);
    const auto& x = out.require_f64("x", 3000);
    for (size_t i = 0; i < x.size(); ++i) {
        ASSERT_EQ(std::memcmp(&x[i], &in.f64.at("x")[i], sizeof(double)), 0) << "element " << i;
    }
    EXPECT_TRUE(std::signbit(x[8]));
    EXPECT_TRUE(out.require_f64("empty").empty());
    EXPECT_EQ(out.i32, in.i32);
    EXPECT_EQ(out.i64, in.i64);
    EXPECT_EQ(out.meta_string, in.meta_string);
    EXPECT_EQ(out.require_double("time"), 0.1 + 0.2);
    EXPECT_EQ(out.require_int("frame"), 12);
    EXPECT_EQ(out.require_string("stage"), "sim");
    EXPECT_EQ(out.source, (dir / "s.ckpt").string());
    // header, then 8 entries, then the checksum
    const std::string bytes = test::read_file(dir / "s.ckpt");
    EXPECT_EQ(bytes.substr(0, 8), std::string("MCCKPT1\0", 8));
    EXPECT_EQ(uint8_t(bytes[8]), 1);   // version 1, little-endian
    EXPECT_EQ(uint8_t(bytes[12]), 8);  // entry count
}

TEST(CheckpointIo, SameContentGivesIdenticalBytes) {
    ScratchDir dir;
    write_checkpoint(dir / "a.ckpt", sample_checkpoint());
    write_checkpoint(dir / "b.ckpt", sample_checkpoint());
    EXPECT_TRUE(test::read_file(dir / "a.ckpt") == test::read_file(dir / "b.ckpt"));
    EXPECT_FALSE(std::filesystem::exists(dir / "a.ckpt.tmp"));
}

TEST(CheckpointIo, RequireNamesTheFileAndEntry) {
    ScratchDir dir;
    write_checkpoint(dir / "s.ckpt", sample_checkpoint());
    const Checkpoint c = read_checkpoint(dir / "s.ckpt");
    test::expect_input_error_naming([&] { c.require_f64("v"); },
                                    "s.ckpt: checkpoint has no float64 array 'v'");
    test::expect_input_error_naming([&] { c.require_f64("x", 9); },
                                    "'x' has 3000 elements, expected 9");
    test::expect_input_error_naming([&] { c.require_i32("x"); }, "s.ckpt");
    test::expect_input_error_naming([&] { c.require_int("time"); }, "'time'");
    test::expect_input_error_naming([&] { c.require_double("frame"); }, "'frame'");
    test::expect_input_error_naming([&] { c.require_string("nope"); }, "'nope'");
}

TEST(CheckpointIo, DamagedFilesNameTheFile) {
    ScratchDir dir;
    test::expect_input_error_naming([&] { read_checkpoint(dir / "missing.ckpt"); }, "missing.ckpt");
    write_checkpoint(dir / "good.ckpt", sample_checkpoint());
    const std::string good = test::read_file(dir / "good.ckpt");
    // every truncation is caught: a sweep over all lengths of the header and the last entries
    for (size_t keep = 0; keep < good.size();
         keep += (keep < 200 || keep > good.size() - 200) ? 1 : 997) {
        const std::string name = "cut" + std::to_string(keep) + ".ckpt";
        test::write_file(dir / name, good.substr(0, keep));
        test::expect_input_error_naming([&] { read_checkpoint(dir / name); }, name);
    }
    // a flipped bit in the data fails the checksum
    std::string flipped = good;
    flipped[good.size() / 2] ^= 0x10;
    test::write_file(dir / "flipped.ckpt", flipped);
    test::expect_input_error_naming([&] { read_checkpoint(dir / "flipped.ckpt"); }, "checksum");
    // another version
    std::string v2 = good;
    v2[8] = 2;
    test::write_file(dir / "v2.ckpt", v2);
    test::expect_input_error_naming([&] { read_checkpoint(dir / "v2.ckpt"); },
                                    "v2.ckpt: checkpoint format version 2");
    // garbage and trailing bytes
    test::write_file(dir / "garbage.ckpt", std::string(100, '\x7f'));
    test::expect_input_error_naming([&] { read_checkpoint(dir / "garbage.ckpt"); }, "garbage.ckpt");
    test::write_file(dir / "long.ckpt", good + "x");
    test::expect_input_error_naming([&] { read_checkpoint(dir / "long.ckpt"); }, "long.ckpt");
}

}  // namespace
}  // namespace mudcrack
