#pragma once
// What every fuzz target shares: the input bytes as a file (the readers take paths, as the stages
// do) and the exit-code contract. A reader may refuse an input only with InputError or
// RuntimeError (a stage's "exit 1"); any other exception, crash, hang or sanitizer report is a
// finding, so nothing else is caught here.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/core/error.h"

namespace mudcrack::fuzz {

/// A folder of this process's own under the temporary directory (fuzzers may run side by side).
inline const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        const std::filesystem::path d = std::filesystem::temp_directory_path() /
                                        ("mudcrack_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

/// Writes the input to scratch_dir()/name and returns its path.
inline std::filesystem::path write_input(const uint8_t* data, size_t size,
                                         const std::string& name) {
    const std::filesystem::path path = scratch_dir() / name;
    std::ofstream os(path, std::ios::binary | std::ios::trunc);
    os.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

/// Runs `read`; the errors a stage reports with exit 1 are an accepted outcome.
template <class Read>
void expect_clean_refusal(Read&& read) {
    try {
        read();
    } catch (const InputError&) {
    } catch (const RuntimeError&) {
    }
}

}  // namespace mudcrack::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
