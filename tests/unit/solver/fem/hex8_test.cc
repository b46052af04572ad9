// The 8-node hexahedron's kernels: shape functions (Kronecker property,
// partition of unity, derivatives), the exactness of the 2 x 2 x 2 rule,
// the patch test on a distorted brick (B-bar and fully integrated), the
// stiffnesses' null spaces, the two elements agreeing on a uniform strain and
// B-bar's strain being the fully integrated one with its volumetric part
// averaged, B-bar against full integration in bending for a nearly
// incompressible material, volume and Jacobian ratio.
#include "fem/hex8.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "material/linear_elastic.h"

namespace pba {
namespace {

Eigen::Vector3d NodeNatural(int a) {
  return Eigen::Vector3d(kHex8NodeNatural[a][0], kHex8NodeNatural[a][1], kHex8NodeNatural[a][2]);
}

// Random points inside the cube [-1, 1]^3.
std::vector<Eigen::Vector3d> InteriorPoints(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> c(-1, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) points.emplace_back(c(rng), c(rng), c(rng));
  return points;
}

// A rectangular brick 1.0 x 1.2 x 0.9 [m], corner at (0.1, -0.2, 0.3).
Hex8Nodes Brick() {
  Hex8Nodes x;
  for (int a = 0; a < 8; ++a) {
    x.row(a) = ((NodeNatural(a).array() + 1) / 2 * Eigen::Array3d(1.0, 1.2, 0.9)).matrix();
    x.row(a) += Eigen::RowVector3d(0.1, -0.2, 0.3);
  }
  return x;
}

// The same with every node moved by 6-15 % of the edge: tapered, warped
// (non-planar faces), det J positive but far from constant.
Hex8Nodes Distorted() {
  Eigen::Matrix<double, 8, 3> offset;
  offset << 0.08, -0.05, 0.06, -0.12, 0.07, -0.04, 0.1, 0.15, 0.05, -0.06, -0.08, 0.09, 0.05, 0.1,
      -0.07, 0.12, -0.06, 0.1, -0.09, 0.08, -0.1, 0.07, -0.11, 0.06;
  return Brick() + offset;
}

constexpr double kE = 3000.0, kNu = 0.3;

TEST(Hex8ShapeFunctions, KroneckerPropertyAtTheNodes) {
  for (int a = 0; a < 8; ++a) {
    const Hex8Vector n = Hex8ShapeFunctions(NodeNatural(a));
    for (int b = 0; b < 8; ++b) EXPECT_EQ(n(b), a == b ? 1.0 : 0.0) << a << " " << b;
  }
}

TEST(Hex8ShapeFunctions, PartitionOfUnityAndGradientsSumToZero) {
  const Hex8Nodes x = Distorted();
  for (const Eigen::Vector3d& xi : InteriorPoints(20, 1)) {
    EXPECT_NEAR(Hex8ShapeFunctions(xi).sum(), 1.0, 1e-15);
    EXPECT_LT(Hex8NaturalGradients(xi).colwise().sum().norm(), 1e-15);
    Hex8Nodes grad;
    ASSERT_GT(Hex8Gradients(x, xi, &grad), 0);
    EXPECT_LT(grad.colwise().sum().norm(), 1e-13);
    // Isoparametric: the coordinates themselves are reproduced, so
    // sum_a X_a (x) grad N_a = I.
    EXPECT_LT((x.transpose() * grad - Eigen::Matrix3d::Identity()).norm(), 1e-13);
  }
}

TEST(Hex8ShapeFunctions, NaturalGradientsAreTheDerivatives) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& xi : InteriorPoints(10, 2)) {
    const Hex8Nodes d = Hex8NaturalGradients(xi);
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(j);
      const Hex8Vector fd =
          (Hex8ShapeFunctions(xi + step) - Hex8ShapeFunctions(xi - step)) / (2 * h);
      // Linear in each coordinate: central differences are exact up to rounding.
      EXPECT_LT((d.col(j) - fd).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// int_{-1}^{1} r^i dr.
double Moment(int i) { return i % 2 ? 0.0 : 2.0 / (i + 1); }

// |rule - exact| for r^i s^j t^k.
double MonomialError(int i, int j, int k) {
  double sum = 0;
  for (const Hex8QuadraturePoint& p : Hex8Rule()) {
    sum += p.weight * std::pow(p.xi.x(), i) * std::pow(p.xi.y(), j) * std::pow(p.xi.z(), k);
  }
  return std::abs(sum - Moment(i) * Moment(j) * Moment(k));
}

TEST(Hex8Quadrature, TwoPointRuleIsExactForTrilinearTimesTrilinear) {
  double weights = 0;
  for (const Hex8QuadraturePoint& p : Hex8Rule()) {
    weights += p.weight;
    EXPECT_LT(p.xi.cwiseAbs().maxCoeff(), 1);
  }
  EXPECT_NEAR(weights, 8, 1e-15);
  // N_a N_b has degree <= 2 in each coordinate; the rule goes to 3.
  for (int i = 0; i <= 3; ++i) {
    for (int j = 0; j <= 3; ++j) {
      for (int k = 0; k <= 3; ++k) EXPECT_LT(MonomialError(i, j, k), 1e-14) << i << j << k;
    }
  }
  // The consistent mass entries themselves: int N_a N_b over the cube is
  // prod_c int_{-1}^{1} (1 + r r_a,c)(1 + r r_b,c) / 4 dr = prod_c (1 + r_a,c r_b,c / 3) / 2.
  for (int a = 0; a < 8; ++a) {
    for (int b = 0; b < 8; ++b) {
      double sum = 0;
      for (const Hex8QuadraturePoint& p : Hex8Rule()) {
        const Hex8Vector n = Hex8ShapeFunctions(p.xi);
        sum += p.weight * n(a) * n(b);
      }
      double exact = 1;
      for (int c = 0; c < 3; ++c)
        exact *= (1 + kHex8NodeNatural[a][c] * kHex8NodeNatural[b][c] / 3) / 2;
      EXPECT_NEAR(sum, exact, 1e-15) << a << " " << b;
    }
  }
  // And no more than that: degree 4 in one coordinate is not exact.
  EXPECT_GT(MonomialError(4, 0, 0), 1e-2);
}

Vector24d LinearField(const Hex8Nodes& x, const Eigen::Matrix3d& grad_u) {
  Vector24d u;
  const Eigen::Vector3d shift(0.01, -0.02, 0.005);  // a translation changes nothing
  for (int a = 0; a < 8; ++a) u.segment<3>(3 * a) = grad_u * x.row(a).transpose() + shift;
  return u;
}

Vector6d VoigtStrain(const Eigen::Matrix3d& g) {
  Vector6d e;
  e << g(0, 0), g(1, 1), g(2, 2), g(1, 2) + g(2, 1), g(0, 2) + g(2, 0), g(0, 1) + g(1, 0);
  return e;
}

TEST(Hex8PatchTest, LinearFieldGivesExactConstantStrain) {
  Eigen::Matrix3d grad_u;
  grad_u << 0.01, 0.002, -0.003, 0.004, -0.02, 0.005, 0.001, 0.006, 0.03;
  const Vector6d expected = VoigtStrain(grad_u);
  for (const Hex8Nodes& x : {Brick(), Distorted()}) {
    const Vector24d u = LinearField(x, grad_u);
    for (const Eigen::Vector3d& xi : InteriorPoints(10, 3)) {
      EXPECT_LT((Hex8Strain(x, u, xi) - expected).norm(), 1e-15);
      EXPECT_LT((Hex8StrainFull(x, u, xi) - expected).norm(), 1e-15);
    }
    for (int a = 0; a < 8; ++a) {
      EXPECT_LT((Hex8Strain(x, u, NodeNatural(a)) - expected).norm(), 1e-15);
      EXPECT_LT((Hex8StrainFull(x, u, NodeNatural(a)) - expected).norm(), 1e-15);
    }
    // The stiffnesses give the energy of that constant strain:
    // u^T K u = eps^T D eps V.
    const Matrix6d d = IsotropicElasticity(kE, kNu);
    const double exact = expected.dot(d * expected) * Hex8Volume(x);
    EXPECT_NEAR(u.dot(Hex8Stiffness(x, d) * u), exact, 1e-12 * exact);
    EXPECT_NEAR(u.dot(Hex8StiffnessFull(x, d) * u), exact, 1e-12 * exact);
  }
}

using StiffnessFunction = Matrix24d (*)(const Hex8Nodes&, const Matrix6d&);

TEST(Hex8Stiffness, ExactlySixRigidModes) {
  for (StiffnessFunction stiffness : {&Hex8Stiffness, &Hex8StiffnessFull}) {
    const char* name = stiffness == &Hex8Stiffness ? "B-bar" : "full";
    for (const Hex8Nodes& x : {Brick(), Distorted()}) {
      for (double nu : {0.3, 0.4999}) {
        const Matrix24d k = stiffness(x, IsotropicElasticity(kE, nu));
        EXPECT_LT((k - k.transpose()).norm(), 1e-13 * k.norm()) << name;
        Eigen::SelfAdjointEigenSolver<Matrix24d> eigen(k);
        const double largest = eigen.eigenvalues().maxCoeff();
        for (int i = 0; i < 6; ++i) {
          EXPECT_LT(std::abs(eigen.eigenvalues()(i)), 1e-12 * largest) << name;
        }
        // No hourglass mode: the deviatoric part is fully integrated in
        // both. Its stiffness is mu-sized against K for the largest, hence
        // the bound.
        for (int i = 6; i < 24; ++i) {
          EXPECT_GT(eigen.eigenvalues()(i), 1e-6 * largest) << name << " " << i;
        }
        Vector24d rotation, translation;
        const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
        for (int a = 0; a < 8; ++a) {
          rotation.segment<3>(3 * a) = axis.cross(Eigen::Vector3d(x.row(a).transpose()));
          translation.segment<3>(3 * a) << 1, 2, 3;
        }
        EXPECT_LT((k * rotation).norm(), 1e-12 * largest) << name;
        EXPECT_LT((k * translation).norm(), 1e-12 * largest) << name;
      }
    }
  }
}

// On a uniform strain B u = B_bar u at every point, and the B-bar
// correction sum_q (B_vol,q - mean B_vol)^T sigma dV_q vanishes for a
// constant sigma: both elements give the same nodal forces K u, at any nu.
TEST(Hex8Stiffness, UniformStrainGivesTheSameForceWithAndWithoutBBar) {
  Eigen::Matrix3d grad_u;
  grad_u << 0.01, 0.002, -0.003, 0.004, -0.02, 0.005, 0.001, 0.006, 0.03;
  for (const Hex8Nodes& x : {Brick(), Distorted()}) {
    const Vector24d u = LinearField(x, grad_u);
    for (double nu : {0.3, 0.4999}) {
      const Matrix6d d = IsotropicElasticity(kE, nu);
      const Vector24d bar = Hex8Stiffness(x, d) * u, full = Hex8StiffnessFull(x, d) * u;
      EXPECT_LT((bar - full).cwiseAbs().maxCoeff(), 1e-12 * full.cwiseAbs().maxCoeff()) << nu;
      // And they differ on a non-uniform field, or the test would be empty.
      const Vector24d v = u + 0.01 * Vector24d::LinSpaced(-1, 1).array().sin().matrix();
      EXPECT_GT((Hex8Stiffness(x, d) * v - Hex8StiffnessFull(x, d) * v).norm(),
                1e-3 * (Hex8StiffnessFull(x, d) * v).norm())
          << nu;
    }
  }
}

// For any displacement the B-bar strain is the plain one with its
// volumetric part replaced by the element mean of the plain one's.
TEST(Hex8StrainFull, BBarStrainIsThePlainStrainWithTheMeanVolumetricPart) {
  const Hex8Nodes x = Distorted();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> c(-1e-3, 1e-3);
  Vector24d u;
  for (int i = 0; i < 24; ++i) u(i) = c(rng);
  const Hex8Geometry g = ComputeHex8Geometry(x);
  double mean_volumetric = 0;
  for (int q = 0; q < 8; ++q) {
    mean_volumetric += g.volume[q] * Hex8StrainFull(x, u, Hex8Rule()[q].xi).head<3>().sum();
  }
  mean_volumetric /= g.element_volume;
  Vector6d m = Vector6d::Zero();
  m.head<3>().setOnes();
  double spread = 0;
  for (const Eigen::Vector3d& xi : InteriorPoints(10, 5)) {
    const Vector6d full = Hex8StrainFull(x, u, xi), bar = Hex8Strain(x, u, xi);
    const double volumetric = full.head<3>().sum();
    spread = std::max(spread, std::abs(volumetric - mean_volumetric));
    EXPECT_LT((bar - (full + (mean_volumetric - volumetric) / 3 * m)).norm(), 1e-15);
  }
  EXPECT_GT(spread, 1e-4);  // the volumetric strain does vary
}

// In-plane bending of one element, u_x = c (X - Xc)(Y - Yc): its axial
// strain varies linearly through the depth with zero mean, so every Gauss
// point of the fully integrated element sees a volume change (penalised by
// the bulk modulus) while B-bar sees only the mean, zero.
TEST(Hex8Stiffness, BBarDoesNotLockInBending) {
  const Hex8Nodes x = Brick();
  const Eigen::RowVector3d centre = x.colwise().mean();
  Vector24d bending = Vector24d::Zero();
  for (int a = 0; a < 8; ++a) {
    bending(3 * a) = (x(a, 0) - centre.x()) * (x(a, 1) - centre.y());
  }
  const auto energy = [&](const Matrix24d& k) { return bending.dot(k * bending); };
  const double bar_3 = energy(Hex8Stiffness(x, IsotropicElasticity(kE, 0.3)));
  const double bar_4 = energy(Hex8Stiffness(x, IsotropicElasticity(kE, 0.4999)));
  const double bar_5 = energy(Hex8Stiffness(x, IsotropicElasticity(kE, 0.49999)));
  const double full_4 = energy(Hex8StiffnessFull(x, IsotropicElasticity(kE, 0.4999)));
  const double full_5 = energy(Hex8StiffnessFull(x, IsotropicElasticity(kE, 0.49999)));
  std::printf(
      "bending energy: B-bar %.4g (nu 0.3), %.4g (0.4999), %.4g (0.49999); full %.4g, %.4g\n",
      bar_3, bar_4, bar_5, full_4, full_5);
  EXPECT_GT(full_4, 1e3 * bar_4);
  // B-bar's bending energy is the shear modulus's: bounded as nu -> 1/2
  // (mu = E / (2 (1 + nu)) changes by 13 % from nu = 0.3).
  EXPECT_NEAR(bar_5, bar_4, 1e-4 * bar_4);
  EXPECT_NEAR(bar_4 / bar_3, 1.3 / 1.4999, 1e-3);
  // The fully integrated element stiffens with the bulk modulus.
  EXPECT_GT(full_5, 5 * full_4);
}

TEST(Hex8Geometry, VolumeAndJacobianRatio) {
  // A parallelepiped: constant J, det J = V / 8.
  Eigen::Matrix3d edges;
  edges << 1.0, 0.2, -0.1, 0.1, 0.9, 0.3, 0.05, -0.2, 1.1;
  Hex8Nodes p;
  for (int a = 0; a < 8; ++a) {
    p.row(a) = (edges * (NodeNatural(a).array() + 1).matrix() / 2).transpose();
  }
  const double volume = edges.determinant();
  EXPECT_NEAR(Hex8Volume(p), volume, 1e-14);
  EXPECT_NEAR(Hex8JacobianRatio(p), 1.0, 1e-14);
  const Hex8Geometry g = ComputeHex8Geometry(p);
  EXPECT_NEAR(g.min_jacobian, volume / 8, 1e-14);
  EXPECT_NEAR(g.element_volume, volume, 1e-14);

  // The distorted brick: the 2-point rule against 4 x 4 x 4 sub-cubes of it.
  const Hex8Nodes x = Distorted();
  double fine = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d corner(-1 + 0.5 * i, -1 + 0.5 * j, -1 + 0.5 * k);
        for (const Hex8QuadraturePoint& q : Hex8Rule()) {
          const Eigen::Vector3d xi = corner + 0.25 * (q.xi.array() + 1).matrix();
          fine += q.weight / 64 * (x.transpose() * Hex8NaturalGradients(xi)).determinant();
        }
      }
    }
  }
  EXPECT_NEAR(Hex8Volume(x), fine, 1e-14);
  const double ratio = Hex8JacobianRatio(x);
  EXPECT_GT(ratio, 0.3);
  EXPECT_LT(ratio, 0.99);

  // A node pushed through the opposite face inverts the element near it.
  Hex8Nodes folded = Brick();
  folded.row(6) = folded.row(0) + 0.2 * (folded.row(6) - folded.row(0));
  folded.row(6).z() = folded(0, 2) - 0.3;
  EXPECT_LE(Hex8JacobianRatio(folded), 0);
  // Mirrored (x -> -x): inverted everywhere.
  Hex8Nodes mirrored = Brick();
  mirrored.col(0) *= -1;
  EXPECT_EQ(Hex8JacobianRatio(mirrored), -1);
  EXPECT_LT(ComputeHex8Geometry(mirrored).min_jacobian, 0);
}

}  // namespace
}  // namespace pba
