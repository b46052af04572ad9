// The total-Lagrangian 10-node tetrahedron: force = dPi/du and tangent =
// d(force)/du by central differences on a curved element, for neo-Hookean and
// Ogden; a homogeneous deformation gives F everywhere and the material's
// stress (virtual work of P = F S); inverted states are refused.
#include "fem/tet10_finite_strain.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
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

    const double h = 1e-8;  // m, against displacements of ~1e-3 m
    const double force_scale = r.force.cwiseAbs().maxCoeff();
    const double tangent_scale = r.tangent.cwiseAbs().maxCoeff();
    for (int i = 0; i < 30; ++i) {
      Vector30d plus = u, minus = u;
      plus(i) += h;
      minus(i) -= h;
      Tet10FiniteStrainResult rp, rm;
      ASSERT_TRUE(Tet10FiniteStrain(x, plus, *c.material, false, &rp));
      ASSERT_TRUE(Tet10FiniteStrain(x, minus, *c.material, false, &rm));
      EXPECT_NEAR(r.force(i), (rp.energy - rm.energy) / (2 * h), 1e-6 * force_scale)
          << c.name << " unknown " << i;
      const Vector30d column = (rp.force - rm.force) / (2 * h);
      EXPECT_LT((r.tangent.col(i) - column).cwiseAbs().maxCoeff(), 1e-6 * tangent_scale)
          << c.name << " unknown " << i;
    }
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

}  // namespace
}  // namespace pba
