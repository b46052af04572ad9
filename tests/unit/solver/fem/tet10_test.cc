// The 10-node tetrahedron's kernels: shape functions (partition of unity,
// Kronecker property, derivatives), quadrature exactness, the patch test on
// straight and curved elements, the stiffness's null space and the Jacobian
// ratio.
#include "fem/tet10.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "material/linear_elastic.h"

namespace pba {
namespace {

// Natural coordinates of the ten nodes (corners, then the edge midpoints).
Eigen::Vector3d NodeNatural(int a) {
  const Eigen::Matrix<double, 4, 3> corners =
      (Eigen::Matrix<double, 4, 3>() << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
  if (a < 4) return corners.row(a).transpose();
  const auto& e = kTet10Edges[a - 4];
  return 0.5 * (corners.row(e[0]) + corners.row(e[1])).transpose();
}

// Random points inside the reference tetrahedron.
std::vector<Eigen::Vector3d> InteriorPoints(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> points;
  while (static_cast<int>(points.size()) < count) {
    const Eigen::Vector3d xi(u(rng), u(rng), u(rng));
    if (xi.sum() < 1) points.push_back(xi);
  }
  return points;
}

// A skewed element with straight edges: mid-edge nodes at the midpoints [m].
Tet10Nodes Straight() {
  Eigen::Matrix<double, 4, 3> corners;
  corners << 0.1, 0.0, 0.2, 1.3, 0.2, -0.1, 0.2, 0.9, 0.1, 0.3, 0.4, 1.1;
  Tet10Nodes x;
  x.topRows<4>() = corners;
  for (int k = 0; k < 6; ++k) {
    x.row(4 + k) = 0.5 * (corners.row(kTet10Edges[k][0]) + corners.row(kTet10Edges[k][1]));
  }
  return x;
}

// The same with every mid-edge node moved off its edge by ~5-10 % of the
// edge length: a curved element with positive det J throughout.
Tet10Nodes Curved() {
  Tet10Nodes x = Straight();
  Eigen::Matrix<double, 6, 3> offset;
  offset << 0.06, -0.05, 0.04, -0.04, 0.07, 0.03, 0.05, 0.03, -0.06, -0.03, 0.05, 0.06, 0.07, -0.04,
      -0.05, 0.04, 0.06, 0.05;
  x.bottomRows<6>() += offset;
  return x;
}

constexpr double kE = 3000.0, kNu = 0.3;

TEST(Tet10ShapeFunctions, KroneckerPropertyAtTheNodes) {
  for (int a = 0; a < 10; ++a) {
    const Tet10Vector n = Tet10ShapeFunctions(NodeNatural(a));
    for (int b = 0; b < 10; ++b) EXPECT_NEAR(n(b), a == b ? 1.0 : 0.0, 1e-15) << a << " " << b;
  }
}

TEST(Tet10ShapeFunctions, PartitionOfUnityAndGradientsSumToZero) {
  for (const Eigen::Vector3d& xi : InteriorPoints(20, 1)) {
    EXPECT_NEAR(Tet10ShapeFunctions(xi).sum(), 1.0, 1e-14);
    EXPECT_LT(Tet10NaturalGradients(xi).colwise().sum().norm(), 1e-14);
    Tet10Nodes grad;
    ASSERT_GT(Tet10Gradients(Curved(), xi, &grad), 0);
    EXPECT_LT(grad.colwise().sum().norm(), 1e-12);
    // Isoparametric: the coordinates themselves are reproduced, so
    // sum_a X_a (x) grad N_a = I.
    EXPECT_LT((Curved().transpose() * grad - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
}

TEST(Tet10ShapeFunctions, NaturalGradientsAreTheDerivatives) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& xi : InteriorPoints(10, 2)) {
    const Tet10Nodes d = Tet10NaturalGradients(xi);
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(j);
      const Tet10Vector fd =
          (Tet10ShapeFunctions(xi + step) - Tet10ShapeFunctions(xi - step)) / (2 * h);
      // Quadratic functions: central differences are exact up to rounding.
      EXPECT_LT((d.col(j) - fd).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// int over the reference tet of r^i s^j t^k = i! j! k! / (i + j + k + 3)!.
double MonomialIntegral(int i, int j, int k) {
  return std::tgamma(i + 1) * std::tgamma(j + 1) * std::tgamma(k + 1) / std::tgamma(i + j + k + 4);
}

// Largest relative error of `rule` over the monomials of total degree `degree`.
double WorstMonomialError(const std::vector<QuadraturePoint>& rule, int degree) {
  double worst = 0;
  for (int i = 0; i <= degree; ++i) {
    for (int j = 0; i + j <= degree; ++j) {
      const int k = degree - i - j;
      double sum = 0;
      for (const QuadraturePoint& p : rule) {
        sum += p.weight * std::pow(p.xi.x(), i) * std::pow(p.xi.y(), j) * std::pow(p.xi.z(), k);
      }
      const double exact = MonomialIntegral(i, j, k);
      worst = std::max(worst, std::abs(sum - exact) / exact);
    }
  }
  return worst;
}

TEST(Tet10Quadrature, RulesIntegrateMonomialsOfTheirDegreeExactly) {
  const auto& stiffness = Tet10StiffnessRule();
  const auto& mass = Tet10MassRule();
  ASSERT_EQ(stiffness.size(), 4u);
  ASSERT_EQ(mass.size(), 14u);
  for (const auto* rule : {&stiffness, &mass}) {
    for (const QuadraturePoint& p : *rule) {
      EXPECT_GT(p.weight, 0);
      EXPECT_GT(p.xi.minCoeff(), 0);  // strictly inside
      EXPECT_LT(p.xi.sum(), 1);
    }
  }
  for (int degree = 0; degree <= 2; ++degree) {
    EXPECT_LT(WorstMonomialError(stiffness, degree), 1e-14) << "degree " << degree;
  }
  for (int degree = 0; degree <= 5; ++degree) {
    EXPECT_LT(WorstMonomialError(mass, degree), 1e-13) << "degree " << degree;
  }
  // And no more than that: the degrees are what the header says.
  EXPECT_GT(WorstMonomialError(stiffness, 3), 1e-3);
  EXPECT_GT(WorstMonomialError(mass, 6), 1e-4);
}

Vector30d LinearField(const Tet10Nodes& x, const Eigen::Matrix3d& grad_u) {
  Vector30d u;
  const Eigen::Vector3d shift(0.01, -0.02, 0.005);  // a translation changes nothing
  for (int a = 0; a < 10; ++a) u.segment<3>(3 * a) = grad_u * x.row(a).transpose() + shift;
  return u;
}

Vector6d VoigtStrain(const Eigen::Matrix3d& g) {
  Vector6d e;
  e << g(0, 0), g(1, 1), g(2, 2), g(1, 2) + g(2, 1), g(0, 2) + g(2, 0), g(0, 1) + g(1, 0);
  return e;
}

TEST(Tet10PatchTest, LinearFieldGivesExactConstantStrain) {
  Eigen::Matrix3d grad_u;
  grad_u << 0.01, 0.002, -0.003, 0.004, -0.02, 0.005, 0.001, 0.006, 0.03;
  const Vector6d expected = VoigtStrain(grad_u);
  for (const Tet10Nodes& x : {Straight(), Curved()}) {
    const Vector30d u = LinearField(x, grad_u);
    for (const Eigen::Vector3d& xi : InteriorPoints(10, 3)) {
      EXPECT_LT((Tet10Strain(x, u, xi) - expected).norm(), 1e-14);
    }
    for (int a = 0; a < 10; ++a) {
      EXPECT_LT((Tet10Strain(x, u, NodeNatural(a)) - expected).norm(), 1e-14);
    }
    // The stiffness gives the energy of that constant strain: u^T K u = eps^T D eps V
    // with V the rule's volume sum_q w_q det J_q.
    const Matrix6d d = IsotropicElasticity(kE, kNu);
    const Tet10Geometry g = ComputeTet10Geometry(x);
    const double volume = g.volume[0] + g.volume[1] + g.volume[2] + g.volume[3];
    const double energy = u.dot(Tet10Stiffness(x, d) * u);
    EXPECT_NEAR(energy, expected.dot(d * expected) * volume, 1e-12 * energy);
  }
}

TEST(Tet10Stiffness, ExactlySixRigidModesOnStraightAndCurvedElements) {
  for (const Tet10Nodes& x : {Straight(), Curved()}) {
    const Matrix30d k = Tet10Stiffness(x, IsotropicElasticity(kE, kNu));
    EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
    Eigen::SelfAdjointEigenSolver<Matrix30d> eigen(k);
    const double largest = eigen.eigenvalues().maxCoeff();
    for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(eigen.eigenvalues()(i)), 1e-10 * largest);
    // No spurious zero-energy mode: the 4-point rule gives 24 strain
    // constraints for the 24 deformation modes.
    for (int i = 6; i < 30; ++i) EXPECT_GT(eigen.eigenvalues()(i), 1e-6 * largest) << i;
    // A small rotation about an axis and a translation produce no force.
    Vector30d rotation, translation;
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
    for (int a = 0; a < 10; ++a) {
      rotation.segment<3>(3 * a) = axis.cross(Eigen::Vector3d(x.row(a).transpose()));
      translation.segment<3>(3 * a) << 1, 2, 3;
    }
    EXPECT_LT((k * rotation).norm(), 1e-10 * largest);
    EXPECT_LT((k * translation).norm(), 1e-10 * largest);
  }
}

TEST(Tet10Geometry, VolumeAndJacobianRatio) {
  const Tet10Nodes straight = Straight();
  const Eigen::Matrix<double, 4, 3> corners = straight.topRows<4>();
  const double volume = ComputeTet4Geometry(corners).volume;
  EXPECT_NEAR(Tet10Volume(straight), volume, 1e-14);
  EXPECT_NEAR(Tet10JacobianRatio(straight), 1.0, 1e-12);
  const Tet10Geometry g = ComputeTet10Geometry(straight);
  EXPECT_NEAR(g.min_jacobian, 6 * volume, 1e-12);
  // Straight element: its gradients are the 4-node element's at the corners.
  const Tet4Geometry linear = ComputeTet4Geometry(corners);
  Tet10Nodes grad;
  Tet10Gradients(straight, Eigen::Vector3d::Zero(), &grad);  // at corner 0: N_0 = L0 (2 L0 - 1)
  EXPECT_LT((grad.row(0) - 3 * linear.grad.row(0)).norm(), 1e-12);

  const double curved = Tet10JacobianRatio(Curved());
  EXPECT_GT(curved, 0.3);
  EXPECT_LT(curved, 0.999);
  // det J is a cubic in xi, so the 14-point rule integrates it exactly: on
  // the whole element and on each of its 8 edge-midpoint sub-tetrahedra.
  const Eigen::Vector3d o(0, 0, 0), r(1, 0, 0), s(0, 1, 0), t(0, 0, 1);
  const Eigen::Vector3d m_or = (o + r) / 2, m_os = (o + s) / 2, m_ot = (o + t) / 2,
                        m_rs = (r + s) / 2, m_rt = (r + t) / 2, m_st = (s + t) / 2;
  const std::array<std::array<Eigen::Vector3d, 4>, 8> pieces = {{{o, m_or, m_os, m_ot},
                                                                 {m_or, r, m_rs, m_rt},
                                                                 {m_os, m_rs, s, m_st},
                                                                 {m_ot, m_rt, m_st, t},
                                                                 {m_or, m_os, m_ot, m_rt},
                                                                 {m_or, m_os, m_rs, m_rt},
                                                                 {m_os, m_ot, m_rt, m_st},
                                                                 {m_os, m_rs, m_rt, m_st}}};
  const Tet10Nodes x = Curved();
  double fine = 0;
  for (const auto& p : pieces) {
    Eigen::Matrix3d map;
    for (int c = 0; c < 3; ++c) map.col(c) = p[c + 1] - p[0];
    const double scale = std::abs(map.determinant());
    for (const QuadraturePoint& q : Tet10MassRule()) {
      const Eigen::Vector3d xi = p[0] + map * q.xi;
      fine += scale * q.weight * (x.transpose() * Tet10NaturalGradients(xi)).determinant();
    }
  }
  EXPECT_NEAR(Tet10Volume(Curved()), fine, 1e-14);

  // A mid-edge node pushed across the element inverts it near a corner.
  Tet10Nodes folded = Straight();
  folded.row(4) = folded.row(0) + 0.2 * (folded.row(1) - folded.row(0));
  EXPECT_LE(Tet10JacobianRatio(folded), 0);
  // Mirrored (x -> -x): inverted everywhere.
  Tet10Nodes mirrored = Straight();
  mirrored.col(0) *= -1;
  EXPECT_EQ(Tet10JacobianRatio(mirrored), -1);
}

}  // namespace
}  // namespace pba
