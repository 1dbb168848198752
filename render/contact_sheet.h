#pragma once
/// A contact sheet: a grid of frame thumbnails labelled with their frame numbers, for a quick
/// review of a whole animation in one image.
#include <utility>
#include <vector>

#include "render/renderer.h"

namespace mudcrack {

/// Box-filtered downscale to `width` pixels wide (height keeps the aspect, at least 1). The
/// result has no coverage. Throws InputError if width < 1.
RenderedImage downscale(const RenderedImage& image, int width);

/// Arranges (frame number, thumbnail) pairs left to right, top to bottom in `columns` columns on
/// a dark background, each labelled "0012"-style (as in the frame file names) at its bottom left.
/// Thumbnails must share one size. Throws InputError if `frames` is empty, sizes differ, or
/// columns < 1.
RenderedImage contact_sheet(const std::vector<std::pair<int, RenderedImage>>& frames, int columns);

/// A column count giving a roughly 16:9 sheet for n thumbnails of the given aspect (w / h).
int contact_sheet_columns(int n, double thumb_aspect);

}  // namespace mudcrack
