// The Zienkiewicz-Zhu estimate split by region: the pieces add up to the
// whole, and a region far from where the stress varies carries no error.
#include "analysis/error_estimator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "material/linear_elastic.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

Mesh Bar() {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 2, 2};
  MeshSpec m;
  m.element_size_mm = 1;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

double CentroidX(const Mesh& mesh, int e) { return TetCorners(mesh, e).col(0).mean(); }

TEST(ErrorByRegion, RegionsAddUpAndAQuietRegionHasNoError) {
  Mesh mesh = Bar();
  const int ne = mesh.num_elements();
  mesh.region_names = {"left", "right"};
  mesh.element_region.resize(ne);
  std::vector<double> stress(6 * static_cast<std::size_t>(ne), 0.0), volume(ne);
  for (int e = 0; e < ne; ++e) {
    const double x = CentroidX(mesh, e);
    mesh.element_region[e] = x < 5e-3 ? 0 : 1;
    volume[e] = ComputeTet4Geometry(TetCorners(mesh, e)).volume;
    stress[6 * e] = 1000;  // uniform, but for a ragged patch near the right end
    if (x > 8e-3) stress[6 * e] += 300 * std::sin(1e4 * x + e);
  }
  const ErrorEstimateResult estimate = EstimateZzError(
      mesh, stress, volume, ElasticityField::Uniform(IsotropicElasticity(3000, 0.3), ne));
  ASSERT_GT(estimate.relative_error, 0);
  const std::vector<RegionError> regions = ErrorByRegion(mesh, estimate, "body");
  ASSERT_EQ(regions.size(), 2u);
  EXPECT_EQ(regions[0].name, "left");
  EXPECT_EQ(regions[0].elements + regions[1].elements, ne);
  EXPECT_LT(regions[0].relative_error, 1e-12);  // rounding of the nodal averages
  EXPECT_LT(regions[0].share, 1e-24);
  EXPECT_NEAR(regions[1].share, 1, 1e-15);
  EXPECT_GT(regions[1].relative_error, estimate.relative_error);  // concentrated there

  // Without regions: one, named by the caller, equal to the whole.
  mesh.region_names.clear();
  mesh.element_region.clear();
  const std::vector<RegionError> one = ErrorByRegion(mesh, estimate, "body");
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].name, "body");
  EXPECT_EQ(one[0].elements, ne);
  EXPECT_NEAR(one[0].relative_error, estimate.relative_error, 1e-15);
}

}  // namespace
}  // namespace pba
