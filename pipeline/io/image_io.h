#pragma once
/// PNG files through libpng: render output, golden images, heightfield inputs.
#include <cstdint>
#include <filesystem>
#include <vector>

namespace mudcrack {

struct Image {
    int width = 0, height = 0, channels = 4;  // channels: 1 (gray), 3 (RGB) or 4 (RGBA)
    std::vector<uint8_t> pixels;              // row-major, top row first
};

/// Atomic write (temporary name + rename).
void write_png(const std::filesystem::path& path, const Image& image);
/// Reads any 8/16-bit PNG, converted to 8-bit with the file's channel count (palette -> RGB).
/// Throws InputError naming the file.
Image read_png(const std::filesystem::path& path);

}  // namespace mudcrack
