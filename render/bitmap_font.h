#pragma once
/// A tiny built-in 5x7 pixel font (the classic HD44780 glyphs) for labels on contact sheets, so
/// no font files or ImageMagick are needed. Covers digits and " -.:/#".
#include <array>
#include <cstdint>
#include <string>

#include "render/renderer.h"

namespace mudcrack {

constexpr int kGlyphWidth = 5;
constexpr int kGlyphHeight = 7;

/// Width in pixels of `text` drawn at `scale` (one blank font column between glyphs).
int text_width(const std::string& text, int scale);

/// Draws `text` with its top-left corner at (x, y), each font pixel a scale x scale block, clipped
/// to the image. Characters outside the font are drawn as a hollow box.
void draw_text(RenderedImage& image, int x, int y, const std::string& text, int scale,
               const std::array<uint8_t, 3>& color);

/// Fills the rectangle [x, x+w) x [y, y+h) (clipped) with `color` blended at `opacity` in [0, 1].
void fill_rect(RenderedImage& image, int x, int y, int w, int h,
               const std::array<uint8_t, 3>& color, float opacity = 1);

}  // namespace mudcrack
