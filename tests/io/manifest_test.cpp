// manifest.json: common fields, atomic pretty write, and the "run mc-<stage> first" message.
#include <gtest/gtest.h>

#include <regex>

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
    EXPECT_TRUE(std::regex_match(time, std::regex(R"(20\d\d-[01]\d-[0-3]\dT[0-2]\d:[0-5]\d:[0-6]\dZ)"))) << time;
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
    EXPECT_NE(text.find("\n  \"frames\": {\n"), std::string::npos) << "pretty-printed with 2 spaces";
}

TEST(Manifest, MissingOrMalformed) {
    ScratchDir dir;
    std::filesystem::create_directories(dir / "init");
    test::expect_input_error_naming([&] { read_manifest(dir / "init"); }, "init/manifest.json: missing: run mc-init first");
    test::expect_input_error_naming([&] { read_manifest(dir / "sim"); }, "run mc-sim first");
    test::write_file(dir / "init" / "manifest.json", "{ \"stage\": ");
    test::expect_input_error_naming([&] { read_manifest(dir / "init"); }, "init/manifest.json: malformed");
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
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); }, "sim/manifest.json: malformed");

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
    test::expect_input_error_naming([&] { read_current_manifest(sim, "abc"); },
                                    "sim/manifest.json: /shot_slice_hash = \"old\": stale for this shot "
                                    "(expected \"abc\"): re-run mc-sim");

    m["shot_slice_hash"] = "abc";
    write_manifest(sim, m);
    EXPECT_EQ(read_current_manifest(sim, "abc"), m);
}

}  // namespace
}  // namespace mudcrack
