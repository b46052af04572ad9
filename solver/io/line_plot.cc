#include "io/line_plot.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/atomic_write.h"
#include "core/format.h"
#include "io/bitmap_font.h"
#include "io/png_io.h"

namespace pba {
namespace {

using Rgb = std::array<uint8_t, 3>;

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrid{226, 226, 226};          // grid lines, behind the data
constexpr Rgb kLegendBorder{150, 150, 150};  // frame of the legend box

constexpr int kTextScale = 2;        // font pixels of tick and axis labels, legend
constexpr int kTickLength = 5;       // [pixels], outwards from the frame
constexpr int kTargetTicks = 6;      // ticks wanted per axis (the nice step decides)
constexpr double kHalfWidth = 1.25;  // half the width of a series' line [pixels]
constexpr double kDotRadius = 2.5;   // a point with no finite neighbour [pixels]

// Height of a line of text at `scale` [pixels].
int TextHeight(int scale) { return kGlyphHeight * scale; }

// Width of the inked part of `text` (TextWidth without the trailing space).
int InkWidth(const std::string& text, int scale) {
  return text.empty() ? 0 : TextWidth(text, scale) - scale;
}

class Canvas {
 public:
  Canvas(int width, int height) {
    image_.width = width;
    image_.height = height;
    image_.rgb.assign(static_cast<std::size_t>(width) * height * 3, 255);
  }
  RgbImage& image() { return image_; }
  int width() const { return image_.width; }
  int height() const { return image_.height; }

  // Blends colour into pixel (c, r) with opacity a in [0, 1].
  void Blend(int c, int r, const Rgb& colour, double a) {
    if (c < 0 || r < 0 || c >= image_.width || r >= image_.height) return;
    uint8_t* px = &image_.rgb[(static_cast<std::size_t>(r) * image_.width + c) * 3];
    for (int k = 0; k < 3; ++k) {
      px[k] = static_cast<uint8_t>(std::lround(px[k] + a * (colour[k] - px[k])));
    }
  }
  void Set(int c, int r, const Rgb& colour) { Blend(c, r, colour, 1); }
  // Columns c0..c1, rows r0..r1, inclusive.
  void Fill(int c0, int r0, int c1, int r1, const Rgb& colour) {
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) Set(c, r, colour);
    }
  }
  void Rectangle(int c0, int r0, int c1, int r1, const Rgb& colour) {
    Fill(c0, r0, c1, r0, colour);
    Fill(c0, r1, c1, r1, colour);
    Fill(c0, r0, c0, r1, colour);
    Fill(c1, r0, c1, r1, colour);
  }

 private:
  RgbImage image_;
};

// Text turned a quarter turn anticlockwise (read from bottom to top), the
// top left corner of its bounding box at (column, row).
void DrawTextUp(const std::string& text, int column, int row, int scale, const Rgb& colour,
                Canvas* canvas) {
  RgbImage flat;
  flat.width = std::max(1, InkWidth(text, scale));
  flat.height = TextHeight(scale);
  flat.rgb.assign(static_cast<std::size_t>(flat.width) * flat.height * 3, 255);
  DrawText(text, 0, 0, scale, kBlack, &flat);
  for (int r = 0; r < flat.height; ++r) {
    for (int c = 0; c < flat.width; ++c) {
      if (flat.rgb[(static_cast<std::size_t>(r) * flat.width + c) * 3] != 0) continue;
      canvas->Set(column + r, row + flat.width - 1 - c, colour);
    }
  }
}

// An axis from lo to hi (multiples of step), step = 1, 2 or 5 x 10^k.
struct Axis {
  double lo = 0, hi = 1, step = 1;
  int ticks() const { return static_cast<int>(std::lround((hi - lo) / step)) + 1; }
  double tick(int k) const { return lo + k * step; }
};

// The nice axis covering [lo, hi] with about kTargetTicks ticks. A range of
// one value (or one too narrow to label) is widened around it.
Axis NiceAxis(double lo, double hi) {
  const double size = std::max(std::fabs(lo), std::fabs(hi));
  if (!(hi - lo > 1e-9 * size)) {
    const double pad = size > 0 ? 0.1 * size : 1;
    lo -= pad;
    hi += pad;
  }
  const double raw = (hi - lo) / kTargetTicks;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / magnitude;
  Axis axis;
  axis.step = (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * magnitude;
  axis.lo = std::floor(lo / axis.step + 1e-9) * axis.step;
  axis.hi = std::ceil(hi / axis.step - 1e-9) * axis.step;
  return axis;
}

// A tick's label: as many decimals as the step needs, or %g with 3 digits
// for very large or small magnitudes; "0" for the zero tick.
std::string TickLabel(const Axis& axis, double v) {
  if (std::fabs(v) < 1e-6 * axis.step) return "0";
  const double size = std::max(std::fabs(axis.lo), std::fabs(axis.hi));
  if (size >= 1e6 || size < 1e-3) return Format("%.3g", v);
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(axis.step) + 1e-9)));
  return Format("%.*f", decimals, v);
}

Status CheckPlot(const LinePlot& plot) {
  if (plot.width < 200 || plot.width > 10000) {
    return Status::InvalidArgument("width",
                                   Format("must be 200..10000 pixels, got %d", plot.width));
  }
  if (plot.height < 200 || plot.height > 10000) {
    return Status::InvalidArgument("height",
                                   Format("must be 200..10000 pixels, got %d", plot.height));
  }
  if (plot.series.empty()) return Status::InvalidArgument("series", "no series to plot");
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const LineSeries& s = plot.series[i];
    const std::string field = "series[" + std::to_string(i) + "]";
    if (s.x.size() != s.y.size()) {
      return Status::InvalidArgument(field, "series \"" + s.name + "\": x has " +
                                                std::to_string(s.x.size()) + " values, y has " +
                                                std::to_string(s.y.size()));
    }
    bool finite = false;
    for (std::size_t k = 0; k < s.x.size() && !finite; ++k) {
      finite = std::isfinite(s.x[k]) && std::isfinite(s.y[k]);
    }
    if (!finite) {
      return Status::InvalidArgument(field,
                                     "series \"" + s.name + "\" has no point with finite x and y");
    }
  }
  return Status::Ok();
}

// The plot area: columns c0..c1, rows r0..r1 (inclusive, the frame on them);
// data x = axis lo..hi maps to c0..c1, y to r1..r0.
struct Frame {
  int c0 = 0, r0 = 0, c1 = 0, r1 = 0;
  Axis x, y;
  double Column(double v) const { return c0 + (v - x.lo) / (x.hi - x.lo) * (c1 - c0); }
  double Row(double v) const { return r1 - (v - y.lo) / (y.hi - y.lo) * (r1 - r0); }
  int columns() const { return c1 - c0 + 1; }
  int rows() const { return r1 - r0 + 1; }
};

// Raises `coverage` (one value per plot-area pixel) to the fraction of each
// pixel a segment of half width hw covers: 1 within hw of the segment,
// falling linearly to 0 over the next pixel (the anti-aliased edge).
void CoverSegment(const Frame& f, double xa, double ya, double xb, double yb, double hw,
                  std::vector<float>* coverage) {
  const int c_lo = std::max(f.c0, static_cast<int>(std::floor(std::min(xa, xb) - hw - 1)));
  const int c_hi = std::min(f.c1, static_cast<int>(std::ceil(std::max(xa, xb) + hw + 1)));
  const int r_lo = std::max(f.r0, static_cast<int>(std::floor(std::min(ya, yb) - hw - 1)));
  const int r_hi = std::min(f.r1, static_cast<int>(std::ceil(std::max(ya, yb) + hw + 1)));
  const double dx = xb - xa, dy = yb - ya, length2 = dx * dx + dy * dy;
  for (int r = r_lo; r <= r_hi; ++r) {
    for (int c = c_lo; c <= c_hi; ++c) {
      double t = length2 > 0 ? ((c - xa) * dx + (r - ya) * dy) / length2 : 0;
      t = std::clamp(t, 0.0, 1.0);
      const double d = std::hypot(c - (xa + t * dx), r - (ya + t * dy));
      const double cover = std::clamp(hw + 0.5 - d, 0.0, 1.0);
      float& value = (*coverage)[static_cast<std::size_t>(r - f.r0) * f.columns() + (c - f.c0)];
      value = std::max(value, static_cast<float>(cover));
    }
  }
}

// Draws one series in the plot area and marks the pixels it inks in `ink`.
void DrawSeries(const Frame& f, const LineSeries& s, Canvas* canvas, std::vector<uint8_t>* ink) {
  std::vector<float> coverage(static_cast<std::size_t>(f.columns()) * f.rows(), 0.0f);
  const auto finite = [&](std::size_t k) {
    return k < s.x.size() && std::isfinite(s.x[k]) && std::isfinite(s.y[k]);
  };
  for (std::size_t k = 0; k < s.x.size(); ++k) {
    if (!finite(k)) continue;
    const double xa = f.Column(s.x[k]), ya = f.Row(s.y[k]);
    if (finite(k + 1)) {
      CoverSegment(f, xa, ya, f.Column(s.x[k + 1]), f.Row(s.y[k + 1]), kHalfWidth, &coverage);
    } else if (k == 0 || !finite(k - 1)) {
      CoverSegment(f, xa, ya, xa, ya, kDotRadius, &coverage);  // an isolated point
    }
  }
  for (int r = 0; r < f.rows(); ++r) {
    for (int c = 0; c < f.columns(); ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * f.columns() + c;
      if (coverage[i] <= 0) continue;
      canvas->Blend(f.c0 + c, f.r0 + r, s.colour, coverage[i]);
      if (coverage[i] >= 0.5f) (*ink)[i] = 1;
    }
  }
}

// The legend in whichever corner of the plot area covers the fewest inked
// pixels (top right, top left, bottom right, bottom left on a tie).
void DrawLegend(const Frame& f, const std::vector<LineSeries>& series,
                const std::vector<uint8_t>& ink, Canvas* canvas) {
  constexpr int kPad = 8, kSample = 28, kGap = 8, kInset = 10;
  const int row_height = TextHeight(kTextScale) + 6;
  int names = 0, name_width = 0;
  for (const LineSeries& s : series) {
    if (s.name.empty()) continue;
    ++names;
    name_width = std::max(name_width, InkWidth(s.name, kTextScale));
  }
  if (names == 0) return;
  const int w = 2 * kPad + kSample + kGap + name_width;
  const int h = 2 * kPad + names * row_height - 6;
  const int left[2] = {f.c1 - kInset - w + 1, f.c0 + kInset};
  const int top[2] = {f.r0 + kInset, f.r1 - kInset - h + 1};
  int best_c = left[0], best_r = top[0];
  long best = std::numeric_limits<long>::max();
  for (int vertical = 0; vertical < 2; ++vertical) {
    for (int horizontal = 0; horizontal < 2; ++horizontal) {
      long count = 0;
      for (int r = std::max(top[vertical], f.r0); r < std::min(top[vertical] + h, f.r1 + 1); ++r) {
        for (int c = std::max(left[horizontal], f.c0); c < std::min(left[horizontal] + w, f.c1 + 1);
             ++c) {
          count += ink[static_cast<std::size_t>(r - f.r0) * f.columns() + (c - f.c0)];
        }
      }
      if (count < best) {
        best = count;
        best_c = left[horizontal];
        best_r = top[vertical];
      }
    }
  }
  canvas->Fill(best_c, best_r, best_c + w - 1, best_r + h - 1, kWhite);
  canvas->Rectangle(best_c, best_r, best_c + w - 1, best_r + h - 1, kLegendBorder);
  int row = best_r + kPad;
  for (const LineSeries& s : series) {
    if (s.name.empty()) continue;
    const int mid = row + TextHeight(kTextScale) / 2;
    canvas->Fill(best_c + kPad, mid - 1, best_c + kPad + kSample - 1, mid + 1, s.colour);
    DrawText(s.name, best_c + kPad + kSample + kGap, row, kTextScale, kBlack, &canvas->image());
    row += row_height;
  }
}

}  // namespace

std::array<uint8_t, 3> SeriesColour(int i) {
  // Ten hues of clearly different tone (after the Tableau 10 palette, with
  // its grey replaced by a dark magenta so no series looks like the grid).
  static constexpr Rgb kColours[] = {
      {31, 119, 180}, {214, 39, 40},   {44, 160, 44},  {255, 127, 14}, {148, 103, 189},
      {140, 86, 75},  {227, 119, 194}, {23, 190, 207}, {188, 189, 34}, {128, 0, 80}};
  constexpr int n = sizeof kColours / sizeof kColours[0];
  return kColours[((i % n) + n) % n];
}

Status WriteLinePlot(const LinePlot& plot, const std::filesystem::path& png) {
  PBA_RETURN_IF_ERROR(CheckPlot(plot));

  // Data range over the finite points of every series.
  double x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  for (const LineSeries& s : plot.series) {
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      x_min = std::min(x_min, s.x[k]);
      x_max = std::max(x_max, s.x[k]);
      y_min = std::min(y_min, s.y[k]);
      y_max = std::max(y_max, s.y[k]);
    }
  }
  if (!std::isfinite(x_max - x_min) || !std::isfinite(y_max - y_min)) {
    return Status::InvalidArgument("series", "the data's range overflows a double");
  }

  Frame f;
  f.x = NiceAxis(x_min, x_max);
  f.y = NiceAxis(y_min, y_max);
  std::vector<std::string> x_labels, y_labels;
  for (int k = 0; k < f.x.ticks(); ++k) x_labels.push_back(TickLabel(f.x, f.x.tick(k)));
  for (int k = 0; k < f.y.ticks(); ++k) y_labels.push_back(TickLabel(f.y, f.y.tick(k)));
  int y_label_width = 0;
  for (const std::string& label : y_labels) {
    y_label_width = std::max(y_label_width, InkWidth(label, kTextScale));
  }

  // Layout [pixels]: title above, y label and tick labels to the left, tick
  // labels and x label below.
  const int text_h = TextHeight(kTextScale);
  int title_scale = 3;
  while (title_scale > 1 && InkWidth(plot.title, title_scale) > plot.width - 20) --title_scale;
  const int title_top = 12;
  f.r0 = title_top + (plot.title.empty() ? 8 : TextHeight(title_scale) + 14);
  const int y_axis_label_left = 10;
  f.c0 = y_axis_label_left + (plot.y_label.empty() ? 0 : text_h + 12) + y_label_width + 6 +
         kTickLength;
  const int right = std::max(20, InkWidth(x_labels.back(), kTextScale) / 2 + 8);
  f.c1 = plot.width - 1 - right;
  f.r1 =
      plot.height - 1 - (kTickLength + 6 + text_h + 12 + (plot.x_label.empty() ? 0 : text_h + 10));
  if (f.c1 - f.c0 < 60 || f.r1 - f.r0 < 60) {
    return Status::InvalidArgument(
        "width", Format("a %d x %d picture leaves too little room for the plot area beside its "
                        "labels",
                        plot.width, plot.height));
  }

  Canvas canvas(plot.width, plot.height);
  // Grid lines at the inner ticks, behind the data.
  for (int k = 1; k + 1 < f.x.ticks(); ++k) {
    const int c = static_cast<int>(std::lround(f.Column(f.x.tick(k))));
    canvas.Fill(c, f.r0, c, f.r1, kGrid);
  }
  for (int k = 1; k + 1 < f.y.ticks(); ++k) {
    const int r = static_cast<int>(std::lround(f.Row(f.y.tick(k))));
    canvas.Fill(f.c0, r, f.c1, r, kGrid);
  }

  std::vector<uint8_t> ink(static_cast<std::size_t>(f.columns()) * f.rows(), 0);
  for (const LineSeries& s : plot.series) DrawSeries(f, s, &canvas, &ink);
  canvas.Rectangle(f.c0, f.r0, f.c1, f.r1, kBlack);

  // Ticks and their labels.
  for (int k = 0; k < f.x.ticks(); ++k) {
    const int c = static_cast<int>(std::lround(f.Column(f.x.tick(k))));
    canvas.Fill(c, f.r1 + 1, c, f.r1 + kTickLength, kBlack);
    DrawText(x_labels[k], c - InkWidth(x_labels[k], kTextScale) / 2, f.r1 + kTickLength + 6,
             kTextScale, kBlack, &canvas.image());
  }
  for (int k = 0; k < f.y.ticks(); ++k) {
    const int r = static_cast<int>(std::lround(f.Row(f.y.tick(k))));
    canvas.Fill(f.c0 - kTickLength, r, f.c0 - 1, r, kBlack);
    DrawText(y_labels[k], f.c0 - kTickLength - 6 - InkWidth(y_labels[k], kTextScale),
             r - text_h / 2, kTextScale, kBlack, &canvas.image());
  }

  // Title, axis labels, legend.
  const int mid_c = (f.c0 + f.c1) / 2, mid_r = (f.r0 + f.r1) / 2;
  if (!plot.title.empty()) {
    DrawText(plot.title, plot.width / 2 - InkWidth(plot.title, title_scale) / 2, title_top,
             title_scale, kBlack, &canvas.image());
  }
  if (!plot.x_label.empty()) {
    DrawText(plot.x_label, mid_c - InkWidth(plot.x_label, kTextScale) / 2,
             f.r1 + kTickLength + 6 + text_h + 10, kTextScale, kBlack, &canvas.image());
  }
  if (!plot.y_label.empty()) {
    DrawTextUp(plot.y_label, y_axis_label_left, mid_r - InkWidth(plot.y_label, kTextScale) / 2,
               kTextScale, kBlack, &canvas);
  }
  DrawLegend(f, plot.series, ink, &canvas);

  if (!plot.title.empty()) canvas.image().text.emplace_back("Title", plot.title);
  return AtomicWrite(png, ".png", [&](int, const std::string& temporary) {
    return WriteRgbPng(temporary, canvas.image());
  });
}

}  // namespace pba
