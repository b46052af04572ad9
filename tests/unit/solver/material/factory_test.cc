// The elasticity and compliance matrices a linear analysis takes from a
// MaterialSpec: isotropic models as before, orthotropic ones rotated into
// the global frame, and each compliance the inverse of its elasticity.
#include "material/factory.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

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

// The three forms of a relaxation give one normalised Prony series.
TEST(PronySeriesOfTest, EachForm) {
  ViscoelasticSpec v;
  EXPECT_TRUE(PronySeriesOf(v).g.empty());  // none: no relaxation

  v.form = ViscoelasticSpec::Form::kProny;
  v.g = {0.5, 0.2};
  v.tau_s = {0.5, 5};
  PronySeries series = PronySeriesOf(v);
  EXPECT_EQ(series.g, (std::vector<double>{0.5, 0.2}));
  EXPECT_EQ(series.tau_s, (std::vector<double>{0.5, 5}));
  EXPECT_NEAR(series.LongTermFactor(), 0.3, 1e-15);

  // G_inf / G0 = 0.3, beta = 2 /s: g = 1 - 0.3, tau = 1/beta.
  v = ViscoelasticSpec();
  v.form = ViscoelasticSpec::Form::kExponential;
  v.long_term_ratio = 0.3;
  v.beta_per_s = 2;
  series = PronySeriesOf(v);
  ASSERT_EQ(series.g.size(), 1u);
  EXPECT_NEAR(series.g[0], 0.7, 1e-15);
  EXPECT_EQ(series.tau_s, (std::vector<double>{0.5}));

  // G_inf = 300 Pa, G_i = 500 and 200 Pa: G0 = 1000 Pa, g = [0.5, 0.2].
  v = ViscoelasticSpec();
  v.form = ViscoelasticSpec::Form::kModuli;
  v.long_term_modulus_pa = 300;
  v.moduli_pa = {500, 200};
  v.tau_s = {0.1, 10};
  series = PronySeriesOf(v);
  ASSERT_EQ(series.g.size(), 2u);
  EXPECT_NEAR(series.g[0], 0.5, 1e-15);
  EXPECT_NEAR(series.g[1], 0.2, 1e-15);
  EXPECT_EQ(series.tau_s, (std::vector<double>{0.1, 10}));
  EXPECT_TRUE(series.Validate().ok());
}

TEST(PronySeriesOfTest, DescriptionAndChecksOfARelaxingMaterial) {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kNeoHookean;
  m.neo_hookean = {1000, 1e6};
  m.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  m.viscoelastic.g = {0.5, 0.2};
  m.viscoelastic.tau_s = {0.5, 5};
  ASSERT_TRUE(ValidateMaterialSpec(m, "material").ok());
  const std::string text = DescribeMaterial(m);
  EXPECT_NE(text.find(", relaxing: g = [0.5, 0.2], tau = [0.5, 5] s, mu_inf/mu0 = 0.3"),
            std::string::npos)
      << text;

  m.kind = MaterialSpec::Kind::kLinearElastic;
  m.linear_elastic = {3000, 0.45};
  const Status status = ValidateMaterialSpec(m, "inclusions[0].material");
  EXPECT_EQ(status.field(), "inclusions[0].material.viscoelastic");
  EXPECT_NE(status.message().find("only for hyperelastic models"), std::string::npos);
}

}  // namespace
}  // namespace pba
