// The plate-contour diff against answers worked by hand: squares shifted,
// grown and added; and the shape comparison's voxel budget (issue 18): two
// boxes of a metre are compared on coarser voxels, in seconds and a few
// hundred MB, where 1 mm voxels would take tens of GB.
#include "service/geometry_diff.h"

#include <gtest/gtest.h>
#include <sys/mman.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <new>
#include <string>
#include <tuple>
#include <utility>

#include "common/bounded_run.h"

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

// A binary STL of the box [lo, hi] [mm]: 12 triangles wound outward.
std::string BoxStl(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const auto corner = [&](int bits) {
    return Eigen::Vector3d(bits & 1 ? hi.x() : lo.x(), bits & 2 ? hi.y() : lo.y(),
                           bits & 4 ? hi.z() : lo.z());
  };
  std::string stl(80, ' ');
  const auto put = [&](const void* bytes, size_t n) {
    stl.append(static_cast<const char*>(bytes), n);
  };
  const uint32_t triangles = 12;
  put(&triangles, sizeof triangles);
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      // The face's corners in order around it: the other two axes' bits
      // 00, 01, 11, 10.
      const int u = 1 << ((axis + 1) % 3), v = 1 << ((axis + 2) % 3), w = side << axis;
      const Eigen::Vector3d quad[4] = {corner(w), corner(w | u), corner(w | u | v), corner(w | v)};
      Eigen::Vector3d outward = Eigen::Vector3d::Zero();
      outward[axis] = side == 0 ? -1 : 1;
      for (const auto& [i, j, k] : {std::tuple{0, 1, 2}, std::tuple{0, 2, 3}}) {
        Eigen::Vector3d a = quad[i], b = quad[j], c = quad[k];
        if ((b - a).cross(c - a).dot(outward) < 0) std::swap(b, c);
        for (const Eigen::Vector3d& p : {outward, a, b, c}) {
          const float xyz[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                static_cast<float>(p.z())};
          put(xyz, sizeof xyz);
        }
        const uint16_t attribute = 0;
        put(&attribute, sizeof attribute);
      }
    }
  }
  return stl;
}

// What a comparison run in a bounded child reports back to the test, in
// memory it shares with the parent.
struct SharedResult {
  int code = -1;  // Status::Code of CompareRevisionShapes
  ShapeComparison shapes;
};

// Two boxes of 990 mm edge, one 10 mm shorter in x (inside the other), as
// the issue measured them: at 1 mm the grid would hold 10^9 voxels (4.8 GB
// seen before the budget). Compared in a child that may map 1 GiB more than
// the test and run 60 s: within the budget it takes a few hundred MB and
// seconds, on 6 mm voxels (the first of the coarser steps whose grid fits
// 2^23 voxels), and the volumes stay within a few percent.
TEST(GeometryDiffTest, BoxesOfAMetreAreComparedOnCoarserVoxelsWithinTheBudget) {
  const std::string a = BoxStl({-495, -495, -495}, {495, 495, 495});
  const std::string b = BoxStl({-485, -495, -495}, {495, 495, 495});
  ASSERT_EQ(a.size(), 684u);
  double chosen = 0;
  ASSERT_TRUE(ChooseDiffVoxel(StructureFormat::kStl, a, StructureFormat::kStl, b, 1.0,
                              kMaxDiffVoxels, &chosen)
                  .ok());
  EXPECT_EQ(chosen, 6.0);
  double voxels = 0;
  ASSERT_TRUE(
      DiffGridVoxels(StructureFormat::kStl, a, StructureFormat::kStl, b, 6.0, &voxels).ok());
  EXPECT_LE(voxels, static_cast<double>(kMaxDiffVoxels));
  ASSERT_TRUE(
      DiffGridVoxels(StructureFormat::kStl, a, StructureFormat::kStl, b, 5.0, &voxels).ok());
  EXPECT_GT(voxels, static_cast<double>(kMaxDiffVoxels)) << "6 mm is not the first step that fits";

  void* shared = ::mmap(nullptr, sizeof(SharedResult), PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  ASSERT_NE(shared, MAP_FAILED);
  auto* result = new (shared) SharedResult();
  const auto start = std::chrono::steady_clock::now();
  const test::BoundedRunResult run = test::RunBounded(int64_t{1} << 30, 60, [&] {
    const Status status = CompareRevisionShapes(StructureFormat::kStl, a, StructureFormat::kStl, b,
                                                1.0, kMaxDiffVoxels, nullptr, &result->shapes);
    result->code = static_cast<int>(status.code());
    return status.ok();
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const SharedResult copy = *result;
  ::munmap(shared, sizeof(SharedResult));
  ASSERT_EQ(run, test::kWorkTrue) << "1 = not ok (code " << copy.code
                                  << "), 2 = out of memory, 3 = out of time, 4 = crashed";
  std::printf("two 990 mm boxes compared in %.2f s on %g mm voxels\n", seconds,
              copy.shapes.overlap.voxel_mm);
  EXPECT_LT(seconds, 30);
  EXPECT_EQ(copy.shapes.overlap.voxel_mm, 6.0);
  const double volume_a = 990.0 * 990 * 990, volume_b = 980.0 * 990 * 990;
  EXPECT_NEAR(copy.shapes.overlap.a_mm3, volume_a, 0.03 * volume_a);
  EXPECT_NEAR(copy.shapes.overlap.b_mm3, volume_b, 0.03 * volume_b);
  EXPECT_NEAR(copy.shapes.overlap.overlap_mm3, copy.shapes.overlap.b_mm3,
              0.01 * copy.shapes.overlap.b_mm3);
  EXPECT_GT(copy.shapes.dice, 0.98);
  EXPECT_LT(copy.shapes.dice, 1.0);
  // The x faces 10 mm apart, seen on 6 mm voxels.
  EXPECT_GE(copy.shapes.hausdorff_mm, 6.0);
  EXPECT_LE(copy.shapes.hausdorff_mm, 18.0);
}

// A pair well within the budget keeps its 1 mm voxels: 40 and 30 mm cubes,
// the smaller inside the larger.
TEST(GeometryDiffTest, SmallShapesKeepTheirMillimetreVoxels) {
  const std::string a = BoxStl({0, 0, 0}, {40, 40, 40});
  const std::string b = BoxStl({5, 5, 5}, {35, 35, 35});
  ShapeComparison shapes;
  const Status status = CompareRevisionShapes(StructureFormat::kStl, a, StructureFormat::kStl, b,
                                              1.0, kMaxDiffVoxels, nullptr, &shapes);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(shapes.overlap.voxel_mm, 1.0);
  EXPECT_NEAR(shapes.overlap.a_mm3, 64000, 0.05 * 64000);
  EXPECT_NEAR(shapes.overlap.b_mm3, 27000, 0.05 * 27000);
  EXPECT_NEAR(shapes.overlap.overlap_mm3, shapes.overlap.b_mm3, 1e-9);
  EXPECT_NEAR(shapes.dice, 2 * 27000.0 / (64000 + 27000), 0.03);
  // The faces 5 mm apart.
  EXPECT_NEAR(shapes.hausdorff_mm, 5 * std::sqrt(3.0), 1.5);
}

// The comparison gives up between its phases once asked to, before it
// voxelises anything.
TEST(GeometryDiffTest, ACancelledComparisonStopsBeforeVoxelising) {
  const std::string a = BoxStl({0, 0, 0}, {40, 40, 40});
  const std::string b = BoxStl({5, 5, 5}, {35, 35, 35});
  int asked = 0;
  ShapeComparison shapes;
  const Status status = CompareRevisionShapes(
      StructureFormat::kStl, a, StructureFormat::kStl, b, 1.0, kMaxDiffVoxels,
      [&] { return ++asked >= 2; }, &shapes);
  EXPECT_EQ(status.code(), Status::Code::kCancelled) << status.ToString();
  EXPECT_EQ(asked, 2);
  EXPECT_EQ(shapes.overlap.voxel_mm, 0);
}

}  // namespace
}  // namespace pba
