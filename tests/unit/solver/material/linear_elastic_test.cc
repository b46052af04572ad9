// Orthotropic elasticity: the compliance and its inverse, the isotropic
// special case, the Bond rotation against a direct tensor rotation, a quarter
// turn that swaps directions 1 and 2, and the checks that name the bad field.
#include "material/linear_elastic.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <string>

#include "material/hyperelastic.h"

namespace pba {
namespace {

// A clearly anisotropic set (E1 = 4 E3), positive definite with margin.
OrthotropicElasticParams Sample() {
  OrthotropicElasticParams p;
  p.e1_pa = 6000;
  p.e2_pa = 3000;
  p.e3_pa = 1500;
  p.nu12 = 0.3;
  p.nu13 = 0.35;
  p.nu23 = 0.4;
  p.g12_pa = 1500;
  p.g13_pa = 900;
  p.g23_pa = 600;
  return p;
}

// An oblique frame: no axis along x, y or z.
Eigen::Matrix3d ObliqueFrame() { return MaterialFrame({1, 2, 0.5}, {-1, 0.3, 2}); }

double MaxAbs(const Matrix6d& m) { return m.cwiseAbs().maxCoeff(); }

TEST(OrthotropicElasticityTest, IsTheInverseOfTheCompliance) {
  const OrthotropicElasticParams p = Sample();
  ASSERT_TRUE(p.Validate("m").ok()) << p.Validate("m").ToString();
  const Matrix6d product = OrthotropicElasticity(p) * OrthotropicCompliance(p);
  EXPECT_LT(MaxAbs(product - Matrix6d::Identity()), 1e-12);
  // The compliance is symmetric by construction: nu21 / E2 = nu12 / E1.
  const Matrix6d s = OrthotropicCompliance(p);
  EXPECT_DOUBLE_EQ(s(1, 0), -(p.nu12 * p.e2_pa / p.e1_pa) / p.e2_pa);
  EXPECT_EQ(MaxAbs(s - s.transpose()), 0.0);
}

TEST(OrthotropicElasticityTest, IsotropicConstantsGiveIsotropicElasticity) {
  const double e = 3000, nu = 0.45, g = e / (2 * (1 + nu));
  OrthotropicElasticParams p;
  p.e1_pa = p.e2_pa = p.e3_pa = e;
  p.nu12 = p.nu13 = p.nu23 = nu;
  p.g12_pa = p.g13_pa = p.g23_pa = g;
  ASSERT_TRUE(p.Validate("m").ok());
  const Matrix6d iso = IsotropicElasticity(e, nu);
  EXPECT_LT(MaxAbs(OrthotropicElasticity(p) - iso), 1e-12 * MaxAbs(iso));
  EXPECT_LT(MaxAbs(OrthotropicCompliance(p) - IsotropicCompliance(e, nu)), 1e-12 / e);
}

TEST(MaterialFrameTest, OrthonormalisesAxisTwoAgainstAxisOne) {
  // Lengths do not matter, and axis_2's component along axis_1 is dropped.
  EXPECT_LT((MaterialFrame({2, 0, 0}, {1, 3, 0}) - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  const Eigen::Matrix3d q = ObliqueFrame();
  EXPECT_LT((q.transpose() * q - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_NEAR(q.determinant(), 1.0, 1e-14);
  EXPECT_LT((q.col(0) - Eigen::Vector3d(1, 2, 0.5).normalized()).norm(), 1e-15);
  // Axis 2 stays in the plane of the two given directions, on axis_2's side.
  EXPECT_NEAR(q.col(1).dot(Eigen::Vector3d(1, 2, 0.5).cross(Eigen::Vector3d(-1, 0.3, 2))), 0,
              1e-14);
  EXPECT_GT(q.col(1).dot(Eigen::Vector3d(-1, 0.3, 2)), 0);
}

TEST(RotateElasticityTest, IdentityFrameChangesNothing) {
  const Matrix6d d = OrthotropicElasticity(Sample());
  const Matrix6d s = OrthotropicCompliance(Sample());
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  EXPECT_EQ(MaxAbs(RotateElasticity(d, identity) - d), 0.0);
  EXPECT_EQ(MaxAbs(RotateCompliance(s, identity) - s), 0.0);
}

TEST(RotateElasticityTest, IsotropicElasticityIsInvariant) {
  const Matrix6d iso = IsotropicElasticity(3000, 0.45);
  EXPECT_LT(MaxAbs(RotateElasticity(iso, ObliqueFrame()) - iso), 1e-12 * MaxAbs(iso));
  const Matrix6d c = IsotropicCompliance(3000, 0.45);
  EXPECT_LT(MaxAbs(RotateCompliance(c, ObliqueFrame()) - c), 1e-12 * MaxAbs(c));
}

TEST(RotateElasticityTest, QuarterTurnAboutZSwapsDirectionsOneAndTwo) {
  // Material 1 along +y, 2 along -x, 3 along z: seen from the global frame
  // the material is the sample with its constants 1 and 2 exchanged.
  const OrthotropicElasticParams p = Sample();
  const Eigen::Matrix3d q = MaterialFrame({0, 1, 0}, {-1, 0, 0});
  ASSERT_LT((q.col(2) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  OrthotropicElasticParams swapped = p;
  swapped.e1_pa = p.e2_pa;
  swapped.e2_pa = p.e1_pa;
  swapped.nu12 = p.nu12 * p.e2_pa / p.e1_pa;  // nu21
  swapped.nu13 = p.nu23;
  swapped.nu23 = p.nu13;
  swapped.g13_pa = p.g23_pa;
  swapped.g23_pa = p.g13_pa;
  const Matrix6d expected = OrthotropicElasticity(swapped);
  EXPECT_LT(MaxAbs(RotateElasticity(OrthotropicElasticity(p), q) - expected),
            1e-12 * MaxAbs(expected));
  EXPECT_LT(MaxAbs(RotateCompliance(OrthotropicCompliance(p), q) - OrthotropicCompliance(swapped)),
            1e-12 / p.e3_pa);
}

// Voigt strain with engineering shears from a symmetric tensor, and back.
Vector6d EngineeringStrain(const Eigen::Matrix3d& eps) {
  Vector6d v = SymmetricToVoigt(eps);
  v.tail<3>() *= 2;
  return v;
}

TEST(RotateElasticityTest, AgreesWithRotatingTheTensors) {
  // sigma_global = Q D(Q^T eps_global Q) Q^T, done with 3 x 3 tensors: the
  // Bond factors for engineering shears must reproduce it.
  const Eigen::Matrix3d q = ObliqueFrame();
  const Matrix6d d = OrthotropicElasticity(Sample());
  Eigen::Matrix3d eps;
  eps << 1e-3, 4e-4, -2e-4, 4e-4, -5e-4, 7e-4, -2e-4, 7e-4, 2e-4;
  const Eigen::Matrix3d eps_material = q.transpose() * eps * q;
  const Eigen::Matrix3d sigma =
      q * VoigtToSymmetric(d * EngineeringStrain(eps_material)) * q.transpose();
  const Vector6d ours = RotateElasticity(d, q) * EngineeringStrain(eps);
  EXPECT_LT((ours - SymmetricToVoigt(sigma)).cwiseAbs().maxCoeff(), 1e-12 * sigma.norm());
  // And back: the rotated compliance returns the strain.
  const Vector6d strain = RotateCompliance(OrthotropicCompliance(Sample()), q) * ours;
  EXPECT_LT((strain - EngineeringStrain(eps)).cwiseAbs().maxCoeff(), 1e-12 * eps.norm());
}

TEST(RotateElasticityTest, RotatedComplianceInvertsRotatedElasticity) {
  const Eigen::Matrix3d q = ObliqueFrame();
  const Matrix6d product = RotateElasticity(OrthotropicElasticity(Sample()), q) *
                           RotateCompliance(OrthotropicCompliance(Sample()), q);
  EXPECT_LT(MaxAbs(product - Matrix6d::Identity()), 1e-12);
  const Matrix6d m = StressRotation(q);
  EXPECT_LT(MaxAbs(m * StressRotation(q.transpose()) - Matrix6d::Identity()), 1e-14);
}

struct BadCase {
  const char* label;
  std::function<void(OrthotropicElasticParams*)> spoil;
  const char* field;
  const char* message_part;
};
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.label; }

class OrthotropicValidateTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(OrthotropicValidateTest, NamesTheField) {
  OrthotropicElasticParams p = Sample();
  GetParam().spoil(&p);
  const Status status = p.Validate("material.orthotropic_elastic");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), GetParam().field);
  EXPECT_NE(status.message().find(GetParam().message_part), std::string::npos) << status.message();
}

INSTANTIATE_TEST_SUITE_P(
    Cases, OrthotropicValidateTest,
    ::testing::Values(BadCase{"zero_e1", [](OrthotropicElasticParams* p) { p->e1_pa = 0; },
                              "material.orthotropic_elastic.e1_pa", "> 0"},
                      BadCase{"negative_e2", [](OrthotropicElasticParams* p) { p->e2_pa = -3000; },
                              "material.orthotropic_elastic.e2_pa", "> 0"},
                      BadCase{"nan_e3", [](OrthotropicElasticParams* p) { p->e3_pa = NAN; },
                              "material.orthotropic_elastic.e3_pa", "finite"},
                      BadCase{"zero_g12", [](OrthotropicElasticParams* p) { p->g12_pa = 0; },
                              "material.orthotropic_elastic.g12_pa", "> 0"},
                      BadCase{"negative_g13", [](OrthotropicElasticParams* p) { p->g13_pa = -1; },
                              "material.orthotropic_elastic.g13_pa", "> 0"},
                      BadCase{"infinite_g23",
                              [](OrthotropicElasticParams* p) { p->g23_pa = INFINITY; },
                              "material.orthotropic_elastic.g23_pa", "finite"},
                      // sqrt(E1 / E2) = 1.414, sqrt(E1 / E3) = 2, sqrt(E2 / E3) = 1.414.
                      BadCase{"nu12_too_large", [](OrthotropicElasticParams* p) { p->nu12 = 1.5; },
                              "material.orthotropic_elastic.nu12", "sqrt(E1 / E2)"},
                      BadCase{"nu13_too_large", [](OrthotropicElasticParams* p) { p->nu13 = 2.0; },
                              "material.orthotropic_elastic.nu13", "sqrt(E1 / E3)"},
                      BadCase{"nu23_too_negative",
                              [](OrthotropicElasticParams* p) { p->nu23 = -1.5; },
                              "material.orthotropic_elastic.nu23", "sqrt(E2 / E3)"},
                      BadCase{"nu23_nan", [](OrthotropicElasticParams* p) { p->nu23 = NAN; },
                              "material.orthotropic_elastic.nu23", "finite"},
                      // Each ratio within its bound, the three together not: equal moduli
                      // and nu = 0.6 give 1 - 3 nu^2 - 2 nu^3 < 0.
                      BadCase{"indefinite",
                              [](OrthotropicElasticParams* p) {
                                p->e1_pa = p->e2_pa = p->e3_pa = 3000;
                                p->nu12 = p->nu13 = p->nu23 = 0.6;
                              },
                              "material.orthotropic_elastic", "indefinite"},
                      BadCase{"zero_axis_1",
                              [](OrthotropicElasticParams* p) {
                                p->axis_1 = {0, 0, 0};
                              },
                              "material.orthotropic_elastic.axis_1", "non-zero"},
                      BadCase{"nan_axis_2",
                              [](OrthotropicElasticParams* p) {
                                p->axis_2 = {0, NAN, 1};
                              },
                              "material.orthotropic_elastic.axis_2", "finite"},
                      BadCase{"parallel_axes",
                              [](OrthotropicElasticParams* p) {
                                p->axis_1 = {1, 1, 0};
                                p->axis_2 = {-2, -2, 0};
                              },
                              "material.orthotropic_elastic.axis_2", "parallel"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.label); });

}  // namespace
}  // namespace pba
