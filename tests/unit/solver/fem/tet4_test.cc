#include "fem/tet4.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "material/linear_elastic.h"

namespace pba {
namespace {

constexpr double kE = 3000.0, kNu = 0.3;
const double kLambda = kE * kNu / ((1 + kNu) * (1 - 2 * kNu));
const double kMu = kE / (2 * (1 + kNu));

Eigen::Matrix<double, 4, 3> UnitTet() {
  Eigen::Matrix<double, 4, 3> x;
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  return x;
}

// Entry (i of node a, j of node b) of the isotropic tet stiffness, by hand:
// K = V (lambda g_a,i g_b,j + mu g_a,j g_b,i + mu delta_ij g_a . g_b), with the
// unit tet's gradients g_0 = (-1,-1,-1), g_1 = e_x, g_2 = e_y, g_3 = e_z, V = 1/6.
TEST(Tet4Test, StiffnessOfUnitTetMatchesHandComputation) {
  const Matrix12d k = Tet4Stiffness(ComputeTet4Geometry(UnitTet()), IsotropicElasticity(kE, kNu));
  const double v = 1.0 / 6.0;
  constexpr double kTol = 1e-12;  // a handful of floating-point operations
  auto entry = [&](int a, int i, int b, int j) { return k(3 * a + i, 3 * b + j); };
  EXPECT_NEAR(entry(1, 0, 1, 0), v * (kLambda + 2 * kMu), kTol * kE);
  EXPECT_NEAR(entry(1, 0, 2, 1), v * kLambda, kTol * kE);
  EXPECT_NEAR(entry(1, 1, 2, 0), v * kMu, kTol * kE);
  EXPECT_NEAR(entry(0, 0, 0, 0), v * (kLambda + 4 * kMu), kTol * kE);
  EXPECT_NEAR(entry(0, 0, 1, 0), -v * (kLambda + 2 * kMu), kTol * kE);
  EXPECT_NEAR(entry(0, 2, 3, 2), -v * (kLambda + 2 * kMu), kTol * kE);
  EXPECT_NEAR(entry(2, 2, 3, 2), 0.0, kTol * kE);
  EXPECT_NEAR(entry(3, 2, 3, 2), v * (kLambda + 2 * kMu), kTol * kE);
}

TEST(Tet4Test, GeometryOfUnitTet) {
  const Tet4Geometry g = ComputeTet4Geometry(UnitTet());
  EXPECT_NEAR(g.volume, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(g.grad(0, 0), -1.0, 1e-15);
  EXPECT_NEAR(g.grad(1, 0), 1.0, 1e-15);
  // Gradients of a partition of unity sum to zero.
  EXPECT_LT(g.grad.colwise().sum().norm(), 1e-14);
}

// A general (skewed) element: symmetric, six rigid modes in the null space,
// the other six eigenvalues positive.
TEST(Tet4Test, StiffnessHasExactlySixRigidModes) {
  Eigen::Matrix<double, 4, 3> x;
  x << 0.1, 0.0, 0.2, 1.3, 0.2, -0.1, 0.2, 0.9, 0.1, 0.3, 0.4, 1.1;
  const Matrix12d k = Tet4Stiffness(ComputeTet4Geometry(x), IsotropicElasticity(kE, kNu));
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
  Eigen::SelfAdjointEigenSolver<Matrix12d> eigen(k);
  const double largest = eigen.eigenvalues().maxCoeff();
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(eigen.eigenvalues()(i)), 1e-10 * largest);
  for (int i = 6; i < 12; ++i) EXPECT_GT(eigen.eigenvalues()(i), 1e-6 * largest);
  // A rotation about z and a translation produce no force.
  Vector12d rotation, translation;
  for (int a = 0; a < 4; ++a) {
    rotation.segment<3>(3 * a) << -x(a, 1), x(a, 0), 0;
    translation.segment<3>(3 * a) << 1, 2, 3;
  }
  EXPECT_LT((k * rotation).norm(), 1e-10 * largest);
  EXPECT_LT((k * translation).norm(), 1e-10 * largest);
}

// A linear displacement field gives its exact constant strain.
TEST(Tet4Test, LinearFieldGivesExactStrain) {
  Eigen::Matrix<double, 4, 3> x;
  x << 0.1, 0.0, 0.2, 1.3, 0.2, -0.1, 0.2, 0.9, 0.1, 0.3, 0.4, 1.1;
  Eigen::Matrix3d grad_u;
  grad_u << 0.01, 0.002, -0.003, 0.004, -0.02, 0.005, 0.001, 0.006, 0.03;
  Vector12d u;
  for (int a = 0; a < 4; ++a) u.segment<3>(3 * a) = grad_u * x.row(a).transpose();
  const Vector6d strain = StrainDisplacement(ComputeTet4Geometry(x)) * u;
  Vector6d expected;
  expected << grad_u(0, 0), grad_u(1, 1), grad_u(2, 2), grad_u(1, 2) + grad_u(2, 1),
      grad_u(0, 2) + grad_u(2, 0), grad_u(0, 1) + grad_u(1, 0);
  EXPECT_LT((strain - expected).norm(), 1e-14);
}

TEST(LinearElasticTest, ComplianceInvertsElasticity) {
  const Matrix6d product = IsotropicElasticity(kE, 0.45) * IsotropicCompliance(kE, 0.45);
  EXPECT_LT((product - Matrix6d::Identity()).norm(), 1e-12);
}

TEST(LinearElasticTest, VonMisesOfUniaxialAndShear) {
  Vector6d s = Vector6d::Zero();
  s(2) = -30;
  EXPECT_NEAR(VonMises(s), 30.0, 1e-12);
  s.setZero();
  s(5) = 10;  // pure shear: sqrt(3) tau
  EXPECT_NEAR(VonMises(s), std::sqrt(3.0) * 10, 1e-12);
}

}  // namespace
}  // namespace pba
