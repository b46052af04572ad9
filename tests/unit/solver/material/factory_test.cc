// The elasticity and compliance matrices a linear analysis takes from a
// MaterialSpec: isotropic models as before, orthotropic ones rotated into
// the global frame, and each compliance the inverse of its elasticity.
#include "material/factory.h"

#include <gtest/gtest.h>

#include <string>

#include "material/linear_elastic.h"

namespace pba {
namespace {

MaterialSpec Orthotropic() {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kOrthotropicElastic;
  m.orthotropic_elastic = {6000, 3000, 1500, 0.3, 0.35, 0.4, 1500, 900, 600, {1, 1, 0}, {0, 0, 1}};
  return m;
}

double MaxAbs(const Matrix6d& m) { return m.cwiseAbs().maxCoeff(); }

TEST(ElasticityMatrixTest, IsotropicModelsKeepTheirMatrix) {
  MaterialSpec linear;
  linear.kind = MaterialSpec::Kind::kLinearElastic;
  linear.linear_elastic = {3000, 0.45};
  EXPECT_EQ(MaxAbs(ElasticityMatrix(linear) - IsotropicElasticity(3000, 0.45)), 0.0);
  EXPECT_EQ(MaxAbs(ComplianceMatrix(linear) - IsotropicCompliance(3000, 0.45)), 0.0);

  MaterialSpec neo;
  neo.kind = MaterialSpec::Kind::kNeoHookean;
  neo.neo_hookean = {1000, 1e6};
  const InitialModuli p = InitialElasticModuli(neo);
  EXPECT_EQ(
      MaxAbs(ElasticityMatrix(neo) - IsotropicElasticity(p.youngs_modulus_pa, p.poissons_ratio)),
      0.0);
}

TEST(ElasticityMatrixTest, OrthotropicIsRotatedIntoTheGlobalFrame) {
  const MaterialSpec m = Orthotropic();
  ASSERT_TRUE(ValidateMaterialSpec(m, "material").ok());
  const OrthotropicElasticParams& p = m.orthotropic_elastic;
  const Matrix6d expected =
      RotateElasticity(OrthotropicElasticity(p), MaterialFrame(p.axis_1, p.axis_2));
  EXPECT_EQ(MaxAbs(ElasticityMatrix(m) - expected), 0.0);
  // Axis 1 at 45 degrees in the x-y plane couples xx and yy to xy shear.
  EXPECT_GT(std::abs(ElasticityMatrix(m)(0, 5)), 100.0);
  EXPECT_LT(MaxAbs(ElasticityMatrix(m) * ComplianceMatrix(m) - Matrix6d::Identity()), 1e-12);
}

TEST(ElasticityMatrixTest, ValidationAndDescriptionNameTheModel) {
  MaterialSpec m = Orthotropic();
  m.orthotropic_elastic.nu23 = 3;
  EXPECT_EQ(ValidateMaterialSpec(m, "material").field(), "material.orthotropic_elastic.nu23");
  const std::string text = DescribeMaterial(Orthotropic());
  EXPECT_NE(text.find("orthotropic linear elastic, E1 = 6000 Pa"), std::string::npos) << text;
  EXPECT_NE(text.find("axis 2 = (0, 0, 1)"), std::string::npos) << text;
  EXPECT_FALSE(Orthotropic().hyperelastic());
}

}  // namespace
}  // namespace pba
