// An artist's input mesh through assimp, as mc-init loads it; the format is chosen by the file
// name's extension, MUDCRACK_FUZZ_MESH_EXT (one target per format, so each corpus stays in one).
#include "fuzz_input.h"
#include "pipeline/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto path = mudcrack::fuzz::write_input(data, size, "input." MUDCRACK_FUZZ_MESH_EXT);
    mudcrack::fuzz::expect_clean_refusal([&] { (void)mudcrack::load_input_surface(path); });
    return 0;
}
