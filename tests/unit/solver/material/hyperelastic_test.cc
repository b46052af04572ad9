// Hyperelastic materials: stress is the derivative of the energy and the
// tangent that of the stress (central differences), the small-strain limit
// is linear elasticity, and homogeneous uniaxial stress matches the closed
// forms of VALIDATION.md.
#include "material/hyperelastic.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "material/linear_elastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"

namespace pba {
namespace {

struct Case {
  std::string name;
  std::function<std::unique_ptr<HyperelasticMaterial>()> make;
};
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

std::unique_ptr<HyperelasticMaterial> Polynomial(const PolynomialCoefficients& p) {
  EXPECT_TRUE(p.Validate("m").ok()) << p.Validate("m").ToString();
  return std::make_unique<PolynomialMaterial>(p);
}

std::unique_ptr<HyperelasticMaterial> Ogden(std::vector<OgdenTerm> terms, double bulk) {
  OgdenCoefficients p;
  p.terms = std::move(terms);
  p.volumetric.d = {2 / bulk, 0, 0};
  EXPECT_TRUE(p.Validate("m").ok()) << p.Validate("m").ToString();
  return std::make_unique<OgdenMaterial>(p);
}

std::vector<Case> Materials() {
  return {
      {"neo_hookean", [] { return Polynomial(NeoHookeanCoefficients(1000, 5e4)); }},
      {"mooney_rivlin", [] { return Polynomial(MooneyRivlinCoefficients(300, 200, 5e4)); }},
      {"polynomial_n2",
       [] {
         PolynomialCoefficients p;
         p.order = 2;
         p.c[1][0] = 300;
         p.c[0][1] = 200;
         p.c[2][0] = 50;
         p.c[1][1] = -20;
         p.c[0][2] = 10;
         p.volumetric.d = {4e-5, 1e-5, 0};
         return Polynomial(p);
       }},
      {"polynomial_n3",
       [] {
         PolynomialCoefficients p;
         p.order = 3;
         p.c[1][0] = 400;
         p.c[3][0] = 30;
         p.c[1][2] = 5;
         p.volumetric.d = {4e-5, 1e-5, 2e-6};
         return Polynomial(p);
       }},
      {"ogden_brain",
       [] {
         return Ogden({{842, -4.7}}, 842e3);
       }},
      {"ogden_three_terms",
       [] {
         return Ogden({{600, 1.3}, {10, 5.0}, {-20, -2.0}}, 1e5);
       }},
  };
}

// A deformation gradient whose right stretch is C^(1/2): W depends on F only
// through C.
Eigen::Matrix3d StretchOf(const Eigen::Matrix3d& c) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(c);
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseSqrt().asDiagonal() *
         eigen.eigenvectors().transpose();
}

// C + 2 dE for a Voigt (engineering shear) increment h in component `r`.
Eigen::Matrix3d Perturb(const Eigen::Matrix3d& c, int r, double h) {
  Vector6d de = Vector6d::Zero();
  de(r) = r < 3 ? h : h / 2;
  return c + 2 * VoigtToSymmetric(de);
}

std::vector<Eigen::Matrix3d> Deformations() {
  std::vector<Eigen::Matrix3d> fs;
  fs.push_back(Eigen::Matrix3d::Identity());
  fs.push_back(Eigen::Vector3d(1.3, 0.9, 0.9).asDiagonal());  // two equal stretches
  fs.push_back(Eigen::Vector3d(0.7, 1.2, 1.2).asDiagonal());
  Eigen::Matrix3d general;
  general << 1.1, 0.3, -0.1, 0.05, 0.8, 0.2, -0.2, 0.1, 1.25;  // shear and volume change
  fs.push_back(general);
  Eigen::Matrix3d rotated = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                            Eigen::Matrix3d(Eigen::Vector3d(0.6, 1.25, 1.4).asDiagonal());
  fs.push_back(rotated);
  return fs;
}

class MaterialTest : public ::testing::TestWithParam<Case> {};

TEST_P(MaterialTest, StressIsTheEnergyDerivative) {
  const auto material = GetParam().make();
  for (const Eigen::Matrix3d& f : Deformations()) {
    const Eigen::Matrix3d c = f.transpose() * f;
    const Vector6d stress = material->Stress(f);
    const double scale = material->ShearModulus() + stress.norm();
    for (int r = 0; r < 6; ++r) {
      const double h = 1e-6;
      const double numeric = (material->Energy(StretchOf(Perturb(c, r, h))) -
                              material->Energy(StretchOf(Perturb(c, r, -h)))) /
                             (2 * h);
      EXPECT_NEAR(stress(r), numeric, 1e-6 * scale) << "component " << r << "\nF =\n" << f;
    }
  }
}

TEST_P(MaterialTest, TangentIsTheStressDerivative) {
  const auto material = GetParam().make();
  for (const Eigen::Matrix3d& f : Deformations()) {
    const Eigen::Matrix3d c = f.transpose() * f;
    const Matrix6d tangent = material->Tangent(f);
    const double scale = tangent.norm();
    for (int col = 0; col < 6; ++col) {
      const double h = 1e-6;
      const Vector6d numeric = (material->Stress(StretchOf(Perturb(c, col, h))) -
                                material->Stress(StretchOf(Perturb(c, col, -h)))) /
                               (2 * h);
      for (int row = 0; row < 6; ++row) {
        EXPECT_NEAR(tangent(row, col), numeric(row), 1e-6 * scale)
            << "entry (" << row << ", " << col << ")\nF =\n"
            << f;
      }
    }
    EXPECT_LT((tangent - tangent.transpose()).norm(), 1e-9 * scale) << "major symmetry";
  }
}

// W = W_iso + U(J): the parts add up, S_vol = J U' C^-1, and the isochoric
// stress is the derivative of the isochoric energy and is deviatoric
// (S_iso : C = 0).
TEST_P(MaterialTest, IsochoricAndVolumetricPartsAddUp) {
  const auto material = GetParam().make();
  for (const Eigen::Matrix3d& f : Deformations()) {
    const Eigen::Matrix3d c = f.transpose() * f;
    const double j = f.determinant();
    double w_iso = 0;
    Vector6d s_iso;
    Matrix6d c_iso;
    material->Isochoric(f, &w_iso, &s_iso, &c_iso);
    const ScalarDerivatives u = material->Volumetric(j);
    const double scale = material->ShearModulus() + material->Stress(f).norm();
    EXPECT_NEAR(w_iso + u.value, material->Energy(f), 1e-12 * scale);
    const Vector6d s_vol = j * u.first * SymmetricToVoigt(c.inverse());
    EXPECT_LT((s_iso + s_vol - material->Stress(f)).norm(), 1e-9 * scale);
    EXPECT_NEAR((VoigtToSymmetric(s_iso).array() * c.array()).sum(), 0, 1e-9 * scale);
    for (int r = 0; r < 6; ++r) {
      const double h = 1e-6;
      double plus = 0, minus = 0;
      material->Isochoric(StretchOf(Perturb(c, r, h)), &plus, nullptr, nullptr);
      material->Isochoric(StretchOf(Perturb(c, r, -h)), &minus, nullptr, nullptr);
      EXPECT_NEAR(s_iso(r), (plus - minus) / (2 * h), 1e-6 * scale) << "component " << r;
    }
    for (int col = 0; col < 6; ++col) {
      const double h = 1e-6;
      Vector6d plus, minus;
      material->Isochoric(StretchOf(Perturb(c, col, h)), nullptr, &plus, nullptr);
      material->Isochoric(StretchOf(Perturb(c, col, -h)), nullptr, &minus, nullptr);
      EXPECT_LT((c_iso.col(col) - (plus - minus) / (2 * h)).norm(), 1e-6 * c_iso.norm());
    }
  }
}

TEST_P(MaterialTest, StressIsObjective) {
  const auto material = GetParam().make();
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 0.5, 2).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d& f : Deformations()) {
    const Vector6d s = material->Stress(f);
    EXPECT_LT((material->Stress(rotation * f) - s).norm(), 1e-9 * (1 + s.norm()));
    EXPECT_NEAR(material->Energy(rotation * f), material->Energy(f),
                1e-9 * (1 + std::abs(material->Energy(f))));
  }
}

TEST_P(MaterialTest, SmallStrainLimitIsLinearElasticity) {
  const auto material = GetParam().make();
  const double mu = material->ShearModulus(), k = material->BulkModulus();
  const double e = 9 * k * mu / (3 * k + mu);
  const double nu = (3 * k - 2 * mu) / (2 * (3 * k + mu));
  const Matrix6d expected = IsotropicElasticity(e, nu);
  EXPECT_LT((material->Tangent(Eigen::Matrix3d::Identity()) - expected).norm(),
            1e-9 * expected.norm());
  EXPECT_LT(material->Stress(Eigen::Matrix3d::Identity()).norm(), 1e-9 * mu);
  EXPECT_NEAR(material->Energy(Eigen::Matrix3d::Identity()), 0, 1e-12 * mu);
}

TEST_P(MaterialTest, InvertedStateHasInfiniteEnergy) {
  const auto material = GetParam().make();
  EXPECT_EQ(material->Energy(Eigen::Vector3d(1, 1, -0.5).asDiagonal()), INFINITY);
  EXPECT_EQ(material->Energy(Eigen::Matrix3d::Zero()), INFINITY);
  EXPECT_FALSE(material->Describe().empty());
}

INSTANTIATE_TEST_SUITE_P(Hyperelastic, MaterialTest, ::testing::ValuesIn(Materials()),
                         [](const auto& info) { return info.param.name; });

// Nominal stress P11 of homogeneous uniaxial stress at stretch `lambda`: the
// lateral stretch is found by Newton's method on S22 = 0.
double UniaxialNominalStress(const HyperelasticMaterial& material, double lambda) {
  double lateral = 1 / std::sqrt(lambda);
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Matrix3d f = Eigen::Vector3d(lambda, lateral, lateral).asDiagonal();
    const Vector6d s = material.Stress(f);
    const Matrix6d c = material.Tangent(f);
    // dS22/d lateral = (C22 + C23) lateral (dE22 = lateral dlateral).
    const double step = s(1) / ((c(1, 1) + c(1, 2)) * lateral);
    lateral -= step;
    if (std::abs(step) < 1e-15) break;
  }
  const Eigen::Matrix3d f = Eigen::Vector3d(lambda, lateral, lateral).asDiagonal();
  EXPECT_LT(std::abs(material.Stress(f)(1)), 1e-9 * material.ShearModulus());
  return lambda * material.Stress(f)(0);
}

// Incompressible closed forms (VALIDATION.md); with K / mu = 1e6 the
// compressible answer differs by O(mu / K), so 1e-5 relative is the
// tolerance.
TEST(Uniaxial, NearlyIncompressibleMatchesClosedForms) {
  const double ratio = 1e6;
  const PolynomialMaterial neo(NeoHookeanCoefficients(1000, 1000 * ratio));
  const PolynomialMaterial mooney(MooneyRivlinCoefficients(300, 200, 1000 * ratio));
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / (842 * ratio), 0, 0};
  const OgdenMaterial ogden(brain);
  for (double lambda : {0.7, 0.8, 1.3}) {
    const double neo_exact = 1000 * (lambda - std::pow(lambda, -2));
    const double mooney_exact = 2 * (300 + 200 / lambda) * (lambda - std::pow(lambda, -2));
    const double ogden_exact =
        2 * 842 / -4.7 * (std::pow(lambda, -4.7 - 1) - std::pow(lambda, 4.7 / 2 - 1));
    EXPECT_NEAR(UniaxialNominalStress(neo, lambda), neo_exact, 1e-5 * std::abs(neo_exact));
    EXPECT_NEAR(UniaxialNominalStress(mooney, lambda), mooney_exact, 1e-5 * std::abs(mooney_exact));
    EXPECT_NEAR(UniaxialNominalStress(ogden, lambda), ogden_exact, 1e-5 * std::abs(ogden_exact));
  }
}

// VALIDATION.md quotes the compressible neo-Hookean at lambda = 0.8 to two
// decimals: -762.29 Pa for K / mu = 1000, -760.36 Pa for K / mu = 100.
TEST(Uniaxial, CompressibleNeoHookeanMatchesQuotedValues) {
  EXPECT_NEAR(UniaxialNominalStress(PolynomialMaterial(NeoHookeanCoefficients(1000, 1e6)), 0.8),
              -762.29, 0.006);
  EXPECT_NEAR(UniaxialNominalStress(PolynomialMaterial(NeoHookeanCoefficients(1000, 1e5)), 0.8),
              -760.36, 0.006);
}

// Approaching incompressibility never stiffens away from the limit.
TEST(Uniaxial, ConvergesMonotonicallyToTheIncompressibleAnswer) {
  const double exact = 1000 * (0.8 - std::pow(0.8, -2));
  double previous_error = INFINITY;
  for (double ratio : {10.0, 100.0, 1e3, 1e4, 1e5, 1e6}) {
    const double p =
        UniaxialNominalStress(PolynomialMaterial(NeoHookeanCoefficients(1000, 1000 * ratio)), 0.8);
    const double error = std::abs(p - exact);
    EXPECT_LT(error, previous_error) << "K / mu = " << ratio;
    previous_error = error;
  }
}

TEST(Validation, NamesTheBadField) {
  PolynomialCoefficients p = NeoHookeanCoefficients(-10, 1e5);
  EXPECT_EQ(p.Validate("material.neo_hookean").field(), "material.neo_hookean.c10");
  p = NeoHookeanCoefficients(1000, 1e5);
  p.volumetric.d[1] = 1e-6;
  EXPECT_EQ(p.Validate("m").field(), "m.d2");
  p.order = 4;
  EXPECT_EQ(p.Validate("m").field(), "m.order");
  p = NeoHookeanCoefficients(1000, 1e5);
  p.c[2][0] = 5;
  EXPECT_EQ(p.Validate("m").field(), "m.c20");
  p = NeoHookeanCoefficients(1000, -1e5);
  EXPECT_EQ(p.Validate("m").field(), "m.d1");
  p = NeoHookeanCoefficients(1000, 1e5);
  p.c[0][1] = NAN;
  EXPECT_EQ(p.Validate("m").field(), "m.c01");

  OgdenCoefficients o;
  EXPECT_EQ(o.Validate("m").field(), "m.terms");
  o.terms = {{842, 0}};
  EXPECT_EQ(o.Validate("m").field(), "m.terms[0].alpha");
  o.terms = {{842, 2}, {1, 1}, {1, 1}, {1, 1}};
  EXPECT_EQ(o.Validate("m").field(), "m.terms");
  o.terms = {{-842, -4.7}};
  EXPECT_EQ(o.Validate("m").field(), "m.terms");
  o.terms = {{842, -4.7}};
  EXPECT_TRUE(o.Validate("m").ok());
}

TEST(Describe, NamesTheModel) {
  EXPECT_EQ(PolynomialMaterial(NeoHookeanCoefficients(1000, 1e6)).Describe(),
            "neo-Hookean, mu = 1000 Pa, K = 1e+06 Pa");
  EXPECT_EQ(PolynomialMaterial(MooneyRivlinCoefficients(300, 200, 1e6)).Describe(),
            "Mooney-Rivlin, C10 = 300 Pa, C01 = 200 Pa, K = 1e+06 Pa");
  OgdenCoefficients o;
  o.terms = {{842, -4.7}};
  o.volumetric.d = {2e-6, 0, 0};
  EXPECT_EQ(OgdenMaterial(o).Describe(), "Ogden mu = 842 Pa, alpha = -4.7, K = 1e+06 Pa");
}

}  // namespace
}  // namespace pba
