#include "mesh/quality.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "mesh/quadratic.h"

namespace pba {
namespace {

// A regular tetrahedron of edge 2 sqrt 2 (alternate corners of a cube),
// positively oriented.
Eigen::Matrix<double, 4, 3> Regular() {
  Eigen::Matrix<double, 4, 3> x;
  x << 1, 1, 1, 1, -1, -1, -1, -1, 1, -1, 1, -1;
  return x;
}

// A 10-node tetrahedron with straight edges: mid-edge nodes at midpoints.
Tet10Nodes Straight(const Eigen::Matrix<double, 4, 3>& corners) {
  Tet10Nodes x;
  x.topRows<4>() = corners;
  for (int k = 0; k < 6; ++k)
    x.row(4 + k) = 0.5 * (corners.row(kTet10Edges[k][0]) + corners.row(kTet10Edges[k][1]));
  return x;
}

TEST(QualityTest, RegularTetrahedronHasAspectRatioOneAndDihedralArccosThird) {
  const Eigen::Matrix<double, 4, 3> x = Regular();
  EXPECT_NEAR(TetAspectRatio(x), 1, 1e-12);
  EXPECT_NEAR(TetAspectRatio(0.001 * x), 1, 1e-12) << "scale invariant";
  const std::array<double, 2> range = TetDihedralRangeDegrees(x);
  const double expected = std::acos(1.0 / 3) * 180 / std::numbers::pi;  // 70.5288
  EXPECT_NEAR(range[0], expected, 1e-10);
  EXPECT_NEAR(range[1], expected, 1e-10);
  EXPECT_NEAR(expected, 70.5288, 1e-4);
}

TEST(QualityTest, FlattenedSliverHasLargeAspectRatioAndExtremeDihedrals) {
  // The four corners of a square, two lifted by +-h: a sliver as h -> 0.
  for (double h : {0.1, 0.01}) {
    Eigen::Matrix<double, 4, 3> x;
    x << 0, 0, 0, 1, 1, 0, 1, 0, h, 0, 1, h;
    if ((x.row(1) - x.row(0)).dot((x.row(2) - x.row(0)).cross(x.row(3) - x.row(0))) < 0)
      x.row(2).swap(x.row(3));
    const double aspect = TetAspectRatio(x);
    const std::array<double, 2> range = TetDihedralRangeDegrees(x);
    EXPECT_GT(aspect, 0.5 / h) << "h = " << h;
    EXPECT_LT(range[0], 20 * h * 180 / std::numbers::pi) << "h = " << h;
    EXPECT_GT(range[1], 180 - 20 * h * 180 / std::numbers::pi) << "h = " << h;
  }
  Eigen::Matrix<double, 4, 3> flat = Regular();
  flat.row(3) = flat.row(1) + flat.row(2) - flat.row(0);  // coplanar: no volume
  EXPECT_TRUE(std::isinf(TetAspectRatio(flat)));
  Eigen::Matrix<double, 4, 3> inverted = Regular();
  inverted.row(2).swap(inverted.row(3));
  EXPECT_TRUE(std::isinf(TetAspectRatio(inverted)));
}

TEST(QualityTest, JacobianRatioIsOneForStraightEdgesAndGrowsWhenAMidEdgeNodeMoves) {
  const Tet10Nodes straight = Straight(Regular());
  EXPECT_NEAR(Tet10MaxJacobianRatio(straight), 1, 1e-12);
  double previous = 1;
  for (double shift : {0.1, 0.3, 0.5}) {
    Tet10Nodes bent = straight;
    bent(4, 2) += shift;  // edge (0, 1)'s node off its midpoint
    const double ratio = Tet10MaxJacobianRatio(bent);
    EXPECT_GT(ratio, previous) << "shift " << shift;
    previous = ratio;
  }
  Tet10Nodes folded = straight;
  folded.row(4) = straight.row(2);  // far beyond the opposite corner: inverted
  EXPECT_TRUE(std::isinf(Tet10MaxJacobianRatio(folded)));
}

// Two regular tetrahedra sharing a face, in two regions, and one of them a
// sliver: per-region figures, the overall ones, the volume.
TEST(QualityTest, SummariseGathersPerRegionAndOverall) {
  Mesh mesh;
  const Eigen::Matrix<double, 4, 3> x = Regular();
  mesh.nodes.resize(5, 3);
  mesh.nodes.topRows<4>() = x;
  // The fifth node mirrors node 0 through face (1, 2, 3), close to it: a
  // flat tetrahedron (1, 2, 3, 4) on the other side of that face.
  const Eigen::RowVector3d centroid = (x.row(1) + x.row(2) + x.row(3)) / 3;
  mesh.nodes.row(4) = centroid + 0.05 * (centroid - x.row(0));
  mesh.tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  mesh.region_names = {"regular", "flat"};
  mesh.element_region = {0, 1};
  const QualitySummary s = Summarise(mesh);
  ASSERT_EQ(s.regions.size(), 2u);
  EXPECT_EQ(s.overall.count, 2);
  EXPECT_EQ(s.regions[0].count, 1);
  EXPECT_NEAR(s.regions[0].median_aspect_ratio, 1, 1e-12);
  EXPECT_NEAR(s.regions[0].min_dihedral_deg, 70.5288, 1e-4);
  EXPECT_GT(s.regions[1].max_aspect_ratio, 3);
  EXPECT_NEAR(s.overall.min_aspect_ratio, 1, 1e-12);
  EXPECT_EQ(s.overall.max_aspect_ratio, s.regions[1].max_aspect_ratio);
  EXPECT_NEAR(s.overall.median_aspect_ratio, 0.5 * (1 + s.regions[1].median_aspect_ratio), 1e-12);
  const double regular_volume = std::pow(2 * std::numbers::sqrt2, 3) / (6 * std::numbers::sqrt2);
  EXPECT_NEAR(s.regions[0].volume, regular_volume, 1e-12);
  EXPECT_NEAR(s.overall.volume, 1.05 * regular_volume, 1e-12);
  EXPECT_EQ(s.overall.max_jacobian_ratio, 1) << "linear mesh";

  // Quadratic: straight mid-edge nodes keep the Jacobian ratio at 1.
  const QualitySummary q = Summarise(MakeQuadratic(mesh));
  EXPECT_NEAR(q.overall.max_jacobian_ratio, 1, 1e-12);
  EXPECT_NEAR(q.overall.volume, s.overall.volume, 1e-12);
}

// The 99th percentile: the aspect ratio 99 % of the elements do not exceed.
// 100 elements: with one flat one it is still the regular elements' 1; with
// two flat ones, the better of the two.
TEST(QualityTest, NinetyNinthPercentileOfTheAspectRatio) {
  Mesh mesh;
  const Eigen::Matrix<double, 4, 3> x = Regular();
  mesh.nodes.resize(6, 3);
  mesh.nodes.topRows<4>() = x;
  const Eigen::RowVector3d centroid = (x.row(1) + x.row(2) + x.row(3)) / 3;
  mesh.nodes.row(4) = centroid + 0.05 * (centroid - x.row(0));  // flat (1, 2, 3, 4)
  mesh.nodes.row(5) = centroid + 0.10 * (centroid - x.row(0));  // less flat (1, 2, 3, 5)
  mesh.tets.assign(99, {0, 1, 2, 3});
  mesh.tets.push_back({1, 2, 3, 4});
  EXPECT_NEAR(Summarise(mesh).overall.p99_aspect_ratio, 1, 1e-12);
  mesh.tets[0] = {1, 2, 3, 5};
  const QualitySummary s = Summarise(mesh);
  const double flat = TetAspectRatio(TetCorners(mesh, 99));
  const double less_flat = TetAspectRatio(TetCorners(mesh, 0));
  ASSERT_GT(flat, less_flat);
  EXPECT_EQ(s.overall.p99_aspect_ratio, less_flat);
  EXPECT_EQ(s.overall.max_aspect_ratio, flat);
}

}  // namespace
}  // namespace pba
