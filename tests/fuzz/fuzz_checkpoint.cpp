// mc-sim's restart file as --resume reads it. The trailing checksum would stop a mutated file at
// the first check, so each input is also read with its checksum made right: the parser behind
// it sees hostile entries too.
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "pipeline/io/checksum.h"
#include "pipeline/stages/sim/sim_checkpoint.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace mudcrack;
    const auto as_given = fuzz::write_input(data, size, "checkpoint.0001.bin");
    fuzz::expect_clean_refusal([&] { (void)read_sim_checkpoint(as_given); });
    if (size >= sizeof(uint64_t)) {
        std::vector<uint8_t> fixed(data, data + size);
        const size_t body = size - sizeof(uint64_t);
        const uint64_t hash = fnv1a64(fixed.data(), body, kFnv1a64Offset);
        // little-endian hosts (the writer's order)
        std::memcpy(fixed.data() + body, &hash, sizeof hash);
        const auto resealed = fuzz::write_input(fixed.data(), fixed.size(), "checkpoint.0002.bin");
        fuzz::expect_clean_refusal([&] { (void)read_sim_checkpoint(resealed); });
    }
    return 0;
}
