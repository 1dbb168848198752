#include "pipeline/io/image_io.h"

#include <png.h>

#include <cerrno>
#include <cstdio>
#include <memory>
#include <string>
#include <system_error>

#include "pipeline/io/atomic_output.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {

namespace {

using FilePtr = std::unique_ptr<FILE, int (*)(FILE*)>;

// libpng reports errors through a callback; it throws so the caller can name the file. Unwinding
// through libpng's C frames works because Debian's gcc emits unwind tables for C on x86_64 and
// aarch64 (the damaged-file tests exercise it); setjmp/longjmp would skip C++ destructors.
[[noreturn]] void throw_png_error(png_structp, png_const_charp message) {
    throw std::runtime_error(message);
}
void ignore_png_warning(png_structp, png_const_charp) {}

int png_color_type(int channels) {
    switch (channels) {
        case 1: return PNG_COLOR_TYPE_GRAY;
        case 2: return PNG_COLOR_TYPE_GRAY_ALPHA;
        case 3: return PNG_COLOR_TYPE_RGB;
        default: return PNG_COLOR_TYPE_RGBA;
    }
}

void write_png_file(const fs::path& tmp, const Image& image) {
    errno = 0;
    FilePtr file(std::fopen(tmp.c_str(), "wb"), &std::fclose);
    if (!file)
        throw RuntimeError(tmp.string() + ": cannot open for writing: " + write_error_reason());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, throw_png_error,
                                              ignore_png_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) throw RuntimeError(tmp.string() + ": libpng could not allocate a writer");
    try {
        png_init_io(png, file.get());
        png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8,
                     png_color_type(image.channels), PNG_INTERLACE_NONE,
                     PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        const size_t stride = size_t(image.width) * size_t(image.channels);
        for (int y = 0; y < image.height; ++y)
            png_write_row(png, image.pixels.data() + size_t(y) * stride);
        png_write_end(png, nullptr);
    } catch (const std::exception& e) {
        png_destroy_write_struct(&png, &info);
        // libpng's stdio writer reports a short fwrite as "Write Error"; errno says why
        throw RuntimeError(tmp.string() + ": PNG write failed: " + e.what() + ": " +
                           write_error_reason());
    }
    png_destroy_write_struct(&png, &info);
    // fclose flushes the last buffer, so its result is the write's
    const bool flushed = std::fflush(file.get()) == 0 && !std::ferror(file.get());
    const bool closed = std::fclose(file.release()) == 0;
    if (!flushed || !closed)
        throw RuntimeError(tmp.string() + ": cannot write: " + write_error_reason());
}

}  // namespace

void write_png(const fs::path& path, const Image& image) {
    const bool valid_channels = image.channels >= 1 && image.channels <= 4;
    if (image.width <= 0 || image.height <= 0 || !valid_channels ||
        image.pixels.size() !=
            size_t(image.width) * size_t(image.height) * size_t(image.channels)) {
        throw RuntimeError(path.string() + ": cannot write a " + std::to_string(image.width) + "x" +
                           std::to_string(image.height) + "x" + std::to_string(image.channels) +
                           " image with " + std::to_string(image.pixels.size()) +
                           " bytes of pixels");
    }
    write_atomically(path, [&](const fs::path& tmp) { write_png_file(tmp, image); });
}

Image read_png(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": PNG file not found");
    FilePtr file(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!file) throw InputError(path.string() + ": cannot open the PNG file");
    unsigned char signature[8] = {0};
    if (std::fread(signature, 1, sizeof signature, file.get()) != sizeof signature ||
        png_sig_cmp(signature, 0, sizeof signature) != 0) {
        throw InputError(path.string() + ": not a PNG file (bad signature)");
    }
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, throw_png_error, ignore_png_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!info) throw RuntimeError(path.string() + ": libpng could not allocate a reader");
    Image image;
    try {
        png_init_io(png, file.get());
        png_set_sig_bytes(png, sizeof signature);
        png_read_info(png, info);
        // normalise to 8-bit gray/gray+alpha/RGB/RGBA: palette -> RGB, <8-bit gray -> 8, 16 -> 8,
        // tRNS -> alpha
        const int color_type = png_get_color_type(png, info);
        if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
        if (color_type == PNG_COLOR_TYPE_GRAY && png_get_bit_depth(png, info) < 8)
            png_set_expand_gray_1_2_4_to_8(png);
        if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
        if (png_get_bit_depth(png, info) == 16) png_set_strip_16(png);
        png_set_interlace_handling(png);
        png_read_update_info(png, info);
        image.width = int(png_get_image_width(png, info));
        image.height = int(png_get_image_height(png, info));
        image.channels = int(png_get_channels(png, info));
        const size_t stride = png_get_rowbytes(png, info);
        image.pixels.resize(stride * size_t(image.height));
        std::vector<png_bytep> rows(size_t(image.height));
        for (int y = 0; y < image.height; ++y)
            rows[size_t(y)] = image.pixels.data() + size_t(y) * stride;
        png_read_image(png, rows.data());
        png_read_end(png, nullptr);
    } catch (const std::exception& e) {
        png_destroy_read_struct(&png, &info, nullptr);
        throw InputError(path.string() +
                         ": cannot read the PNG (truncated or damaged?): " + e.what());
    }
    png_destroy_read_struct(&png, &info, nullptr);
    return image;
}

}  // namespace mudcrack
