// A particle cache (OpenVDB points) as mc-surface and mc-render read a frame: metadata first,
// then the whole cloud and its conversion to a simulation frame.
#include "fuzz_input.h"
#include "pipeline/io/points_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const auto path = mudcrack::fuzz::write_input(data, size, "particles.0001.vdb");
    mudcrack::fuzz::expect_clean_refusal([&] { (void)mudcrack::read_points_metadata(path); });
    mudcrack::fuzz::expect_clean_refusal(
        [&] { (void)mudcrack::points_to_frame(mudcrack::read_points(path), path.string()); });
    return 0;
}
