// Line plots: a plot of two straight lines read back from its PNG (size,
// frame, grid at the nice ticks, each series' colour where its data points
// fall), the legend, and the errors that name the bad series.

#include "io/line_plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>
#include <string>

#include "io/png_io.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

class LinePlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("line_plot_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

using Rgb = std::array<uint8_t, 3>;

Rgb Pixel(const RgbImage& image, int c, int r) {
  const uint8_t* p = &image.rgb[(static_cast<size_t>(r) * image.width + c) * 3];
  return {p[0], p[1], p[2]};
}

bool IsBlack(const RgbImage& image, int c, int r) { return Pixel(image, c, r) == Rgb{0, 0, 0}; }

// Whether a pixel within `radius` of (c, r) has `colour` to within 40 per
// channel (the line's core is the full colour; its edges are blended).
bool ColourNear(const RgbImage& image, double c, double r, const Rgb& colour, int radius = 2) {
  for (int dr = -radius; dr <= radius; ++dr) {
    for (int dc = -radius; dc <= radius; ++dc) {
      const Rgb p = Pixel(image, static_cast<int>(std::lround(c)) + dc,
                          static_cast<int>(std::lround(r)) + dr);
      bool close = true;
      for (int k = 0; k < 3; ++k) close = close && std::abs(p[k] - colour[k]) <= 40;
      if (close) return true;
    }
  }
  return false;
}

// The plot frame: the outermost rows and columns that hold a black run of
// more than half the picture's width (height); nothing else is that long.
struct FoundFrame {
  int c0 = -1, r0 = -1, c1 = -1, r1 = -1;
};

FoundFrame FindFrame(const RgbImage& image) {
  FoundFrame f;
  for (int r = 0; r < image.height; ++r) {
    int run = 0, longest = 0;
    for (int c = 0; c < image.width; ++c) {
      run = IsBlack(image, c, r) ? run + 1 : 0;
      longest = std::max(longest, run);
    }
    if (longest > image.width / 2) {
      if (f.r0 < 0) f.r0 = r;
      f.r1 = r;
    }
  }
  for (int c = 0; c < image.width; ++c) {
    int run = 0, longest = 0;
    for (int r = 0; r < image.height; ++r) {
      run = IsBlack(image, c, r) ? run + 1 : 0;
      longest = std::max(longest, run);
    }
    if (longest > image.height / 2) {
      if (f.c0 < 0) f.c0 = c;
      f.c1 = c;
    }
  }
  return f;
}

// Two lines over x = 0..10: "rising" y = 2 + 0.3 x and "falling" y = 8 -
// 0.3 x; the nice axes are x 0..10 (step 2) and y 2..8 (step 1).
LinePlot TwoLines() {
  LinePlot plot;
  plot.title = "Two lines";
  plot.x_label = "time [s]";
  plot.y_label = "force [N]";
  LineSeries rising{"rising", {}, {}, SeriesColour(0)};
  LineSeries falling{"falling", {}, {}, SeriesColour(1)};
  for (int k = 0; k <= 20; ++k) {
    const double x = 0.5 * k;
    rising.x.push_back(x);
    rising.y.push_back(2 + 0.3 * x);
    falling.x.push_back(x);
    falling.y.push_back(8 - 0.3 * x);
  }
  plot.series = {rising, falling};
  return plot;
}

TEST_F(LinePlotTest, DrawsSeriesWhereTheirDataLie) {
  const fs::path png = dir_ / "plot.png";
  const LinePlot plot = TwoLines();
  const Status status = WriteLinePlot(plot, png);
  ASSERT_TRUE(status.ok()) << status.ToString();
  // Written atomically: no temporary file is left beside it.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);

  RgbImage image;
  ASSERT_TRUE(ReadRgbPng(png, &image).ok());
  EXPECT_EQ(image.width, 800);
  EXPECT_EQ(image.height, 560);
  ASSERT_EQ(image.text.size(), 1u);
  EXPECT_EQ(image.text[0].first, "Title");
  EXPECT_EQ(image.text[0].second, "Two lines");

  const FoundFrame f = FindFrame(image);
  ASSERT_GT(f.c0, 0);
  ASSERT_GT(f.r0, 0);
  ASSERT_LT(f.c1, image.width - 1);
  ASSERT_LT(f.r1, image.height - 1);
  ASSERT_GT(f.c1 - f.c0, 400);
  ASSERT_GT(f.r1 - f.r0, 300);
  const auto column = [&](double x) { return f.c0 + x / 10 * (f.c1 - f.c0); };
  const auto row = [&](double y) { return f.r1 - (y - 2) / 6 * (f.r1 - f.r0); };

  // Known data points, each in its series' colour.
  for (double x : {1.0, 2.0, 3.5, 7.0}) {
    EXPECT_TRUE(ColourNear(image, column(x), row(2 + 0.3 * x), SeriesColour(0))) << x;
    EXPECT_TRUE(ColourNear(image, column(x), row(8 - 0.3 * x), SeriesColour(1))) << x;
    // Not the other series' colour there: the lines are 1.8 units apart at
    // x = 7 and more elsewhere.
    EXPECT_FALSE(ColourNear(image, column(x), row(2 + 0.3 * x), SeriesColour(1))) << x;
  }
  // Between the lines, away from both and from the grid, the background
  // is white.
  EXPECT_EQ(Pixel(image, static_cast<int>(column(1)), static_cast<int>(row(5.5))),
            (Rgb{255, 255, 255}));

  // Grid lines at the nice ticks: x = 4 (x step 2) and y = 7 (y step 1),
  // away from the data.
  const Rgb grid{226, 226, 226};
  EXPECT_EQ(Pixel(image, static_cast<int>(std::lround(column(4))), static_cast<int>(row(5))), grid);
  EXPECT_EQ(Pixel(image, static_cast<int>(column(5)), static_cast<int>(std::lround(row(7)))), grid);

  // Black text above the frame (the title) and left of it (tick labels and
  // the y label) and below it (tick labels, x label).
  const auto black_in = [&](int c0, int r0, int c1, int r1) {
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        if (IsBlack(image, c, r)) return true;
      }
    }
    return false;
  };
  EXPECT_TRUE(black_in(0, 0, image.width - 1, f.r0 - 2));
  EXPECT_TRUE(black_in(0, f.r0, f.c0 - 8, f.r1));
  EXPECT_TRUE(black_in(f.c0, f.r1 + 8, f.c1, image.height - 1));

  // The legend sits in the top right corner, where no line passes: both
  // colours appear there, in short horizontal samples.
  std::set<Rgb> legend_colours;
  for (int r = f.r0 + 1; r < f.r0 + 80; ++r) {
    for (int c = f.c1 - 200; c < f.c1; ++c) legend_colours.insert(Pixel(image, c, r));
  }
  EXPECT_TRUE(legend_colours.count(SeriesColour(0)));
  EXPECT_TRUE(legend_colours.count(SeriesColour(1)));
}

TEST_F(LinePlotTest, BrokenAndSinglePointsAndFlatSeries) {
  LinePlot plot;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  plot.series.push_back({"gappy", {0, 1, 2, 3, 4}, {1, 1, nan, 1, 1}, SeriesColour(2)});
  plot.series.push_back({"", {2}, {1}, SeriesColour(3)});  // a lone point, no legend entry
  plot.width = 400;
  plot.height = 300;
  const fs::path png = dir_ / "flat.png";
  const Status status = WriteLinePlot(plot, png);
  ASSERT_TRUE(status.ok()) << status.ToString();
  RgbImage image;
  ASSERT_TRUE(ReadRgbPng(png, &image).ok());
  EXPECT_EQ(image.width, 400);
  EXPECT_EQ(image.height, 300);
}

TEST_F(LinePlotTest, BadInputNamesTheSeries) {
  const fs::path png = dir_ / "bad.png";
  LinePlot plot;
  Status status = WriteLinePlot(plot, png);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "series");

  plot = TwoLines();
  plot.series[1].y.pop_back();
  status = WriteLinePlot(plot, png);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "series[1]");
  EXPECT_NE(status.message().find("\"falling\""), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("21"), std::string::npos) << status.message();

  plot = TwoLines();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  plot.series[0].x.assign(plot.series[0].x.size(), nan);
  status = WriteLinePlot(plot, png);
  EXPECT_EQ(status.field(), "series[0]");
  EXPECT_NE(status.message().find("\"rising\" has no point with finite x and y"), std::string::npos)
      << status.message();

  plot = TwoLines();
  plot.series.push_back({"empty", {}, {}, SeriesColour(2)});
  status = WriteLinePlot(plot, png);
  EXPECT_EQ(status.field(), "series[2]");
  EXPECT_NE(status.message().find("\"empty\""), std::string::npos);

  plot = TwoLines();
  plot.width = 50;
  EXPECT_EQ(WriteLinePlot(plot, png).field(), "width");
  EXPECT_FALSE(fs::exists(png));  // nothing written for bad input

  plot = TwoLines();
  status = WriteLinePlot(plot, dir_ / "no-such-dir" / "plot.png");
  EXPECT_EQ(status.code(), Status::Code::kIo);
}

TEST(SeriesColourTest, TenDistinctColoursAwayFromGreyAndWhite) {
  std::set<Rgb> seen;
  for (int i = 0; i < 10; ++i) {
    const Rgb c = SeriesColour(i);
    seen.insert(c);
    const int spread = std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]});
    EXPECT_GT(spread, 60) << i;  // a hue, not a grey
  }
  EXPECT_EQ(seen.size(), 10u);
  EXPECT_EQ(SeriesColour(10), SeriesColour(0));
}

}  // namespace
}  // namespace pba
