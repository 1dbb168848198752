// A stage's manifest.json as the next stage reads it.
#include "fuzz_input.h"
#include "pipeline/io/manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto path = mudcrack::fuzz::write_input(data, size, "manifest.json");
    mudcrack::fuzz::expect_clean_refusal([&] {
        const nlohmann::json m = mudcrack::read_manifest(path.parent_path());
        (void)mudcrack::manifest_slice_hash(m);
    });
    return 0;
}
