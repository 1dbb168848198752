// The fuzz targets outside libFuzzer: runs LLVMFuzzerTestOneInput on every file of the folders
// (or files) given, in name order, so the seed corpus and every input a fuzzer once broke the
// readers with are replayed by ctest in the normal build. A crash or sanitizer report ends the
// process; a clean pass prints how many inputs it ran.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_input.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    std::vector<fs::path> inputs;
    for (int i = 1; i < argc; ++i) {
        const fs::path arg = argv[i];
        if (fs::is_directory(arg)) {
            for (const auto& e : fs::directory_iterator(arg))
                if (e.is_regular_file()) inputs.push_back(e.path());
        } else if (fs::is_regular_file(arg)) {
            inputs.push_back(arg);
        } else {
            std::fprintf(stderr, "%s: %s: no such file or folder\n", argv[0], argv[i]);
            return 2;
        }
    }
    std::sort(inputs.begin(), inputs.end());
    if (inputs.empty()) {
        std::fprintf(stderr, "%s: no inputs to replay\n", argv[0]);
        return 2;
    }
    for (const fs::path& p : inputs) {
        std::ifstream is(p, std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(is)),
                                      std::istreambuf_iterator<char>());
        LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    }
    std::error_code ec;
    fs::remove_all(mudcrack::fuzz::scratch_dir(), ec);
    std::printf("%s: %zu inputs replayed, each refused cleanly or read\n", argv[0], inputs.size());
    return 0;
}
