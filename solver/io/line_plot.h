// Line plots as PNG pictures (e.g. a reaction force or a relaxation curve
// against time): a white canvas with a framed plot area, "nice" ticks (steps
// of 1, 2 or 5 x 10^k) with labels and light grid lines, axis labels, a
// title, each series as an anti-aliased polyline about 2.5 pixels wide, and a
// legend in the corner of the plot area the lines cross least. Text uses the
// atlas pictures' bitmap font (io/bitmap_font.h).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pba/status.h"

namespace pba {

struct LineSeries {
  std::string name;  // in the legend
  // Data coordinates, one point per index; x.size() == y.size(). A point
  // with a non-finite coordinate is left out and breaks the line there.
  std::vector<double> x, y;
  std::array<uint8_t, 3> colour{0, 0, 0};  // RGB
};

struct LinePlot {
  std::string title, x_label, y_label;  // the y label is written upwards
  std::vector<LineSeries> series;
  int width = 800, height = 560;  // [pixels], each 200..10000
};

// Draws `plot` and writes it to `png` atomically (a reader sees the old file
// or the whole new one). kInvalidArgument when there is no series, a size
// is out of range, or a series has x and y of different sizes or no finite
// point (field "series[i]", the message naming the series); kIo when the
// file cannot be written.
Status WriteLinePlot(const LinePlot& plot, const std::filesystem::path& png);

// A colour for series i >= 0, distinct from its neighbours and from the
// plot's black, grey and white; repeats after 10.
std::array<uint8_t, 3> SeriesColour(int i);

}  // namespace pba
