#include "atlas/midside_projection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "atlas/label_mesher.h"
#include "common/plate_stacks.h"
#include "mesh/quadratic.h"
#include "mesh/quality.h"

namespace pba {
namespace {

// Three nested balls drawn on plates 0.5 mm apart (0.2 mm pixels): label 3
// inside radius 4, label 2 out to 6, label 1 out to 9.
constexpr double kRadius[] = {0, 9, 6, 4};

LoftField NestedBalls() {
  std::vector<double> z;
  for (double h = -10; h <= 10; h += 0.5) z.push_back(h);
  const PlateStack stack =
      testing::PaintPlateStack(0.2, 100, 100, z, [](int, double x, double y, double h) {
        const double r = std::sqrt(x * x + y * y + h * h);
        return uint16_t(r <= kRadius[3] ? 3 : r <= kRadius[2] ? 2 : r <= kRadius[1] ? 1 : 0);
      });
  LoftOptions options;
  options.voxel_size_mm = 0.5;
  LoftField field;
  EXPECT_TRUE(field.Build(stack, options).ok());
  return field;
}

// The 10-node mesh of the loft's regions: region r + 1 holds the labels of
// regions[r], the other labels are outside.
Mesh QuadraticMesh(const LoftField& field, const std::vector<std::vector<int>>& regions) {
  std::vector<int> region_of(65536, 0);
  std::vector<std::string> names;
  for (size_t r = 0; r < regions.size(); ++r) {
    for (int l : regions[r]) region_of[l] = static_cast<int>(r) + 1;
    names.push_back("region " + std::to_string(r));
  }
  LabelMeshOptions options;
  options.box_min_mm = Eigen::Vector3d::Constant(-11);
  options.box_max_mm = Eigen::Vector3d::Constant(11);
  options.cell_size_mm = options.facet_size_mm = 3;
  options.facet_distance_mm = 0.5;
  Mesh mesh;
  const Status s = MeshLabels([&](const Eigen::Vector3d& x) { return region_of[field.Label(x)]; },
                              names, options, &mesh);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return MakeQuadratic(mesh);
}

// Mean | |x| - radius | [mm] over the mid-edge nodes of a face set, away
// from the poles (|z| < 0.75 radius, where the loft's end caps are not a
// sphere), at the nodes and at their edges' midpoints.
std::array<double, 2> GapToSphere(const Mesh& mesh, const std::string& set, double radius) {
  std::array<double, 2> gap{0, 0};
  int count = 0;
  const FaceSet& f = mesh.face_sets.at(set);
  for (size_t t = 0; t < f.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = 1e3 * mesh.nodes.row(f.triangles[t][k]).transpose();
      const Eigen::Vector3d b = 1e3 * mesh.nodes.row(f.triangles[t][(k + 1) % 3]).transpose();
      const Eigen::Vector3d m = 1e3 * mesh.nodes.row(f.triangle_midside[t][k]).transpose();
      if (std::abs(m.z()) > 0.75 * radius) continue;
      gap[0] += std::abs(m.norm() - radius);
      gap[1] += std::abs((0.5 * (a + b)).norm() - radius);
      ++count;
    }
  }
  EXPECT_GT(count, 20) << set;
  gap[0] /= count;
  gap[1] /= count;
  return gap;
}

double MaxJacobianRatio(const Mesh& mesh) {
  double worst = 1;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    worst = std::max(worst, Tet10MaxJacobianRatio(Tet10Coordinates(mesh, e)));
  }
  return worst;
}

// An interface and the outer surface: their mid-edge nodes go onto the
// spheres of radius 4 (the shell, a region of two labels {1, 2}, against
// the core {3}: phi = min(d_1, d_2) - d_3) and 9 (the foreground's edge).
TEST(MidsideProjectionTest, InterfaceAndSurfaceNodesGoOntoTheirSpheres) {
  const LoftField field = NestedBalls();
  const std::vector<std::vector<int>> regions = {{1, 2}, {3}};
  Mesh mesh = QuadraticMesh(field, regions);
  const Mesh straight = mesh;
  const MidsideProjectionReport report =
      ProjectMidsideNodes(field, regions, MidsideProjectionOptions(), &mesh);
  const auto interface = GapToSphere(mesh, "interface:region 0|region 1", kRadius[3]);
  const auto surface = GapToSphere(mesh, "surface", kRadius[1]);
  std::printf(
      "nested balls: %lld boundary mid-edge nodes, %lld projected, %lld part of the way, %lld "
      "reset, %lld left; interface %.4f mm from its sphere (%.4f at the midpoints), surface "
      "%.4f (%.4f); mean distance from the level sets %.4f mm (%.4f at the midpoints); "
      "Jacobian ratio up to %.3f\n",
      static_cast<long long>(report.boundary_nodes), static_cast<long long>(report.projected),
      static_cast<long long>(report.shortened), static_cast<long long>(report.reset),
      static_cast<long long>(report.unprojected), interface[0], interface[1], surface[0],
      surface[1], report.gap_mm.mean_mm, report.gap_midpoints_mm.mean_mm, MaxJacobianRatio(mesh));
  EXPECT_LT(5 * interface[0], interface[1]);
  EXPECT_LT(5 * surface[0], surface[1]);
  EXPECT_LT(5 * report.gap_mm.mean_mm, report.gap_midpoints_mm.mean_mm);
  EXPECT_LT(5 * report.gap_mm.p90_mm, report.gap_midpoints_mm.p90_mm);
  EXPECT_LE(report.gap_mm.median_mm, report.gap_mm.p90_mm);
  EXPECT_GT(report.projected, report.boundary_nodes * 9 / 10);
  const double ratio = MaxJacobianRatio(mesh);
  EXPECT_GT(ratio, 1.01);
  EXPECT_LE(ratio, MidsideProjectionOptions().max_jacobian_ratio);
  // Corners and interior mid-edge nodes stay where they were.
  int interior_moved = 0;
  std::vector<char> boundary(mesh.num_nodes(), 0);
  for (const auto& [name, set] : mesh.face_sets) {
    for (int node : set.nodes) boundary[node] = 1;
  }
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    if (!boundary[node]) interior_moved += mesh.nodes.row(node) != straight.nodes.row(node);
  }
  EXPECT_EQ(interior_moved, 0);
}

// Labels of no region are outside: with only the core kept, the core's
// boundary is the surface, against label 2 (phi = max(d_fg, d_3 - d_2)).
TEST(MidsideProjectionTest, SurfaceAgainstLabelsLeftOutFollowsTheirBoundary) {
  const LoftField field = NestedBalls();
  const std::vector<std::vector<int>> regions = {{3}};
  Mesh mesh = QuadraticMesh(field, regions);
  const MidsideProjectionReport report =
      ProjectMidsideNodes(field, regions, MidsideProjectionOptions(), &mesh);
  const auto surface = GapToSphere(mesh, "surface", kRadius[3]);
  std::printf("core alone: surface %.4f mm from its sphere (%.4f at the midpoints)\n", surface[0],
              surface[1]);
  EXPECT_LT(5 * surface[0], surface[1]);
  EXPECT_GT(report.projected, report.boundary_nodes * 9 / 10);
}

// The element check: with a bound no curved element meets and no halving,
// every move is undone; with halvings, a move is undone only after them.
TEST(MidsideProjectionTest, ElementsOverTheBoundGetTheirMidpointsBack) {
  const LoftField field = NestedBalls();
  const std::vector<std::vector<int>> regions = {{1, 2, 3}};
  const Mesh straight = QuadraticMesh(field, regions);
  for (const int halvings : {0, 2}) {
    SCOPED_TRACE(halvings);
    Mesh mesh = straight;
    MidsideProjectionOptions options;
    options.max_jacobian_ratio = 1 + 1e-9;
    options.halvings = halvings;
    const MidsideProjectionReport report = ProjectMidsideNodes(field, regions, options, &mesh);
    // (A node already on its level set, not moved, counts as projected.)
    EXPECT_GT(report.reset, report.boundary_nodes * 9 / 10);
    EXPECT_EQ(report.shortened, 0);
    EXPECT_EQ(report.mean_move_mm, 0);
    EXPECT_GE(report.check_passes, halvings + 2);
    EXPECT_LE(MaxJacobianRatio(mesh), 1 + 1e-9);
  }
}

}  // namespace
}  // namespace pba
