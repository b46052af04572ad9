// The plate-contour diff against answers worked by hand: squares shifted,
// grown and added.
#include "service/geometry_diff.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace pba {
namespace {

// A square of side `side` at (x0, y0) on each of the heights `z`.
std::string Squares(const std::vector<double>& z, double side, double x0 = 0, double y0 = 0) {
  std::string json = "{\"plates\": [";
  for (size_t i = 0; i < z.size(); ++i) {
    if (i > 0) json += ", ";
    const auto p = [&](double x, double y) {
      return "[" + std::to_string(x0 + x) + ", " + std::to_string(y0 + y) + "]";
    };
    json += "{\"z_mm\": " + std::to_string(z[i]) + ", \"polygons\": [[" + p(0, 0) + ", " +
            p(side, 0) + ", " + p(side, side) + ", " + p(0, side) + "]]}";
  }
  return json + "]}";
}

Contours Parse(const std::string& json) {
  Contours contours;
  const Status s = ParseContoursJson(json, "contours", &contours);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return contours;
}

TEST(GeometryDiffTest, VolumeIsAreaTimesSlab) {
  // Plates 2 mm apart: slabs of 2 mm each, the end ones reaching 1 mm out.
  EXPECT_NEAR(ContoursVolume(Parse(Squares({0, 2, 4}, 10))), 3 * 100 * 2, 1e-9);
  // Unevenly spaced, z = 0, 2, 5: the slabs' halves below and above are
  // 1 + 1, 1 + 1.5 and 1.5 + 1.5 mm.
  EXPECT_NEAR(ContoursVolume(Parse(Squares({0, 2, 5}, 10))), 100 * (2 + 2.5 + 3), 1e-9);
  EXPECT_EQ(ContoursVolume(Parse(Squares({1}, 10))), 0);
  // Two pieces on one plate add up.
  ContourPlate two = Parse(Squares({0}, 10)).plates[0];
  two.polygons.push_back(Parse(Squares({0}, 2, 50, 50)).plates[0].polygons[0]);
  EXPECT_NEAR(PlateArea(two), 104, 1e-9);
}

TEST(GeometryDiffTest, AShiftedSquareIsItsShiftAway) {
  // Shifted 1.5 mm in x: the farthest points are 1.5 mm from the other
  // square (along the x edges); points on the top and bottom edges inside
  // the overlap lie on the other's edges, so the mean is below the shift.
  const ContoursDistance d =
      DistanceBetween(Parse(Squares({0, 2}, 10)), Parse(Squares({0, 2}, 10, 1.5, 0)));
  EXPECT_EQ(d.plates_compared, 2);
  EXPECT_NEAR(d.hausdorff_mm, 1.5, 1e-9);
  EXPECT_GT(d.mean_mm, 0.3);
  EXPECT_LT(d.mean_mm, 1.5);
  const ContoursDistance same = DistanceBetween(Parse(Squares({0}, 10)), Parse(Squares({0}, 10)));
  EXPECT_EQ(same.hausdorff_mm, 0);
  EXPECT_EQ(same.mean_mm, 0);
}

TEST(GeometryDiffTest, AGrownSquareIsItsCornerAway) {
  // Side 10 at the origin against side 12 at (-1, -1): every edge 1 mm out,
  // the outer corners sqrt(2) mm from the inner ones.
  const ContoursDistance d =
      DistanceBetween(Parse(Squares({0}, 10)), Parse(Squares({0}, 12, -1, -1)));
  EXPECT_NEAR(d.hausdorff_mm, std::sqrt(2.0), 1e-9);
  EXPECT_GT(d.mean_mm, 1.0);
  EXPECT_LT(d.mean_mm, std::sqrt(2.0));
}

TEST(GeometryDiffTest, PlatesOnlyOneSideHasAreListedNotCompared) {
  const ContoursDistance d =
      DistanceBetween(Parse(Squares({0, 2}, 10)), Parse(Squares({2, 4, 6}, 10)));
  EXPECT_EQ(d.plates_compared, 1);
  EXPECT_EQ(d.only_in_a_z_mm, std::vector<double>({0}));
  EXPECT_EQ(d.only_in_b_z_mm, std::vector<double>({4, 6}));
  EXPECT_EQ(d.hausdorff_mm, 0);
}

}  // namespace
}  // namespace pba
