// Tracing plate pixels into contours and rasterising them back
// (contours.h): the shapes of small cases, and the exact round trip on
// random label images and on the synthetic atlas's plates.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "atlas/contours.h"
#include "atlas/plates.h"
#include "atlas/synthetic_atlas.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

// A one-plate stack from rows of characters: '.' is background, a digit is
// that label.
PlateStack StackFromRows(const std::vector<std::string>& rows, double pixel_mm = 0.5,
                         const Eigen::Vector2d& origin_mm = Eigen::Vector2d(-3, 7)) {
  PlateStack stack;
  stack.pixel_size_mm = pixel_mm;
  stack.origin_mm = origin_mm;
  stack.height = static_cast<int>(rows.size());
  stack.width = static_cast<int>(rows[0].size());
  stack.z_mm = {2.5};
  stack.files = {"plate_01.png"};
  stack.labels.assign(1, std::vector<uint16_t>());
  for (const std::string& row : rows) {
    for (char ch : row) stack.labels[0].push_back(ch == '.' ? 0 : static_cast<uint16_t>(ch - '0'));
  }
  return stack;
}

double SignedArea(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return twice / 2;
}

double TotalArea(const ContourPlate& plate) {
  double area = 0;
  for (const auto& polygon : plate.polygons) area += SignedArea(polygon);
  return area;
}

int64_t CountLabel(const PlateStack& stack, int plate, uint16_t label) {
  int64_t count = 0;
  for (uint16_t l : stack.labels[plate]) count += l == label;
  return count;
}

// The label's pixels traced and rasterised onto an empty grid, compared
// with the original pixel by pixel; the number of differing pixels.
int64_t RoundTripMismatches(const PlateStack& stack, int plate, uint16_t label) {
  const ContourPlate contour = TraceContourPlate(stack, plate, label);
  // Empty: a value no test uses as a label, so label 0 can be traced too.
  std::vector<uint16_t> drawn(static_cast<size_t>(stack.width) * stack.height, 0xffff);
  RasterizeContourPlate(contour, stack.origin_mm, stack.pixel_size_mm, stack.width, stack.height,
                        label, &drawn);
  int64_t mismatches = 0;
  for (size_t i = 0; i < drawn.size(); ++i) {
    mismatches += (drawn[i] == label) != (stack.labels[plate][i] == label);
  }
  return mismatches;
}

// No two consecutive edges of a polygon run the same or opposite way.
void ExpectNoCollinearPoints(const std::vector<Eigen::Vector2d>& polygon) {
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d d0 = polygon[i] - polygon[(i + n - 1) % n];
    const Eigen::Vector2d d1 = polygon[(i + 1) % n] - polygon[i];
    EXPECT_NE(d0.x() * d1.y() - d0.y() * d1.x(), 0) << "point " << i;
  }
}

TEST(TraceContourPlate, SinglePixelIsACounterClockwiseSquareOnItsFaces) {
  const PlateStack stack = StackFromRows({"...", ".1.", "..."});
  const ContourPlate plate = TraceContourPlate(stack, 0, 1);
  EXPECT_EQ(plate.z_mm, 2.5);
  ASSERT_EQ(plate.polygons.size(), 1u);
  const auto& square = plate.polygons[0];
  ASSERT_EQ(square.size(), 4u);
  // Pixel (1, 1) is centred at (-3 + 0.5, 7 - 0.5).
  double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
  for (const Eigen::Vector2d& p : square) {
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
    min_y = std::min(min_y, p.y());
    max_y = std::max(max_y, p.y());
  }
  EXPECT_DOUBLE_EQ(min_x, -2.75);
  EXPECT_DOUBLE_EQ(max_x, -2.25);
  EXPECT_DOUBLE_EQ(min_y, 6.25);
  EXPECT_DOUBLE_EQ(max_y, 6.75);
  EXPECT_DOUBLE_EQ(SignedArea(square), 0.25);
  EXPECT_EQ(RoundTripMismatches(stack, 0, 1), 0);
}

TEST(TraceContourPlate, AbsentLabelGivesNoPolygons) {
  const PlateStack stack = StackFromRows({"...", ".1.", "..."});
  EXPECT_TRUE(TraceContourPlate(stack, 0, 2).polygons.empty());
  EXPECT_TRUE(TraceContours(stack, 2).plates.empty());
}

TEST(TraceContourPlate, LShapeHasSixCorners) {
  const PlateStack stack = StackFromRows({
      "1...",
      "1...",
      "111.",
  });
  const ContourPlate plate = TraceContourPlate(stack, 0, 1);
  ASSERT_EQ(plate.polygons.size(), 1u);
  EXPECT_EQ(plate.polygons[0].size(), 6u);
  ExpectNoCollinearPoints(plate.polygons[0]);
  EXPECT_DOUBLE_EQ(SignedArea(plate.polygons[0]), 5 * 0.25);
  EXPECT_EQ(RoundTripMismatches(stack, 0, 1), 0);
}

TEST(TraceContourPlate, RingGivesAnOuterLoopAndAHoleOfOppositeOrientation) {
  const PlateStack stack = StackFromRows({
      ".....",
      ".111.",
      ".1.1.",
      ".111.",
      ".....",
  });
  const ContourPlate plate = TraceContourPlate(stack, 0, 1);
  ASSERT_EQ(plate.polygons.size(), 2u);
  std::vector<double> areas = {SignedArea(plate.polygons[0]), SignedArea(plate.polygons[1])};
  std::sort(areas.begin(), areas.end());
  EXPECT_DOUBLE_EQ(areas[0], -0.25);     // the hole, clockwise
  EXPECT_DOUBLE_EQ(areas[1], 9 * 0.25);  // the outer boundary, counter-clockwise
  for (const auto& polygon : plate.polygons) EXPECT_EQ(polygon.size(), 4u);
  EXPECT_EQ(RoundTripMismatches(stack, 0, 1), 0);
  // The hole's pixel traced as its own label: the same square, turned the
  // other way.
  EXPECT_DOUBLE_EQ(TotalArea(TraceContourPlate(stack, 0, 0)), 16 * 0.25 + 0.25);
}

TEST(TraceContourPlate, PixelsTouchingAtACornerGiveTwoSquares) {
  for (const auto& rows :
       {std::vector<std::string>{"1.", ".1"}, std::vector<std::string>{".1", "1."}}) {
    const PlateStack stack = StackFromRows(rows);
    const ContourPlate plate = TraceContourPlate(stack, 0, 1);
    ASSERT_EQ(plate.polygons.size(), 2u) << rows[0];
    for (const auto& polygon : plate.polygons) {
      EXPECT_EQ(polygon.size(), 4u);
      EXPECT_DOUBLE_EQ(SignedArea(polygon), 0.25);
    }
    EXPECT_EQ(RoundTripMismatches(stack, 0, 1), 0);
    // The background touches itself at the same corner: a hole-free pair
    // of squares too.
    EXPECT_EQ(RoundTripMismatches(stack, 0, 0), 0);
  }
}

TEST(TraceContourPlate, LabelOnTheGridBorderIsClosedByTheBorder) {
  const PlateStack stack = StackFromRows({"11", "11"});
  const ContourPlate plate = TraceContourPlate(stack, 0, 1);
  ASSERT_EQ(plate.polygons.size(), 1u);
  EXPECT_EQ(plate.polygons[0].size(), 4u);
  EXPECT_DOUBLE_EQ(SignedArea(plate.polygons[0]), 1.0);
  EXPECT_EQ(RoundTripMismatches(stack, 0, 1), 0);
}

TEST(TraceContourPlate, RandomLabelImagesRoundTripExactly) {
  std::mt19937 random(20261202);
  for (int trial = 0; trial < 4; ++trial) {
    PlateStack stack;
    stack.pixel_size_mm = trial == 0 ? 1.0 : 0.3 + 0.1 * trial;
    stack.origin_mm = Eigen::Vector2d(-41.7 + trial, 63.1);
    stack.width = stack.height = 64;
    stack.z_mm = {-4};
    stack.files = {"plate_01.png"};
    stack.labels.assign(1, std::vector<uint16_t>(64 * 64));
    // Noise (every shape of diagonal touch) for the first images, blobs of
    // noise-grown regions for the others.
    std::uniform_int_distribution<int> label_of(0, 5);
    for (uint16_t& l : stack.labels[0]) l = static_cast<uint16_t>(label_of(random));
    if (trial >= 2) {
      for (int pass = 0; pass < 3; ++pass) {
        std::vector<uint16_t> smoothed = stack.labels[0];
        for (int r = 1; r + 1 < 64; ++r) {
          for (int c = 1; c + 1 < 64; ++c) {
            std::uniform_int_distribution<int> neighbour(0, 3);
            const int dc[4] = {1, -1, 0, 0}, dr[4] = {0, 0, 1, -1};
            const int n = neighbour(random);
            smoothed[r * 64 + c] = stack.at(0, c + dc[n], r + dr[n]);
          }
        }
        stack.labels[0] = smoothed;
      }
    }
    const double pixel_area = stack.pixel_size_mm * stack.pixel_size_mm;
    for (uint16_t label = 0; label <= 5; ++label) {
      const int64_t count = CountLabel(stack, 0, label);
      EXPECT_EQ(RoundTripMismatches(stack, 0, label), 0) << "trial " << trial << " label " << label;
      const ContourPlate plate = TraceContourPlate(stack, 0, label);
      EXPECT_NEAR(TotalArea(plate), count * pixel_area, 1e-9 * count * pixel_area)
          << "trial " << trial << " label " << label;
      for (const auto& polygon : plate.polygons) ExpectNoCollinearPoints(polygon);
    }
  }
}

TEST(RasterizeContourPlate, LeavesOtherPixelsAndCountsVerticesOnAScanlineOnce) {
  // A diamond whose vertices all lie on pixel centres.
  ContourPlate plate;
  plate.polygons = {{{2, 0}, {4, 2}, {2, 4}, {0, 2}}};
  // Pixel (c, r) centred at (c, 4 - r), 1 mm pixels.
  std::vector<uint16_t> labels(5 * 5, 9);
  RasterizeContourPlate(plate, Eigen::Vector2d(0, 4), 1.0, 5, 5, 3, &labels);
  // Centres on the outline: a span takes its left end, not its right one;
  // a vertex on a scanline counts by the half-open rule in y.
  const std::vector<uint16_t> expected = {
      9, 9, 9, 9, 9,  // y = 4: the top vertex only touches the scanline
      9, 3, 3, 9, 9,  // y = 3: x in [1, 3)
      3, 3, 3, 3, 9,  // y = 2: through the side vertices, x in [0, 4)
      9, 3, 3, 9, 9,  // y = 1
      9, 9, 9, 9, 9,  // y = 0: the bottom vertex crossed twice, an empty span
  };
  EXPECT_EQ(labels, expected);
}

TEST(TraceContours, SyntheticAtlasPlatesRoundTripForEveryStructure) {
  SyntheticAtlasOptions options;
  options.voxel_size_mm = 2.0;
  const LabelVolume atlas = MakeSyntheticAtlas(options);
  const fs::path root =
      fs::temp_directory_path() / ("pba_contour_trace_test_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const Status written = WritePlates(atlas, ColourTable::Builtin(), PlateOptions(), root / "stack");
  ASSERT_TRUE(written.ok()) << written.ToString();
  PlateStack stack;
  const Status read = ReadPlates(root / "stack", &stack);
  fs::remove_all(root);
  ASSERT_TRUE(read.ok()) << read.ToString();

  int traced = 0;
  for (const ColourEntry& entry : stack.colours.entries()) {
    const Contours contours = TraceContours(stack, entry.label);
    EXPECT_EQ(contours.pixel_size_mm, stack.pixel_size_mm);
    size_t next = 0;
    for (int p = 0; p < stack.num_plates(); ++p) {
      const int64_t count = CountLabel(stack, p, entry.label);
      if (count == 0) continue;
      ASSERT_LT(next, contours.plates.size()) << entry.name;
      const ContourPlate& plate = contours.plates[next++];
      EXPECT_EQ(plate.z_mm, stack.z_mm[p]);
      std::vector<uint16_t> drawn(static_cast<size_t>(stack.width) * stack.height, 0);
      RasterizeContourPlate(plate, stack.origin_mm, stack.pixel_size_mm, stack.width, stack.height,
                            entry.label, &drawn);
      int64_t mismatches = 0;
      for (size_t i = 0; i < drawn.size(); ++i) {
        mismatches += (drawn[i] == entry.label) != (stack.labels[p][i] == entry.label);
      }
      EXPECT_EQ(mismatches, 0) << entry.name << " plate " << p;
      EXPECT_NEAR(TotalArea(plate), count * stack.pixel_size_mm * stack.pixel_size_mm, 1e-6)
          << entry.name << " plate " << p;
      ++traced;
    }
    EXPECT_EQ(next, contours.plates.size()) << entry.name;
  }
  // Most of the 44 structures are on several plates.
  EXPECT_GT(traced, 200);
}

}  // namespace
}  // namespace pba
