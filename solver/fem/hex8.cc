#include "fem/hex8.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "fem/strain_displacement.h"

namespace pba {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

Eigen::Vector3d NodeNatural(int a) {
  return Eigen::Vector3d(kHex8NodeNatural[a][0], kHex8NodeNatural[a][1], kHex8NodeNatural[a][2]);
}

std::array<Hex8QuadraturePoint, 8> MakeRule() {
  const double g = 1 / std::sqrt(3.0);
  std::array<Hex8QuadraturePoint, 8> rule;
  for (int q = 0; q < 8; ++q) rule[q] = {g * NodeNatural(q), 1.0};
  return rule;
}

// det J at `xi` (no inverse).
double JacobianDeterminant(const Hex8Nodes& x, const Eigen::Vector3d& xi) {
  return (x.transpose() * Hex8NaturalGradients(xi)).determinant();
}

// sum_q B_q^T D B_q |w_q det J_q|, B_q the B-bar or the plain matrix.
// |det J| as for the tetrahedra, so that a consistently negatively oriented
// element still gives its (positive) stiffness.
Matrix24d Stiffness(const Hex8Nodes& x, const Matrix6d& d, bool mean_dilatation) {
  const Hex8Geometry g = ComputeHex8Geometry(x);
  Matrix24d k = Matrix24d::Zero();
  for (int q = 0; q < 8; ++q) {
    const Hex8BMatrix b = mean_dilatation ? Hex8StrainDisplacementBar(g.grad[q], g.mean_grad)
                                          : Hex8StrainDisplacement(g.grad[q]);
    k.noalias() += std::abs(g.volume[q]) * b.transpose() * d * b;
  }
  return k;
}

}  // namespace

const std::array<Hex8QuadraturePoint, 8>& Hex8Rule() {
  static const std::array<Hex8QuadraturePoint, 8> rule = MakeRule();
  return rule;
}

Hex8Vector Hex8ShapeFunctions(const Eigen::Vector3d& xi) {
  Hex8Vector n;
  for (int a = 0; a < 8; ++a) {
    n(a) = (1 + xi.x() * kHex8NodeNatural[a][0]) * (1 + xi.y() * kHex8NodeNatural[a][1]) *
           (1 + xi.z() * kHex8NodeNatural[a][2]) / 8;
  }
  return n;
}

Hex8Nodes Hex8NaturalGradients(const Eigen::Vector3d& xi) {
  Hex8Nodes d;
  for (int a = 0; a < 8; ++a) {
    const double r = kHex8NodeNatural[a][0], s = kHex8NodeNatural[a][1], t = kHex8NodeNatural[a][2];
    const double fr = 1 + xi.x() * r, fs = 1 + xi.y() * s, ft = 1 + xi.z() * t;
    d(a, 0) = r * fs * ft / 8;
    d(a, 1) = fr * s * ft / 8;
    d(a, 2) = fr * fs * t / 8;
  }
  return d;
}

double Hex8Gradients(const Hex8Nodes& x, const Eigen::Vector3d& xi, Hex8Nodes* grad) {
  return PhysicalGradients<8>(x, Hex8NaturalGradients(xi), grad);
}

Hex8BMatrix Hex8StrainDisplacement(const Hex8Nodes& grad) { return SmallStrainB<8>(grad); }

Hex8BMatrix Hex8StrainDisplacementBar(const Hex8Nodes& grad, const Hex8Nodes& mean_grad) {
  // The volumetric part of B is (1/3) m (div row), the div row of node a
  // being grad N_a in its three columns; swap it for the mean's.
  Hex8BMatrix b = Hex8StrainDisplacement(grad);
  for (int a = 0; a < 8; ++a) {
    const Eigen::RowVector3d shift = (mean_grad.row(a) - grad.row(a)) / 3;
    for (int row = 0; row < 3; ++row) b.block<1, 3>(row, 3 * a) += shift;
  }
  return b;
}

Hex8Geometry ComputeHex8Geometry(const Hex8Nodes& x) {
  Hex8Geometry g;
  const auto& rule = Hex8Rule();
  g.min_jacobian = kInfinity;
  g.mean_grad.setZero();
  for (int q = 0; q < 8; ++q) {
    const double det = Hex8Gradients(x, rule[q].xi, &g.grad[q]);
    if (det == 0) g.grad[q].setZero();
    g.volume[q] = rule[q].weight * det;
    g.element_volume += g.volume[q];
    g.mean_grad += g.volume[q] * g.grad[q];
    g.min_jacobian = std::min(g.min_jacobian, det);
  }
  // Signed weights: for a consistently negatively oriented element the signs
  // cancel and the mean is still the mean.
  if (g.element_volume != 0) g.mean_grad /= g.element_volume;
  return g;
}

Matrix24d Hex8Stiffness(const Hex8Nodes& x, const Matrix6d& d) { return Stiffness(x, d, true); }

Matrix24d Hex8StiffnessFull(const Hex8Nodes& x, const Matrix6d& d) {
  return Stiffness(x, d, false);
}

Vector6d Hex8Strain(const Hex8Nodes& x, const Vector24d& u, const Eigen::Vector3d& xi) {
  Hex8Nodes grad;
  if (Hex8Gradients(x, xi, &grad) == 0)
    return Vector6d::Constant(std::numeric_limits<double>::quiet_NaN());
  return Hex8StrainDisplacementBar(grad, ComputeHex8Geometry(x).mean_grad) * u;
}

Vector6d Hex8StrainFull(const Hex8Nodes& x, const Vector24d& u, const Eigen::Vector3d& xi) {
  Hex8Nodes grad;
  if (Hex8Gradients(x, xi, &grad) == 0)
    return Vector6d::Constant(std::numeric_limits<double>::quiet_NaN());
  return Hex8StrainDisplacement(grad) * u;
}

double Hex8Volume(const Hex8Nodes& x) {
  double volume = 0;
  for (const Hex8QuadraturePoint& p : Hex8Rule()) volume += p.weight * JacobianDeterminant(x, p.xi);
  return volume;
}

double Hex8JacobianRatio(const Hex8Nodes& x) {
  double lo = kInfinity, hi = -kInfinity;
  const auto sample = [&](const Eigen::Vector3d& xi) {
    const double det = JacobianDeterminant(x, xi);
    lo = std::min(lo, det);
    hi = std::max(hi, det);
  };
  for (int a = 0; a < 8; ++a) sample(NodeNatural(a));
  for (const Hex8QuadraturePoint& p : Hex8Rule()) sample(p.xi);
  if (!(hi > 0)) return -1;
  return lo / hi;
}

}  // namespace pba
