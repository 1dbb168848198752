#pragma once
/// Image metrics and golden-image checks for the render tests (pbrt's `imgtool diff` idea: a
/// tolerance metric, not exact equality, so goldens survive small llvmpipe differences).
#include <string>

#include "pipeline/io/image_io.h"
#include "render/renderer.h"

namespace mudcrack::test {

struct ImageDiff {
    double mean_abs = 0;  // mean |a - b| over all pixels and RGB channels [8-bit levels]
    double p99 = 0;       // 99th percentile of the per-pixel max channel error [8-bit levels]
    double max = 0;       // largest per-pixel error [8-bit levels]
};

/// Compares the RGB channels of two images of the same size.
ImageDiff compare_rgb(const Image& a, const Image& b);

/// RGB copy of a rendered image in pipeline/io's layout.
Image to_rgb_image(const RenderedImage& image);

/// |a - b| per channel, amplified 4x, for humans looking at a failure.
Image diff_image(const Image& a, const Image& b);

/// Mean Rec. 709 luma (of the sRGB values, in [0, 255]) over pixels [x0, x1) x [y0, y1) whose
/// coverage is at least 0.99 (pure object pixels); NaN if there are none.
double mean_object_luma(const RenderedImage& image, int x0, int y0, int x1, int y1);

/// Checks `actual` against tests/render/golden/<name>.png within tol::kImageMeanAbs and
/// tol::kImageP99. With MUDCRACK_UPDATE_GOLDENS=1 in the environment it rewrites the golden
/// instead. On failure writes <cwd>/render_failures/<name>.{actual,diff}.png and says where.
void expect_matches_golden(const RenderedImage& actual, const std::string& name);

}  // namespace mudcrack::test
