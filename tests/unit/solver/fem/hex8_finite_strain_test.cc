// The total-Lagrangian hexahedra, mean-dilatation and fully integrated:
// force = dPi/du and tangent = d(force)/du by central differences on a
// distorted brick, for neo-Hookean and Ogden; a homogeneous deformation gives
// the material's energy and stress (and the same force from both); at u = 0
// the tangents are the small-strain B-bar and full stiffnesses; the definite
// approximation (no pressure initial-stress term) equals the consistent
// tangent at rest and is positive semi-definite with six zero modes where
// the consistent tangent is indefinite; inverted states are refused.
#include "fem/hex8_finite_strain.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "material/linear_elastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"

namespace pba {
namespace {

// A 10 mm brick with every node moved by 6-15 % of the edge (tapered and
// warped) [m].
Hex8Nodes DistortedElement() {
  Hex8Nodes x;
  for (int a = 0; a < 8; ++a) {
    for (int c = 0; c < 3; ++c) x(a, c) = (kHex8NodeNatural[a][c] + 1) / 2;
  }
  Eigen::Matrix<double, 8, 3> offset;
  offset << 0.08, -0.05, 0.06, -0.12, 0.07, -0.04, 0.1, 0.15, 0.05, -0.06, -0.08, 0.09, 0.05, 0.1,
      -0.07, 0.12, -0.06, 0.1, -0.09, 0.08, -0.1, 0.07, -0.11, 0.06;
  return 0.01 * (x + offset);
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

// The two element kernels, by their Hex8Geometry overloads.
using Kernel = bool (*)(const Hex8Geometry&, const Vector24d&, const HyperelasticMaterial&, bool,
                        Hex8FiniteStrainResult*, bool);

struct KernelCase {
  const char* name;
  Kernel kernel;
};

std::vector<KernelCase> Kernels() {
  return {{"mean_dilatation", &Hex8FiniteStrain}, {"full", &Hex8FiniteStrainFull}};
}

// A random displacement of ~`amplitude` x the element size [m].
Vector24d RandomDisplacement(double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c(-1, 1);
  Vector24d u;
  for (int i = 0; i < 24; ++i) u(i) = amplitude * 0.01 * c(rng);
  return u;
}

// u = (F - I) X at every node.
Vector24d Homogeneous(const Hex8Nodes& x, const Eigen::Matrix3d& f) {
  Vector24d u;
  for (int a = 0; a < 8; ++a) {
    u.segment<3>(3 * a) = (f - Eigen::Matrix3d::Identity()) * x.row(a).transpose();
  }
  return u;
}

TEST(Hex8FiniteStrain, ForceIsTheEnergyDerivativeAndTangentTheForceDerivative) {
  const Hex8Nodes x = DistortedElement();
  const Hex8Geometry g = ComputeHex8Geometry(x);
  ASSERT_GT(g.min_jacobian, 0);
  for (const KernelCase& k : Kernels()) {
    for (const MaterialCase& c : Materials()) {
      const Vector24d u = RandomDisplacement(0.1, 5);
      Hex8FiniteStrainResult r;
      ASSERT_TRUE(k.kernel(g, u, *c.material, true, &r, false)) << k.name << " " << c.name;
      double j_min = 1e300, j_max = 0;
      for (const Eigen::Matrix3d& f : r.f) {
        j_min = std::min(j_min, f.determinant());
        j_max = std::max(j_max, f.determinant());
      }
      ASSERT_GT(j_min, 0.6) << c.name;
      ASSERT_GT(j_max - j_min, 0.05) << c.name << ": F should vary over the element";
      ASSERT_GT(std::abs(r.theta - 1), 1e-3) << c.name << ": the pressure term should be active";
      EXPECT_LT((r.tangent - r.tangent.transpose()).cwiseAbs().maxCoeff(),
                1e-12 * r.tangent.cwiseAbs().maxCoeff())
          << k.name << " " << c.name;

      const double h = 1e-8;  // m, against displacements of ~1e-3 m
      const double force_scale = r.force.cwiseAbs().maxCoeff();
      const double tangent_scale = r.tangent.cwiseAbs().maxCoeff();
      for (int i = 0; i < 24; ++i) {
        Vector24d plus = u, minus = u;
        plus(i) += h;
        minus(i) -= h;
        Hex8FiniteStrainResult rp, rm;
        ASSERT_TRUE(k.kernel(g, plus, *c.material, false, &rp, false));
        ASSERT_TRUE(k.kernel(g, minus, *c.material, false, &rm, false));
        EXPECT_NEAR(r.force(i), (rp.energy - rm.energy) / (2 * h), 1e-6 * force_scale)
            << k.name << " " << c.name << " unknown " << i;
        const Vector24d column = (rp.force - rm.force) / (2 * h);
        EXPECT_LT((r.tangent.col(i) - column).cwiseAbs().maxCoeff(), 1e-6 * tangent_scale)
            << k.name << " " << c.name << " unknown " << i;
      }
    }
  }
}

TEST(Hex8FiniteStrain, HomogeneousDeformationReproducesTheMaterial) {
  const Hex8Nodes x = DistortedElement();
  const Hex8Geometry g = ComputeHex8Geometry(x);
  const double volume = Hex8Volume(x);
  Eigen::Matrix3d f;
  f << 1.1, 0.05, -0.02, 0.03, 0.92, 0.04, -0.01, 0.02, 1.05;
  const Vector24d u = Homogeneous(x, f);
  for (const MaterialCase& c : Materials()) {
    Hex8FiniteStrainResult bar;
    ASSERT_TRUE(Hex8FiniteStrain(g, u, *c.material, false, &bar));
    for (const KernelCase& k : Kernels()) {
      Hex8FiniteStrainResult r;
      ASSERT_TRUE(k.kernel(g, u, *c.material, true, &r, false));
      for (const Eigen::Matrix3d& fq : r.f) EXPECT_LT((fq - f).norm(), 1e-13) << c.name;
      EXPECT_NEAR(r.theta, f.determinant(), 1e-14) << k.name << " " << c.name;
      EXPECT_NEAR(r.energy, volume * c.material->Energy(f), 1e-12 * r.energy)
          << k.name << " " << c.name;
      // Virtual work: for a linear virtual displacement du = A X the internal
      // work is du . f = V P : A with P = F S, the first Piola-Kirchhoff stress.
      const Eigen::Matrix3d p = f * VoigtToSymmetric(c.material->Stress(f));
      std::mt19937 rng(9);
      std::uniform_real_distribution<double> coefficient(-1, 1);
      for (int trial = 0; trial < 3; ++trial) {
        Eigen::Matrix3d a;
        for (int n = 0; n < 9; ++n) a(n) = coefficient(rng);
        Vector24d du;
        for (int n = 0; n < 8; ++n) du.segment<3>(3 * n) = a * x.row(n).transpose();
        const double expected = volume * (p.array() * a.array()).sum();
        EXPECT_NEAR(du.dot(r.force), expected, 1e-11 * p.norm() * volume)
            << k.name << " " << c.name;
      }
      // Self-equilibrated: no resultant force.
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int a = 0; a < 8; ++a) sum += r.force.segment<3>(3 * a);
      EXPECT_LT(sum.norm(), 1e-12 * r.force.norm()) << k.name << " " << c.name;
      // The same nodal forces from both elements, not just the same work on
      // linear fields.
      EXPECT_LT((r.force - bar.force).cwiseAbs().maxCoeff(),
                1e-12 * bar.force.cwiseAbs().maxCoeff())
          << k.name << " " << c.name;
    }
  }
}

// Linearised at u = 0 the mean-dilatation element is Hughes's B-bar brick:
// the isochoric tangent is the deviatoric part of the initial elasticity and
// the volumetric term K V mean(div) mean(div)^T. The fully integrated one is
// the plain small-strain brick.
TEST(Hex8FiniteStrain, TangentAtRestIsTheSmallStrainStiffness) {
  const Hex8Nodes x = DistortedElement();
  const double mu = 1000, k = 1e5;
  const PolynomialMaterial material(NeoHookeanCoefficients(mu, k));
  const double e = 9 * k * mu / (3 * k + mu), nu = (3 * k - 2 * mu) / (2 * (3 * k + mu));
  const Matrix6d d = IsotropicElasticity(e, nu);
  for (const KernelCase& c : Kernels()) {
    const bool full = c.kernel == Kernel(&Hex8FiniteStrainFull);
    Hex8FiniteStrainResult r;
    ASSERT_TRUE(c.kernel(ComputeHex8Geometry(x), Vector24d::Zero(), material, true, &r, false));
    const Matrix24d small = full ? Hex8StiffnessFull(x, d) : Hex8Stiffness(x, d);
    EXPECT_LT((r.tangent - small).cwiseAbs().maxCoeff(), 1e-10 * small.cwiseAbs().maxCoeff())
        << c.name;
    EXPECT_LT(r.force.norm(), 1e-12) << c.name;
    EXPECT_EQ(r.energy, 0) << c.name;
    EXPECT_EQ(r.theta, 1) << c.name;
  }
  // And the two differ: the full one carries K at every point.
  EXPECT_GT((Hex8StiffnessFull(x, d) - Hex8Stiffness(x, d)).cwiseAbs().maxCoeff(),
            1e-2 * Hex8Stiffness(x, d).cwiseAbs().maxCoeff());
}

TEST(Hex8FiniteStrain, DefiniteApproximation) {
  const Hex8Nodes x = DistortedElement();
  const Hex8Geometry g = ComputeHex8Geometry(x);
  const double mu = 1000;
  const PolynomialMaterial material(NeoHookeanCoefficients(mu, 1e4 * mu));  // K / mu = 1e4
  for (const KernelCase& c : Kernels()) {
    // At rest the pressure U'(1) is zero and the two tangents agree (up to
    // rounding: the full element's definite tangent is assembled from the
    // isochoric and volumetric parts, its consistent one from Tangent()).
    Hex8FiniteStrainResult consistent, definite;
    ASSERT_TRUE(c.kernel(g, Vector24d::Zero(), material, true, &consistent, false));
    ASSERT_TRUE(c.kernel(g, Vector24d::Zero(), material, true, &definite, true));
    EXPECT_LE((consistent.tangent - definite.tangent).cwiseAbs().maxCoeff(),
              1e-14 * consistent.tangent.cwiseAbs().maxCoeff())
        << c.name;

    // Compressed by 10 % in each direction (theta = 0.729: pressure
    // -0.271 K, 2710 mu). Hydrostatic, because there the isochoric stress
    // vanishes and rotations are exact zero modes (K W x = W f_iso for an
    // objective energy, rotation W, the dropped term contributing
    // -U' W dv/dx); under shear they would carry O(mu) energy.
    const Vector24d u = Homogeneous(x, 0.9 * Eigen::Matrix3d::Identity());
    ASSERT_TRUE(c.kernel(g, u, material, true, &consistent, false));
    ASSERT_TRUE(c.kernel(g, u, material, true, &definite, true));
    EXPECT_NEAR(consistent.theta, 0.729, 1e-14) << c.name;
    EXPECT_EQ((consistent.force - definite.force).norm(), 0) << c.name;
    EXPECT_EQ(consistent.energy, definite.energy) << c.name;

    Eigen::SelfAdjointEigenSolver<Matrix24d> full(consistent.tangent);
    Eigen::SelfAdjointEigenSolver<Matrix24d> approx(definite.tangent);
    const double largest = approx.eigenvalues().maxCoeff();
    std::printf("%s eigenvalues / largest: consistent min %.3g; definite %.3g .. %.3g, then %.3g\n",
                c.name, full.eigenvalues()(0) / largest, approx.eigenvalues()(0) / largest,
                approx.eigenvalues()(5) / largest, approx.eigenvalues()(6) / largest);
    EXPECT_LT(full.eigenvalues()(0), -1e-3 * largest) << c.name;  // indefinite
    for (int i = 0; i < 6; ++i) {
      EXPECT_LT(std::abs(approx.eigenvalues()(i)), 1e-12 * largest) << c.name << " " << i;
    }
    // The other 18 are positive; the smallest are shear modes, mu against
    // K for the largest.
    for (int i = 6; i < 24; ++i) {
      EXPECT_GT(approx.eigenvalues()(i), 1e-7 * largest) << c.name << " " << i;
    }
  }
}

TEST(Hex8FiniteStrain, RefusesInvertedStates) {
  const Hex8Nodes x = DistortedElement();
  const Hex8Geometry g = ComputeHex8Geometry(x);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e4));
  Hex8Nodes mirrored = x;
  mirrored.col(0) *= -1;
  const Hex8Geometry mirrored_geometry = ComputeHex8Geometry(mirrored);
  for (const KernelCase& c : Kernels()) {
    Hex8FiniteStrainResult r;
    // A homogeneous reflection (det F = -0.5).
    Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();
    reflection(2, 2) = -0.5;
    EXPECT_FALSE(c.kernel(g, Homogeneous(x, reflection), material, true, &r, false)) << c.name;
    // One node pushed through the element: det F <= 0 at some points only.
    Vector24d u = Vector24d::Zero();
    u.segment<3>(18) = -0.012 * Eigen::Vector3d::Ones();  // node 6 past node 0
    EXPECT_FALSE(c.kernel(g, u, material, true, &r, false)) << c.name;
    // Non-finite displacement.
    u.setZero();
    u(4) = std::nan("");
    EXPECT_FALSE(c.kernel(g, u, material, false, &r, false)) << c.name;
    // A mirrored (inverted) reference element.
    EXPECT_FALSE(c.kernel(mirrored_geometry, Vector24d::Zero(), material, false, &r, false))
        << c.name;
    // The undeformed element is fine.
    ASSERT_TRUE(c.kernel(g, Vector24d::Zero(), material, true, &r, false)) << c.name;
    EXPECT_LT(r.force.norm(), 1e-12) << c.name;
    EXPECT_NEAR(r.energy, 0, 1e-15) << c.name;
  }
  // The node-coordinate overloads say the same.
  Hex8FiniteStrainResult r;
  EXPECT_FALSE(Hex8FiniteStrain(mirrored, Vector24d::Zero(), material, false, &r));
  EXPECT_FALSE(Hex8FiniteStrainFull(mirrored, Vector24d::Zero(), material, false, &r));
  EXPECT_TRUE(Hex8FiniteStrainFull(x, Vector24d::Zero(), material, false, &r));
}

}  // namespace
}  // namespace pba
