// The Zienkiewicz-Zhu estimate split by region: the pieces add up to the
// whole, and a region far from where the stress varies carries no error.
// The one entry point gives each element shape's own estimate: none for a
// uniform stress, some where the finite-element stress jumps.
#include "analysis/error_estimator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "assembly/assembler.h"
#include "common/finite_strain_checks.h"
#include "fem/hex8.h"
#include "material/linear_elastic.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

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
      mesh, stress, volume, ElasticityField::Uniform(IsotropicElasticity(3000, 0.3), ne),
      ThreadContext());
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

// A 2 x 2 x 2 mm box in 1 mm cells, of 4-node tetrahedra or bricks.
Mesh SmallBox(ElementType element) { return testing::BoxMesh(2, 2, 2, 1, element); }

// The nodal displacement u(X) of every node, 3 per node [m].
Eigen::VectorXd Displacement(const Mesh& mesh,
                             const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& u) {
  Eigen::VectorXd out(3 * mesh.num_nodes());
  for (int a = 0; a < mesh.num_nodes(); ++a) {
    out.segment<3>(3 * a) = u(mesh.nodes.row(a).transpose());
  }
  return out;
}

// The finite-element stress of displacement u on the mesh's elements (plain
// integration for bricks).
ElementStress FeStress(const Mesh& mesh, const Eigen::VectorXd& u,
                       const ElasticityField& elasticity) {
  return [&mesh, &u, &elasticity](int e, const Eigen::Vector3d& xi) -> Vector6d {
    if (mesh.quadratic()) {
      return elasticity.D(e) *
             Tet10Strain(Tet10Coordinates(mesh, e), GatherElementTet10(mesh, e, u), xi);
    }
    if (mesh.hexahedral()) {
      return elasticity.D(e) *
             Hex8StrainFull(Hex8Coordinates(mesh, e), GatherElementHex8(mesh, e, u), xi);
    }
    return elasticity.D(e) * StrainDisplacement(ComputeTet4Geometry(TetCorners(mesh, e))) *
           GatherElement(mesh, e, u);
  };
}

// The 4-node estimate from element stresses and volumes, as an analysis
// would call it.
ErrorEstimateResult Tet4Estimate(const Mesh& mesh, const ElementStress& stress,
                                 const ElasticityField& elasticity, const ThreadContext& threads) {
  const int ne = mesh.num_elements();
  std::vector<double> sigma(6 * static_cast<std::size_t>(ne)), volume(ne);
  for (int e = 0; e < ne; ++e) {
    Vector6d::Map(&sigma[6 * static_cast<std::size_t>(e)]) =
        stress(e, Eigen::Vector3d::Constant(0.25));
    volume[e] = ComputeTet4Geometry(TetCorners(mesh, e)).volume;
  }
  return EstimateZzError(mesh, sigma, volume, elasticity, threads);
}

using PerShape = std::function<ErrorEstimateResult(const Mesh&, const ElementStress&,
                                                   const ElasticityField&, const ThreadContext&)>;

struct ShapeCase {
  const char* name;
  Mesh mesh;
  PerShape per_shape;
  // A displacement the element cannot represent, whose stress jumps between
  // elements: quadratic for the linear elements, cubic for the quadratic one
  // (which represents a quadratic one exactly).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> rough;
};

TEST(EstimateZzError, OneEntryPointGivesEachShapesEstimate) {
  const double l = 2e-3;
  const auto linear = [](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    Eigen::Matrix3d a;
    a << 0.010, 0.002, -0.003, 0.001, -0.004, 0.002, 0.003, 0.001, 0.006;
    return a * x + Eigen::Vector3d(1e-5, -2e-5, 3e-5);
  };
  const auto quadratic = [l](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return 0.01 / l * Eigen::Vector3d(x.x() * x.x() + x.y() * x.z(), x.y() * x.y(), x.x() * x.z());
  };
  const auto cubic = [l](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return 0.01 / (l * l) *
           Eigen::Vector3d(x.x() * x.x() * x.x(), x.y() * x.y() * x.z(), x.x() * x.y() * x.z());
  };
  std::vector<ShapeCase> cases;
  cases.push_back({"TET4", SmallBox(ElementType::kTet4), Tet4Estimate, quadratic});
  cases.push_back({"TET10", MakeQuadratic(SmallBox(ElementType::kTet4)),
                   [](const Mesh& m, const ElementStress& s, const ElasticityField& c,
                      const ThreadContext& t) { return EstimateZzErrorTet10(m, s, c, t); },
                   cubic});
  cases.push_back({"HEX8", SmallBox(ElementType::kHex8),
                   [](const Mesh& m, const ElementStress& s, const ElasticityField& c,
                      const ThreadContext& t) { return EstimateZzErrorHex8(m, s, c, t); },
                   quadratic});
  const ThreadContext threads(1);
  for (const ShapeCase& c : cases) {
    SCOPED_TRACE(c.name);
    const Mesh& mesh = c.mesh;
    const ElasticityField elasticity =
        ElasticityField::Uniform(IsotropicElasticity(3000, 0.3), mesh.num_elements());
    ASSERT_GT(mesh.num_elements(), 1);
    const auto estimate = [&](const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& u,
                              ErrorEstimateResult* per_shape) {
      const Eigen::VectorXd nodal = Displacement(mesh, u);
      const ElementStress stress = FeStress(mesh, nodal, elasticity);
      *per_shape = c.per_shape(mesh, stress, elasticity, threads);
      return EstimateZzError(mesh, stress, elasticity, threads);
    };
    ErrorEstimateResult expected;
    // A uniform stress is recovered exactly: no error, up to rounding.
    const ErrorEstimateResult uniform = estimate(linear, &expected);
    EXPECT_LT(uniform.relative_error, 1e-9);
    EXPECT_EQ(uniform.relative_error, expected.relative_error);
    // The quadratic element reproduces a quadratic displacement: none
    // either.
    if (mesh.quadratic()) {
      EXPECT_LT(estimate(quadratic, &expected).relative_error, 1e-9);
    }

    const ErrorEstimateResult rough = estimate(c.rough, &expected);
    EXPECT_GT(rough.relative_error, 1e-3);
    EXPECT_LT(rough.relative_error, 1);
    EXPECT_EQ(rough.relative_error, expected.relative_error);
    EXPECT_EQ(rough.element_share, expected.element_share);
    EXPECT_EQ(rough.element_error2, expected.element_error2);
    EXPECT_EQ(rough.element_energy2, expected.element_energy2);
  }
}

TEST(ZzMethod, NamesTheRecoveryByShapeAndStress) {
  const Mesh tet4 = SmallBox(ElementType::kTet4);
  EXPECT_EQ(ZzMethod(tet4), "Zienkiewicz-Zhu stress recovery (nodal averaging)");
  EXPECT_EQ(ZzMethod(MakeQuadratic(tet4)),
            "Zienkiewicz-Zhu stress recovery (nodal averaging, quadratic)");
  EXPECT_EQ(ZzMethod(SmallBox(ElementType::kHex8)),
            "Zienkiewicz-Zhu stress recovery (nodal averaging, trilinear)");
  EXPECT_EQ(ZzMethod(tet4, ZzStress::kSecondPiolaKirchhoff),
            "Zienkiewicz-Zhu recovery of the second Piola-Kirchhoff stress (nodal averaging), "
            "measured with the initial compliance");
}

}  // namespace
}  // namespace pba
