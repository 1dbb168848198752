// The shot loader on hostile text: JSON with comments, duplicate keys, every spec check.
#include <string>

#include "fuzz_input.h"
#include "pipeline/shot/shot.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    mudcrack::fuzz::expect_clean_refusal([&] {
        const mudcrack::Shot shot = mudcrack::parse_shot(text, "fuzz/shot.json");
        (void)shot.slice_hash(mudcrack::Stage::Sim);
    });
    return 0;
}
