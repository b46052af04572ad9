// A 5 x 7 pixel bitmap font for the captions of the atlas pictures
// (atlas_pictures.h) and the labels of line plots (io/line_plot.h): digits,
// "+-.,:=()/[]%_^*'&<>" and the space, the letters a-z and A-Z. Any other
// character is drawn as a hollow box, so a caption never silently loses one.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "io/png_io.h"

namespace pba {

inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 7;

// Width [pixels] of `text` at `scale`: each character takes kGlyphWidth + 1
// columns (one of spacing), times scale, the last one's spacing included.
int TextWidth(std::string_view text, int scale);

// Draws `text` with the top left corner of its first glyph at image pixel
// (column, row), each font pixel a scale x scale block of colour `rgb`
// (only the glyphs' set pixels are painted); clipped to the image.
void DrawText(std::string_view text, int column, int row, int scale,
              const std::array<uint8_t, 3>& rgb, RgbImage* image);

}  // namespace pba
