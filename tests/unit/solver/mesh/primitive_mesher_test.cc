#include "mesh/primitive_mesher.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "fem/tet4.h"

namespace pba {
namespace {

double TotalVolume(const Mesh& mesh, double* min_volume) {
  double total = 0;
  *min_volume = INFINITY;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double v = ComputeTet4Geometry(TetCorners(mesh, e)).volume;
    total += v;
    *min_volume = std::min(*min_volume, v);
  }
  return total;
}

// Conforming: every interior triangle is shared by exactly two elements, and
// the faces used once are exactly the boundary face sets.
void ExpectConforming(const Mesh& mesh) {
  std::map<std::array<int, 3>, int> count;
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (const auto& t : mesh.tets) {
    for (const auto& f : kFaces) {
      std::array<int, 3> key = {t[f[0]], t[f[1]], t[f[2]]};
      std::sort(key.begin(), key.end());
      ++count[key];
    }
  }
  std::set<std::array<int, 3>> boundary;
  for (const auto& [name, set] : mesh.face_sets) {
    for (auto tri : set.triangles) {
      std::sort(tri.begin(), tri.end());
      boundary.insert(tri);
    }
  }
  std::size_t once = 0;
  for (const auto& [face, n] : count) {
    ASSERT_LE(n, 2);
    if (n == 1) {
      ++once;
      EXPECT_TRUE(boundary.count(face)) << "a boundary face belongs to no set";
    }
  }
  EXPECT_EQ(once, boundary.size());
}

TEST(PrimitiveMesherTest, BoxVolumeIsExactAndMeshConforming) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec options;
  options.element_size_mm = 5;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  EXPECT_EQ(mesh.num_elements(), 6 * 2 * 4 * 6);
  EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
  double min_volume;
  EXPECT_NEAR(TotalVolume(mesh, &min_volume), 10e-3 * 20e-3 * 30e-3, 1e-15);
  EXPECT_GT(min_volume, 0);
  ExpectConforming(mesh);
  // Face set areas [m^2].
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("bottom")), 200e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("top")), 200e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("x_min")), 600e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("y_max")), 300e-6, 1e-15);
  for (int node : mesh.face_sets.at("top").nodes) EXPECT_NEAR(mesh.nodes(node, 2), 30e-3, 1e-15);
}

TEST(PrimitiveMesherTest, CylinderVolumeConvergesAndMeshIsConforming) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  g.cylinder = {10, 20};
  const double exact = std::numbers::pi * 10e-3 * 10e-3 * 20e-3;
  double previous_error = INFINITY;
  for (double h : {4.0, 2.0, 1.0}) {
    MeshSpec options;
    options.element_size_mm = h;
    MeshStats stats;
    const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
    EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
    double min_volume;
    const double error = std::abs(TotalVolume(mesh, &min_volume) - exact) / exact;
    EXPECT_GT(min_volume, 0) << "h = " << h;
    // A polygon inscribed in the circle: the error falls like h^2.
    EXPECT_LT(error, 0.4 * previous_error) << "h = " << h;
    previous_error = error;
    if (h == 2.0) ExpectConforming(mesh);
    for (int node : mesh.face_sets.at("side").nodes) {
      EXPECT_NEAR(mesh.nodes.row(node).head<2>().norm(), 10e-3, 1e-12);
    }
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(PrimitiveMesherTest, DefaultElementSizeIsATwentiethOfTheLargestDimension) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 40};
  EXPECT_DOUBLE_EQ(EffectiveElementSize(g, MeshSpec()), 2.0);
}

}  // namespace
}  // namespace pba
