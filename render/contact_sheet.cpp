#include "render/contact_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/bitmap_font.h"
#include "sim/core/error.h"

namespace mudcrack {

namespace {
constexpr int kPadding = 6;  // [px] around and between thumbnails
constexpr std::array<uint8_t, 3> kSheetColor{24, 25, 27};
constexpr std::array<uint8_t, 3> kLabelBox{0, 0, 0};
constexpr std::array<uint8_t, 3> kLabelText{235, 235, 235};
}  // namespace

RenderedImage downscale(const RenderedImage& image, int width) {
    if (width < 1)
        throw InputError("downscale: width = " + std::to_string(width) + ": expected >= 1");
    RenderedImage out;
    out.width = width;
    out.height = std::max(1, int(std::lround(double(image.height) * width / image.width)));
    out.rgba.assign(size_t(out.width) * out.height * 4, 255);
    const double sx = double(image.width) / out.width, sy = double(image.height) / out.height;
    // each output pixel averages the source pixels whose centers fall in its footprint
    for (int y = 0; y < out.height; ++y) {
        const int y0 = int(y * sy),
                  y1 = std::max(y0 + 1, std::min(image.height, int((y + 1) * sy)));
        for (int x = 0; x < out.width; ++x) {
            const int x0 = int(x * sx),
                      x1 = std::max(x0 + 1, std::min(image.width, int((x + 1) * sx)));
            double sum[3] = {0, 0, 0};
            for (int v = y0; v < y1; ++v)
                for (int u = x0; u < x1; ++u)
                    for (int k = 0; k < 3; ++k)
                        sum[k] += image.rgba[(size_t(v) * image.width + u) * 4 + k];
            const double n = double((y1 - y0) * (x1 - x0));
            for (int k = 0; k < 3; ++k)
                out.rgba[(size_t(y) * out.width + x) * 4 + k] = uint8_t(std::lround(sum[k] / n));
        }
    }
    return out;
}

int contact_sheet_columns(int n, double thumb_aspect) {
    // rows * cols >= n with (cols * aspect) / rows close to 16/9
    const double cols = std::sqrt(double(n) * (16.0 / 9.0) / std::max(thumb_aspect, 1e-3));
    return std::clamp(int(std::ceil(cols)), 1, std::max(n, 1));
}

RenderedImage contact_sheet(const std::vector<std::pair<int, RenderedImage>>& frames, int columns) {
    if (frames.empty()) throw InputError("contact sheet: no frames");
    if (columns < 1)
        throw InputError("contact sheet: columns = " + std::to_string(columns) + ": expected >= 1");
    const int tw = frames[0].second.width, th = frames[0].second.height;
    for (const auto& [frame, img] : frames)
        if (img.width != tw || img.height != th)
            throw InputError("contact sheet: frame " + std::to_string(frame) + " is " +
                             std::to_string(img.width) + "x" + std::to_string(img.height) +
                             ", expected " + std::to_string(tw) + "x" + std::to_string(th));
    const int cols = std::min(columns, int(frames.size()));
    const int rows = (int(frames.size()) + cols - 1) / cols;
    RenderedImage sheet;
    sheet.width = kPadding + cols * (tw + kPadding);
    sheet.height = kPadding + rows * (th + kPadding);
    sheet.rgba.assign(size_t(sheet.width) * sheet.height * 4, 255);
    fill_rect(sheet, 0, 0, sheet.width, sheet.height, kSheetColor);
    const int scale = std::max(1, std::min(3, th / 60));
    for (size_t i = 0; i < frames.size(); ++i) {
        const int ox = kPadding + int(i % cols) * (tw + kPadding);
        const int oy = kPadding + int(i / cols) * (th + kPadding);
        const RenderedImage& img = frames[i].second;
        for (int y = 0; y < th; ++y)
            std::copy_n(&img.rgba[size_t(y) * tw * 4], size_t(tw) * 4,
                        &sheet.rgba[(size_t(oy + y) * sheet.width + ox) * 4]);
        char label[16];
        std::snprintf(label, sizeof label, "%04d", frames[i].first);
        const int lw = text_width(label, scale), lh = kGlyphHeight * scale;
        fill_rect(sheet, ox, oy + th - lh - 2 * scale, lw + 2 * scale, lh + 2 * scale, kLabelBox,
                  0.6f);
        draw_text(sheet, ox + scale, oy + th - lh - scale, label, scale, kLabelText);
    }
    return sheet;
}

}  // namespace mudcrack
