#include "image_compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <vector>

#include "tolerance.h"

namespace fs = std::filesystem;

namespace mudcrack::test {

Image to_rgb_image(const RenderedImage& image) {
    Image out;
    out.width = image.width;
    out.height = image.height;
    out.channels = 3;
    out.pixels.resize(size_t(image.width) * image.height * 3);
    for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
        for (int k = 0; k < 3; ++k) out.pixels[i * 3 + k] = image.rgba[i * 4 + k];
    return out;
}

ImageDiff compare_rgb(const Image& a, const Image& b) {
    ImageDiff d;
    const size_t n = size_t(a.width) * a.height;
    std::vector<double> per_pixel(n);
    double sum = 0;
    for (size_t i = 0; i < n; ++i) {
        double m = 0;
        for (int k = 0; k < 3; ++k) {
            const double e = std::abs(double(a.pixels[i * a.channels + k]) -
                                      double(b.pixels[i * b.channels + k]));
            sum += e;
            m = std::max(m, e);
        }
        per_pixel[i] = m;
    }
    d.mean_abs = sum / double(3 * n);
    std::sort(per_pixel.begin(), per_pixel.end());
    d.p99 = per_pixel[std::min(n - 1, size_t(0.99 * double(n)))];
    d.max = per_pixel.back();
    return d;
}

Image diff_image(const Image& a, const Image& b) {
    Image d = a;
    d.channels = 3;
    d.pixels.resize(size_t(a.width) * a.height * 3);
    for (size_t i = 0; i < size_t(a.width) * a.height; ++i)
        for (int k = 0; k < 3; ++k) {
            const int e =
                std::abs(int(a.pixels[i * a.channels + k]) - int(b.pixels[i * b.channels + k]));
            d.pixels[i * 3 + k] = uint8_t(std::min(255, 4 * e));
        }
    return d;
}

double mean_object_luma(const RenderedImage& image, int x0, int y0, int x1, int y1) {
    double sum = 0;
    int n = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const size_t i = size_t(y) * image.width + x;
            if (image.coverage[i] < 252) continue;
            const uint8_t* p = &image.rgba[i * 4];
            sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            ++n;
        }
    return n ? sum / n : std::numeric_limits<double>::quiet_NaN();
}

void expect_matches_golden(const RenderedImage& actual, const std::string& name) {
    const fs::path golden = fs::path(MUDCRACK_SOURCE_DIR) / "tests/render/golden" / (name + ".png");
    const Image got = to_rgb_image(actual);
    const char* update = std::getenv("MUDCRACK_UPDATE_GOLDENS");
    if (update && std::string(update) == "1") {
        write_png(golden, got);
        std::cout << "updated golden " << golden << "\n";
        return;
    }
    ASSERT_TRUE(fs::exists(golden)) << golden << " is missing: run tools/update_goldens";
    const Image want = read_png(golden);
    ASSERT_EQ(want.width, got.width) << golden;
    ASSERT_EQ(want.height, got.height) << golden;
    ASSERT_GE(want.channels, 3) << golden;
    const ImageDiff d = compare_rgb(got, want);
    const bool ok = d.mean_abs <= tol::kImageMeanAbs && d.p99 <= tol::kImageP99;
    if (!ok) {
        const fs::path dir = fs::absolute("render_failures");
        fs::create_directories(dir);
        write_png(dir / (name + ".actual.png"), got);
        write_png(dir / (name + ".diff.png"), diff_image(got, want));
        ADD_FAILURE() << name << " differs from " << golden << ": mean |diff| = " << d.mean_abs
                      << " (tolerance " << tol::kImageMeanAbs << "), p99 = " << d.p99
                      << " (tolerance " << tol::kImageP99 << "), max = " << d.max
                      << " levels; actual and 4x diff written to " << (dir / (name + ".actual.png"))
                      << " and " << (dir / (name + ".diff.png"));
    }
}

}  // namespace mudcrack::test
