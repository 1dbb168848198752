#include "render/bitmap_font.h"

#include <algorithm>
#include <cmath>

namespace mudcrack {

namespace {

/// Rows top to bottom; bit 4 is the leftmost column.
const std::array<uint8_t, kGlyphHeight>* glyph(char c) {
    static const std::array<uint8_t, kGlyphHeight> digits[10] = {
        {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}, {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E},
        {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}, {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E},
        {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}, {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E},
        {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08},
        {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}, {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}};
    static const std::array<uint8_t, kGlyphHeight> space{}, dash{0, 0, 0, 0x1F, 0, 0, 0},
        dot{0, 0, 0, 0, 0, 0x0C, 0x0C}, colon{0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0},
        slash{0x01, 0x01, 0x02, 0x04, 0x08, 0x10, 0x10},
        hash{0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A},
        box{0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F};
    if (c >= '0' && c <= '9') return &digits[c - '0'];
    switch (c) {
        case ' ': return &space;
        case '-': return &dash;
        case '.': return &dot;
        case ':': return &colon;
        case '/': return &slash;
        case '#': return &hash;
        default: return &box;
    }
}

}  // namespace

int text_width(const std::string& text, int scale) {
    if (text.empty()) return 0;
    return (int(text.size()) * (kGlyphWidth + 1) - 1) * scale;
}

void fill_rect(RenderedImage& image, int x, int y, int w, int h,
               const std::array<uint8_t, 3>& color, float opacity) {
    const int x0 = std::max(x, 0), x1 = std::min(x + w, image.width);
    const int y0 = std::max(y, 0), y1 = std::min(y + h, image.height);
    const float a = std::clamp(opacity, 0.0f, 1.0f);
    for (int py = y0; py < y1; ++py)
        for (int px = x0; px < x1; ++px) {
            uint8_t* p = &image.rgba[(size_t(py) * image.width + px) * 4];
            for (int k = 0; k < 3; ++k) p[k] = uint8_t(std::lround(p[k] * (1 - a) + color[k] * a));
            p[3] = 255;
        }
}

void draw_text(RenderedImage& image, int x, int y, const std::string& text, int scale,
               const std::array<uint8_t, 3>& color) {
    for (size_t i = 0; i < text.size(); ++i) {
        const auto& rows = *glyph(text[i]);
        const int gx = x + int(i) * (kGlyphWidth + 1) * scale;
        for (int r = 0; r < kGlyphHeight; ++r)
            for (int c = 0; c < kGlyphWidth; ++c)
                if (rows[r] & (1 << (kGlyphWidth - 1 - c)))
                    fill_rect(image, gx + c * scale, y + r * scale, scale, scale, color);
    }
}

}  // namespace mudcrack
