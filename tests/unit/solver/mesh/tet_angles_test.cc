#include "mesh/tet_angles.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "mesh/quality.h"

namespace pba {
namespace {

using Vec3 = Eigen::Vector3d;

constexpr double kDegree = kPi / 180;

// A positively oriented tetrahedron with random corners in the unit cube.
Eigen::Matrix<double, 4, 3> RandomTet(std::mt19937* random) {
  std::uniform_real_distribution<double> uniform(0, 1);
  Eigen::Matrix<double, 4, 3> x;
  for (int a = 0; a < 4; ++a) {
    for (int c = 0; c < 3; ++c) x(a, c) = uniform(*random);
  }
  const Vec3 e1 = (x.row(1) - x.row(0)).transpose();
  const Vec3 e2 = (x.row(2) - x.row(0)).transpose();
  const Vec3 e3 = (x.row(3) - x.row(0)).transpose();
  if (e1.dot(e2.cross(e3)) < 0) {
    const Eigen::RowVector3d swap = x.row(2);
    x.row(2) = x.row(3);
    x.row(3) = swap;
  }
  return x;
}

Vec3 Row(const Eigen::Matrix<double, 4, 3>& x, int a) { return x.row(a).transpose(); }

TEST(TetAnglesTest, QualityIsTheSmallestDihedralAngleOfQualityH) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix<double, 4, 3> x = RandomTet(&random);
    const double q = TetQuality(Row(x, 0), Row(x, 1), Row(x, 2), Row(x, 3));
    EXPECT_NEAR(q / kDegree, TetDihedralRangeDegrees(x)[0], 1e-9) << "trial " << trial;
  }
  // The regular tetrahedron: arccos(1/3) along every edge.
  const Vec3 p0(1, 1, 1), p1(1, -1, -1), p2(-1, -1, 1), p3(-1, 1, -1);
  ASSERT_GT((p1 - p0).dot((p2 - p0).cross(p3 - p0)), 0);
  EXPECT_NEAR(TetQuality(p0, p1, p2, p3), std::acos(1.0 / 3), 1e-14);
  // Inverted, flat.
  EXPECT_EQ(TetQuality(p0, p2, p1, p3), kInvalidTet);
  EXPECT_EQ(TetQuality(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)), kInvalidTet);
}

// The gradients against central differences of the angles, at each corner
// in turn (put first by an even permutation).
TEST(TetAnglesTest, GradientsMatchFiniteDifferences) {
  std::mt19937 random(11);
  static constexpr int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
  int checked = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix<double, 4, 3> tet = RandomTet(&random);
    if (TetDihedralRangeDegrees(tet)[0] < 5) continue;  // too close to the kinks at 0 and 180
    for (const auto& order : kEven) {
      const Vec3 x = Row(tet, order[0]);
      const std::array<Vec3, 3> p = {Row(tet, order[1]), Row(tet, order[2]), Row(tet, order[3])};
      std::array<double, 6> angle;
      std::array<Vec3, 6> gradient;
      DihedralAnglesAndGradients(x, p, &angle, &gradient);
      const double h = 1e-6;
      for (int c = 0; c < 3; ++c) {
        std::array<double, 6> plus, minus;
        std::array<Vec3, 6> unused;
        DihedralAnglesAndGradients(x + h * Vec3::Unit(c), p, &plus, &unused);
        DihedralAnglesAndGradients(x - h * Vec3::Unit(c), p, &minus, &unused);
        for (int edge = 0; edge < 6; ++edge) {
          const double numeric = (plus[edge] - minus[edge]) / (2 * h);
          EXPECT_NEAR(gradient[edge][c], numeric, 1e-6 * (1 + std::abs(numeric)))
              << "trial " << trial << " edge " << edge << " component " << c;
        }
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

// The eight tetrahedra of an octahedron of unit half-diagonal around its
// centre node, each positively oriented with the node at the centre.
std::vector<std::array<Vec3, 3>> OctahedronStar() {
  std::vector<std::array<Vec3, 3>> star;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      for (const double sz : {-1.0, 1.0}) {
        std::array<Vec3, 3> p = {Vec3(sx, 0, 0), Vec3(0, sy, 0), Vec3(0, 0, sz)};
        if (sx * sy * sz < 0) std::swap(p[1], p[2]);
        star.push_back(p);
      }
    }
  }
  return star;
}

// The eight tetrahedra of an octahedron around its centre node: moved off
// the centre, the ascent brings the node back towards it, where every
// tetrahedron's smallest angle is arctan(sqrt 2) = 54.7 degrees.
TEST(TetAnglesTest, AscentRecentresAnOctahedronsNode) {
  const std::vector<std::array<Vec3, 3>> star = OctahedronStar();
  const StarObjective objective(star);
  const double best = std::atan(std::sqrt(2.0));
  EXPECT_NEAR(objective.Value(Vec3::Zero()), best, 1e-12);
  Vec3 x(0.3, -0.2, 0.1);
  const double start = objective.Value(x);
  ASSERT_GT(start, 0);
  const double end = objective.Ascend(&x, start, 50);
  EXPECT_GT(end, start + 10 * kDegree);
  EXPECT_NEAR(end, objective.Value(x), 1e-15);
  EXPECT_GT(end, best - 1 * kDegree);
  EXPECT_LT(x.norm(), 0.02);
  // Inverted: the value says so, and the ascent does not start.
  EXPECT_EQ(objective.Value(Vec3(2, 0, 0)), kInvalidTet);
  Vec3 outside(2, 0, 0);
  EXPECT_EQ(objective.Ascend(&outside, kInvalidTet), kInvalidTet);
  EXPECT_EQ(outside, Vec3(2, 0, 0));
}

// TetMeasure: the angle alone without a scale; with one, the smaller of
// 1 / A (TetAspectRatio, computed independently in quality.cc) and the
// scaled angle; a needle with good angles is caught by its aspect ratio.
TEST(TetAnglesTest, MeasureIsTheSmallerOfInverseAspectRatioAndScaledAngle) {
  std::mt19937 random(13);
  const TetMeasure angle_only;
  const TetMeasure both{15 * kDegree * 4};
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix<double, 4, 3> x = RandomTet(&random);
    const Vec3 p0 = Row(x, 0), p1 = Row(x, 1), p2 = Row(x, 2), p3 = Row(x, 3);
    const double angle = TetQuality(p0, p1, p2, p3);
    if (angle == kInvalidTet) continue;
    EXPECT_EQ(angle_only(p0, p1, p2, p3), angle);
    const double expected = std::min(1 / TetAspectRatio(x), angle / both.angle_scale);
    EXPECT_NEAR(both(p0, p1, p2, p3), expected, 1e-12 * expected) << "trial " << trial;
  }
  // A needle: an equilateral base of side 0.05 under an apex 1 away. Its
  // smallest dihedral angle is near 60 degrees, its aspect ratio far above 4.
  const Vec3 a(0, 0, 0), b(0.05, 0, 0), c(0.025, 0.05 * std::sqrt(3.0) / 2, 0),
      apex(0.025, 0.05 * std::sqrt(3.0) / 6, 1);
  EXPECT_GT(TetQuality(a, b, c, apex), 55 * kDegree);
  EXPECT_LT(both(a, b, c, apex), 1.0 / 20);
  // Inverted: invalid either way.
  EXPECT_EQ(both(a, c, b, apex), kInvalidTet);
  // The regular tetrahedron reaches 1.
  const Vec3 q0(1, 1, 1), q1(1, -1, -1), q2(-1, -1, 1), q3(-1, 1, -1);
  EXPECT_NEAR(both(q0, q1, q2, q3), 1, 1e-14);
}

// The gradient of 1 / A against central differences, at each corner.
TEST(TetAnglesTest, InverseAspectRatioGradientMatchesFiniteDifferences) {
  std::mt19937 random(17);
  static constexpr int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
  int checked = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix<double, 4, 3> tet = RandomTet(&random);
    if (TetDihedralRangeDegrees(tet)[0] < 1) continue;
    for (const auto& order : kEven) {
      const Vec3 x = Row(tet, order[0]);
      const std::array<Vec3, 3> p = {Row(tet, order[1]), Row(tet, order[2]), Row(tet, order[3])};
      double value;
      Vec3 gradient;
      InverseAspectRatioAndGradient(x, p, &value, &gradient);
      EXPECT_NEAR(value, 1 / TetAspectRatio(tet), 1e-12) << "trial " << trial;
      const double h = 1e-6;
      for (int c = 0; c < 3; ++c) {
        double plus, minus;
        Vec3 unused;
        InverseAspectRatioAndGradient(x + h * Vec3::Unit(c), p, &plus, &unused);
        InverseAspectRatioAndGradient(x - h * Vec3::Unit(c), p, &minus, &unused);
        const double numeric = (plus - minus) / (2 * h);
        EXPECT_NEAR(gradient[c], numeric, 1e-6 * (1 + std::abs(numeric)))
            << "trial " << trial << " component " << c;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 200);
}

// The octahedron's star under the measure with the aspect ratio: at the
// centre each tetrahedron has edges 1, 1, 1, sqrt 2 (three times), so
// 1 / A = sqrt 2 / 1.5^1.5 = 0.7698, below its scaled angle; off the centre
// the ascent comes back to it.
TEST(TetAnglesTest, AscentWithTheAspectRatioRecentresAnOctahedronsNode) {
  const std::vector<std::array<Vec3, 3>> star = OctahedronStar();
  const StarObjective objective(star, TetMeasure{15 * kDegree * 4});
  const double best = std::sqrt(2.0) / std::pow(1.5, 1.5);
  EXPECT_NEAR(objective.Value(Vec3::Zero()), best, 1e-12);
  Vec3 x(0.3, -0.2, 0.1);
  const double start = objective.Value(x);
  ASSERT_GT(start, 0);
  const double end = objective.Ascend(&x, start, 50);
  EXPECT_GT(end, start + 0.1);
  EXPECT_NEAR(end, objective.Value(x), 1e-15);
  EXPECT_GT(end, best - 0.01);
  EXPECT_LT(x.norm(), 0.02);
}

}  // namespace
}  // namespace pba
