// The total-Lagrangian 10-node tetrahedron: force = dPi/du and tangent =
// d(force)/du by central differences on a curved element, for neo-Hookean and
// Ogden; a homogeneous deformation gives F everywhere and the material's
// stress (virtual work of P = F S); inverted states are refused.
//
// The mean-dilatation element (TET10_MD) the same way, and: on a homogeneous
// deformation it is the plain element; the tangent without the pressure
// stiffness differs from the consistent one by exactly U'(theta) d2v/dx2;
// at rest it is symmetric positive semi-definite, its zero modes the rigid
// ones and (one element alone) three special conformal fields, and under
// hydrostatic compression the consistent tangent is indefinite where the
// approximation stays semi-definite.
#include "fem/tet10_finite_strain.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "fem/tet4_finite_strain.h"
#include "material/ogden.h"
#include "material/polynomial.h"

namespace pba {
namespace {

// A curved element of ~10 mm edges [m]: mid-edge nodes moved off their
// edges by 5-10 % of the edge length.
Tet10Nodes CurvedElement() {
  Eigen::Matrix<double, 4, 3> corners;
  corners << 0.1, 0.0, 0.2, 1.3, 0.2, -0.1, 0.2, 0.9, 0.1, 0.3, 0.4, 1.1;
  Eigen::Matrix<double, 6, 3> offset;
  offset << 0.06, -0.05, 0.04, -0.04, 0.07, 0.03, 0.05, 0.03, -0.06, -0.03, 0.05, 0.06, 0.07, -0.04,
      -0.05, 0.04, 0.06, 0.05;
  Tet10Nodes x;
  x.topRows<4>() = corners;
  for (int k = 0; k < 6; ++k) {
    x.row(4 + k) =
        0.5 * (corners.row(kTet10Edges[k][0]) + corners.row(kTet10Edges[k][1])) + offset.row(k);
  }
  return 0.01 * x;
}

struct MaterialCase {
  const char* name;
  std::shared_ptr<HyperelasticMaterial> material;
};

std::vector<MaterialCase> Materials() {
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / 842e2, 0, 0};  // K / mu = 100
  return {{"neo_hookean", std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e4))},
          {"ogden_brain", std::make_shared<OgdenMaterial>(brain)}};
}

// A random displacement of ~`amplitude` x the element size [m].
Vector30d RandomDisplacement(double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c(-1, 1);
  Vector30d u;
  for (int i = 0; i < 30; ++i) u(i) = amplitude * 0.01 * c(rng);
  return u;
}

// The element kernels, by their Tet10Geometry overloads.
using Kernel = bool (*)(const Tet10Geometry&, const Vector30d&, const HyperelasticMaterial&, bool,
                        Tet10FiniteStrainResult*, bool);

// Central differences at `u`: the force `r.force` is dPi/du and the tangent
// `r.tangent` d(force)/du, column by column.
void ExpectDerivatives(Kernel kernel, const Tet10Geometry& g, const Vector30d& u,
                       const HyperelasticMaterial& material, const Tet10FiniteStrainResult& r,
                       const char* name) {
  const double h = 1e-8;  // m, against displacements of ~1e-3 m
  const double force_scale = r.force.cwiseAbs().maxCoeff();
  const double tangent_scale = r.tangent.cwiseAbs().maxCoeff();
  for (int i = 0; i < 30; ++i) {
    Vector30d plus = u, minus = u;
    plus(i) += h;
    minus(i) -= h;
    Tet10FiniteStrainResult rp, rm;
    ASSERT_TRUE(kernel(g, plus, material, false, &rp, false));
    ASSERT_TRUE(kernel(g, minus, material, false, &rm, false));
    EXPECT_NEAR(r.force(i), (rp.energy - rm.energy) / (2 * h), 1e-6 * force_scale)
        << name << " unknown " << i;
    const Vector30d column = (rp.force - rm.force) / (2 * h);
    EXPECT_LT((r.tangent.col(i) - column).cwiseAbs().maxCoeff(), 1e-6 * tangent_scale)
        << name << " unknown " << i;
  }
}

TEST(Tet10FiniteStrain, ForceIsTheEnergyDerivativeAndTangentTheForceDerivative) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  ASSERT_GT(g.min_jacobian, 0);
  for (const MaterialCase& c : Materials()) {
    const Vector30d u = RandomDisplacement(0.1, 5);
    Tet10FiniteStrainResult r;
    ASSERT_TRUE(Tet10FiniteStrain(x, u, *c.material, true, &r)) << c.name;
    double j_min = 1e300, j_max = 0;
    for (const Eigen::Matrix3d& f : r.f) {
      j_min = std::min(j_min, f.determinant());
      j_max = std::max(j_max, f.determinant());
    }
    ASSERT_GT(j_min, 0.6) << c.name;
    ASSERT_GT(j_max - j_min, 0.02) << c.name << ": F should vary over the element";
    EXPECT_LT((r.tangent - r.tangent.transpose()).cwiseAbs().maxCoeff(),
              1e-12 * r.tangent.cwiseAbs().maxCoeff())
        << c.name;

    ExpectDerivatives(Tet10FiniteStrain, g, u, *c.material, r, c.name);
  }
}

TEST(Tet10FiniteStrain, HomogeneousDeformationReproducesTheMaterialStress) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  const double volume = g.volume[0] + g.volume[1] + g.volume[2] + g.volume[3];
  Eigen::Matrix3d f;
  f << 1.1, 0.05, -0.02, 0.03, 0.92, 0.04, -0.01, 0.02, 1.05;
  Vector30d u;
  for (int a = 0; a < 10; ++a) {
    u.segment<3>(3 * a) = (f - Eigen::Matrix3d::Identity()) * x.row(a).transpose();
  }
  for (const MaterialCase& c : Materials()) {
    Tet10FiniteStrainResult r;
    ASSERT_TRUE(Tet10FiniteStrain(g, u, *c.material, true, &r));
    for (const Eigen::Matrix3d& fq : r.f) EXPECT_LT((fq - f).norm(), 1e-13) << c.name;
    EXPECT_NEAR(r.energy, volume * c.material->Energy(f), 1e-12 * r.energy) << c.name;
    // Virtual work: for a linear virtual displacement du = A X the internal
    // work is du . f = V P : A with P = F S, the first Piola-Kirchhoff stress.
    const Eigen::Matrix3d p = f * VoigtToSymmetric(c.material->Stress(f));
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> coefficient(-1, 1);
    for (int trial = 0; trial < 3; ++trial) {
      Eigen::Matrix3d a;
      for (int k = 0; k < 9; ++k) a(k) = coefficient(rng);
      Vector30d du;
      for (int n = 0; n < 10; ++n) du.segment<3>(3 * n) = a * x.row(n).transpose();
      const double expected = volume * (p.array() * a.array()).sum();
      EXPECT_NEAR(du.dot(r.force), expected, 1e-11 * p.norm() * volume) << c.name;
    }
  }
}

TEST(Tet10FiniteStrain, StraightElementUnderHomogeneousDeformationIsTheLinearElement) {
  Tet10Nodes x = CurvedElement();
  for (int k = 0; k < 6; ++k) {
    x.row(4 + k) = 0.5 * (x.row(kTet10Edges[k][0]) + x.row(kTet10Edges[k][1]));
  }
  Eigen::Matrix3d f;
  f << 0.9, 0.1, 0.0, -0.05, 1.08, 0.02, 0.03, 0.0, 1.12;
  Vector30d u;
  for (int a = 0; a < 10; ++a) {
    u.segment<3>(3 * a) = (f - Eigen::Matrix3d::Identity()) * x.row(a).transpose();
  }
  const Tet4Geometry linear = ComputeTet4Geometry(x.topRows<4>());
  for (const MaterialCase& c : Materials()) {
    Tet10FiniteStrainResult quadratic;
    Tet4FiniteStrainResult reference;
    ASSERT_TRUE(Tet10FiniteStrain(x, u, *c.material, false, &quadratic));
    ASSERT_TRUE(Tet4FiniteStrain(linear, u.head<12>(), *c.material, false, &reference));
    EXPECT_NEAR(quadratic.energy, reference.energy, 1e-12 * reference.energy) << c.name;
    // Resultant force on the element is zero (self-equilibrated), as for TET4.
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int a = 0; a < 10; ++a) sum += quadratic.force.segment<3>(3 * a);
    EXPECT_LT(sum.norm(), 1e-12 * quadratic.force.norm()) << c.name;
  }
}

TEST(Tet10FiniteStrain, RefusesInvertedStates) {
  const Tet10Nodes x = CurvedElement();
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e4));
  Tet10FiniteStrainResult r;
  // A homogeneous reflection (det F = -0.5).
  Vector30d u;
  const Eigen::Vector3d stretch(1, 1, -0.5);
  for (int a = 0; a < 10; ++a) {
    u.segment<3>(3 * a) = (stretch.array() - 1).matrix().cwiseProduct(x.row(a).transpose());
  }
  EXPECT_FALSE(Tet10FiniteStrain(x, u, material, true, &r));
  // Non-finite displacement.
  u.setZero();
  u(4) = std::nan("");
  EXPECT_FALSE(Tet10FiniteStrain(x, u, material, false, &r));
  // A mirrored (inverted) reference element.
  Tet10Nodes mirrored = x;
  mirrored.col(0) *= -1;
  EXPECT_FALSE(Tet10FiniteStrain(mirrored, Vector30d::Zero(), material, false, &r));
  // The undeformed element is fine, with zero force and energy.
  ASSERT_TRUE(Tet10FiniteStrain(x, Vector30d::Zero(), material, true, &r));
  EXPECT_LT(r.force.norm(), 1e-12);
  EXPECT_NEAR(r.energy, 0, 1e-15);
}

// u = (F - I) X at every node.
Vector30d Homogeneous(const Tet10Nodes& x, const Eigen::Matrix3d& f) {
  Vector30d u;
  for (int a = 0; a < 10; ++a) {
    u.segment<3>(3 * a) = (f - Eigen::Matrix3d::Identity()) * x.row(a).transpose();
  }
  return u;
}

TEST(Tet10FiniteStrainMeanDilatation, ForceIsTheEnergyDerivativeAndTangentTheForceDerivative) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  for (const MaterialCase& c : Materials()) {
    const Vector30d u = RandomDisplacement(0.1, 5);
    Tet10FiniteStrainResult r;
    ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, *c.material, true, &r)) << c.name;
    ASSERT_GT(std::abs(r.theta - 1), 1e-3) << c.name << ": the pressure term should be active";
    Tet10FiniteStrainResult plain;
    ASSERT_TRUE(Tet10FiniteStrain(g, u, *c.material, false, &plain)) << c.name;
    EXPECT_GT(std::abs(r.energy - plain.energy), 1e-3 * plain.energy)
        << c.name << ": F varies, so the two elements should differ";
    EXPECT_LT((r.tangent - r.tangent.transpose()).cwiseAbs().maxCoeff(),
              1e-12 * r.tangent.cwiseAbs().maxCoeff())
        << c.name;
    ExpectDerivatives(Tet10FiniteStrainMeanDilatation, g, u, *c.material, r, c.name);
  }
}

// Without the pressure stiffness the tangent lacks exactly U'(theta) d2v/dx2.
// dv/dx comes from two materials that differ only in K: the force is
// f_iso + U'(theta) dv/dx, so dv/dx = (f_1 - f_2) / (U'_1 - U'_2), and
// d2v/dx2 by central differences of that.
TEST(Tet10FiniteStrainMeanDilatation, DroppedTermIsThePressureTimesTheVolumeHessian) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  const PolynomialMaterial soft(NeoHookeanCoefficients(1000, 1e4));
  const PolynomialMaterial stiff(NeoHookeanCoefficients(1000, 3e4));
  const auto volume_gradient = [&](const Vector30d& u) -> Vector30d {
    Tet10FiniteStrainResult a, b;
    EXPECT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, soft, false, &a));
    EXPECT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, stiff, false, &b));
    return (b.force - a.force) / (stiff.Volumetric(b.theta).first - soft.Volumetric(a.theta).first);
  };
  const Vector30d u = RandomDisplacement(0.1, 7);
  Tet10FiniteStrainResult consistent, definite;
  ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, soft, true, &consistent, false));
  ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, soft, true, &definite, true));
  ASSERT_GT(std::abs(consistent.theta - 1), 1e-3);
  EXPECT_EQ((consistent.force - definite.force).norm(), 0);
  EXPECT_EQ(consistent.energy, definite.energy);
  const double h = 1e-8;
  Matrix30d hessian;
  for (int i = 0; i < 30; ++i) {
    Vector30d plus = u, minus = u;
    plus(i) += h;
    minus(i) -= h;
    hessian.col(i) = (volume_gradient(plus) - volume_gradient(minus)) / (2 * h);
  }
  const Matrix30d dropped = consistent.tangent - definite.tangent;
  const Matrix30d expected = soft.Volumetric(consistent.theta).first * hessian;
  ASSERT_GT(expected.cwiseAbs().maxCoeff(), 1e-3 * consistent.tangent.cwiseAbs().maxCoeff());
  EXPECT_LT((dropped - expected).cwiseAbs().maxCoeff(), 1e-5 * expected.cwiseAbs().maxCoeff());
}

TEST(Tet10FiniteStrainMeanDilatation, HomogeneousDeformationIsThePlainElement) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  Eigen::Matrix3d f;
  f << 1.1, 0.05, -0.02, 0.03, 0.92, 0.04, -0.01, 0.02, 1.05;
  const Vector30d u = Homogeneous(x, f);
  for (const MaterialCase& c : Materials()) {
    Tet10FiniteStrainResult plain, bar;
    ASSERT_TRUE(Tet10FiniteStrain(g, u, *c.material, false, &plain));
    ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, *c.material, false, &bar));
    EXPECT_NEAR(bar.theta, f.determinant(), 1e-14) << c.name;
    EXPECT_NEAR(bar.energy, plain.energy, 1e-12 * plain.energy) << c.name;
    EXPECT_LT((bar.force - plain.force).cwiseAbs().maxCoeff(),
              1e-12 * plain.force.cwiseAbs().maxCoeff())
        << c.name;
  }
}

// At rest: symmetric and positive semi-definite. One element alone has nine
// zero modes, not six: the isochoric energy at four points constrains at
// most 5 x 4 = 20 of its 30 unknowns, the mean dilatation one more. On a
// straight element the three beyond the rigid modes are the special
// conformal fields u = 2 (b . y) y - |y|^2 b, y = X - centroid (zero
// deviatoric strain, 2 (b . y) I, and zero mean dilatation); neighbours
// constrain them, and an assembled mesh has only the six rigid modes
// (Tet10Model.MeanDilatationTangentAtRestHasOnlyTheRigidModes). Nearly
// incompressible (K / mu = 1e4), the plain element has four eigenvalues of
// order K (a volume constraint per point: what makes it lock), the
// mean-dilatation element one.
TEST(Tet10FiniteStrainMeanDilatation, TangentAtRest) {
  Tet10Nodes x = CurvedElement();
  for (int k = 0; k < 6; ++k) {
    x.row(4 + k) = 0.5 * (x.row(kTet10Edges[k][0]) + x.row(kTet10Edges[k][1]));
  }
  const Tet10Geometry g = ComputeTet10Geometry(x);
  const double mu = 1000;
  const PolynomialMaterial material(NeoHookeanCoefficients(mu, 1e4 * mu));
  Tet10FiniteStrainResult bar, plain;
  ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, Vector30d::Zero(), material, true, &bar));
  ASSERT_TRUE(Tet10FiniteStrain(g, Vector30d::Zero(), material, true, &plain));
  EXPECT_EQ(bar.theta, 1);
  EXPECT_LT(bar.force.norm(), 1e-12);
  EXPECT_EQ(bar.energy, 0);
  EXPECT_LT((bar.tangent - bar.tangent.transpose()).cwiseAbs().maxCoeff(),
            1e-14 * bar.tangent.cwiseAbs().maxCoeff());
  Eigen::SelfAdjointEigenSolver<Matrix30d> md(bar.tangent), full(plain.tangent);
  const double largest = md.eigenvalues().maxCoeff();
  std::printf(
      "at rest, K / mu = 1e4: TET10_MD eigenvalues 9, 28, 29 / largest %.3g %.3g %.3g; "
      "TET10 eigenvalues 6, 25, 26 / largest %.3g %.3g %.3g\n",
      md.eigenvalues()(9) / largest, md.eigenvalues()(28) / largest, md.eigenvalues()(29) / largest,
      full.eigenvalues()(6) / largest, full.eigenvalues()(25) / largest,
      full.eigenvalues()(26) / largest);
  for (int i = 0; i < 9; ++i) EXPECT_LT(std::abs(md.eigenvalues()(i)), 1e-12 * largest) << i;
  EXPECT_GT(md.eigenvalues()(9), 1e-7 * largest);
  EXPECT_GT(full.eigenvalues()(6), 1e-7 * largest);
  // Eigenvalues of order K: the element's volume constraints.
  const auto stiff = [](const Eigen::VectorXd& lambda, double scale) {
    return (lambda.array() > 1e-2 * scale).count();
  };
  EXPECT_EQ(stiff(md.eigenvalues(), largest), 1);
  EXPECT_EQ(stiff(full.eigenvalues(), full.eigenvalues().maxCoeff()), 4);
  // The special conformal fields are zero modes of TET10_MD and not of TET10.
  const Eigen::Vector3d centroid = x.topRows<4>().colwise().mean().transpose();
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d b = Eigen::Vector3d::Unit(axis);
    Vector30d u;
    for (int a = 0; a < 10; ++a) {
      const Eigen::Vector3d y = x.row(a).transpose() - centroid;
      u.segment<3>(3 * a) = 2 * b.dot(y) * y - y.squaredNorm() * b;
    }
    EXPECT_LT((bar.tangent * u).norm(), 1e-10 * largest * u.norm()) << axis;
    EXPECT_GT((plain.tangent * u).norm(), 1e-4 * largest * u.norm()) << axis;
  }
}

// As Hex8FiniteStrain.DefiniteApproximation: hydrostatic compression by 10 %
// in each direction at K / mu = 1e4; the approximation keeps the nine zero
// modes of TangentAtRest.
TEST(Tet10FiniteStrainMeanDilatation, DefiniteApproximation) {
  const Tet10Nodes x = CurvedElement();
  const Tet10Geometry g = ComputeTet10Geometry(x);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  Tet10FiniteStrainResult consistent, definite;
  const Vector30d u = Homogeneous(x, 0.9 * Eigen::Matrix3d::Identity());
  ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, material, true, &consistent, false));
  ASSERT_TRUE(Tet10FiniteStrainMeanDilatation(g, u, material, true, &definite, true));
  EXPECT_NEAR(consistent.theta, 0.729, 1e-14);
  Eigen::SelfAdjointEigenSolver<Matrix30d> full(consistent.tangent), approx(definite.tangent);
  const double largest = approx.eigenvalues().maxCoeff();
  EXPECT_LT(full.eigenvalues()(0), -1e-3 * largest);  // indefinite
  for (int i = 0; i < 9; ++i) {
    EXPECT_LT(std::abs(approx.eigenvalues()(i)), 1e-12 * largest) << i;
  }
  for (int i = 9; i < 30; ++i) EXPECT_GT(approx.eigenvalues()(i), 1e-7 * largest) << i;
}

TEST(Tet10FiniteStrainMeanDilatation, RefusesInvertedStates) {
  const Tet10Nodes x = CurvedElement();
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e4));
  Tet10FiniteStrainResult r;
  EXPECT_FALSE(Tet10FiniteStrainMeanDilatation(
      x, Homogeneous(x, Eigen::Vector3d(1, 1, -0.5).asDiagonal()), material, true, &r));
  Vector30d u = Vector30d::Zero();
  u(4) = std::nan("");
  EXPECT_FALSE(Tet10FiniteStrainMeanDilatation(x, u, material, false, &r));
  Tet10Nodes mirrored = x;
  mirrored.col(0) *= -1;
  EXPECT_FALSE(Tet10FiniteStrainMeanDilatation(mirrored, Vector30d::Zero(), material, false, &r));
}

}  // namespace
}  // namespace pba
