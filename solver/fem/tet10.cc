#include "fem/tet10.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "fem/strain_displacement.h"

namespace pba {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Volume coordinates (L0, L1, L2, L3) of natural point xi.
Eigen::Vector4d VolumeCoordinates(const Eigen::Vector3d& xi) {
  return Eigen::Vector4d(1 - xi.sum(), xi.x(), xi.y(), xi.z());
}

// The natural point of volume coordinates (l0, l1, l2, l3).
Eigen::Vector3d Natural(const Eigen::Vector4d& l) { return l.tail<3>(); }

// dL_a/dxi: rows (-1 -1 -1), e_r, e_s, e_t.
Eigen::Matrix<double, 4, 3> VolumeCoordinateGradients() {
  Eigen::Matrix<double, 4, 3> d;
  d << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  return d;
}

// Adds the points of the orbit of (l0, l1, l2, l3) under permutations of the
// four volume coordinates, each with `weight`.
void AddOrbit(const Eigen::Vector4d& l, double weight, std::vector<QuadraturePoint>* rule) {
  std::array<int, 4> order = {0, 1, 2, 3};
  std::vector<Eigen::Vector4d> seen;
  do {
    const Eigen::Vector4d p(l(order[0]), l(order[1]), l(order[2]), l(order[3]));
    const bool repeated = std::any_of(seen.begin(), seen.end(), [&](const Eigen::Vector4d& q) {
      return (q - p).cwiseAbs().maxCoeff() == 0.0;
    });
    if (repeated) continue;
    seen.push_back(p);
    rule->push_back({Natural(p), weight});
  } while (std::next_permutation(order.begin(), order.end()));
}

std::vector<QuadraturePoint> MakeStiffnessRule() {
  const double a = (5 + 3 * std::sqrt(5.0)) / 20, b = (5 - std::sqrt(5.0)) / 20;
  std::vector<QuadraturePoint> rule;
  AddOrbit(Eigen::Vector4d(a, b, b, b), 1.0 / 24, &rule);
  return rule;
}

std::vector<QuadraturePoint> MakeMassRule() {
  // Solved again from the moment equations of degree <= 5 to double
  // precision (the published values carry 16 digits).
  constexpr double kA = 0.045503704125653084;  // (a, a, 1/2 - a, 1/2 - a)
  constexpr double kC1 = 0.09273525031089053;  // (c, c, c, 1 - 3c)
  constexpr double kC2 = 0.31088591926330034;
  constexpr double kW0 = 0.007091003462847408, kW1 = 0.01224884051939344,
                   kW2 = 0.018781320953002115;
  std::vector<QuadraturePoint> rule;
  AddOrbit(Eigen::Vector4d(kA, kA, 0.5 - kA, 0.5 - kA), kW0, &rule);
  AddOrbit(Eigen::Vector4d(kC1, kC1, kC1, 1 - 3 * kC1), kW1, &rule);
  AddOrbit(Eigen::Vector4d(kC2, kC2, kC2, 1 - 3 * kC2), kW2, &rule);
  return rule;
}

// det J at `xi` (no inverse).
double JacobianDeterminant(const Tet10Nodes& x, const Eigen::Vector3d& xi) {
  const Eigen::Matrix3d jacobian = x.transpose() * Tet10NaturalGradients(xi);
  return jacobian.determinant();
}

}  // namespace

const std::vector<QuadraturePoint>& Tet10StiffnessRule() {
  static const std::vector<QuadraturePoint> rule = MakeStiffnessRule();
  return rule;
}

const std::vector<QuadraturePoint>& Tet10MassRule() {
  static const std::vector<QuadraturePoint> rule = MakeMassRule();
  return rule;
}

Tet10Vector Tet10ShapeFunctions(const Eigen::Vector3d& xi) {
  const Eigen::Vector4d l = VolumeCoordinates(xi);
  Tet10Vector n;
  for (int a = 0; a < 4; ++a) n(a) = l(a) * (2 * l(a) - 1);
  for (int k = 0; k < 6; ++k) n(4 + k) = 4 * l(kTet10Edges[k][0]) * l(kTet10Edges[k][1]);
  return n;
}

Tet10Nodes Tet10NaturalGradients(const Eigen::Vector3d& xi) {
  const Eigen::Vector4d l = VolumeCoordinates(xi);
  const Eigen::Matrix<double, 4, 3> dl = VolumeCoordinateGradients();
  Tet10Nodes d;
  for (int a = 0; a < 4; ++a) d.row(a) = (4 * l(a) - 1) * dl.row(a);
  for (int k = 0; k < 6; ++k) {
    const int i = kTet10Edges[k][0], j = kTet10Edges[k][1];
    d.row(4 + k) = 4 * (l(j) * dl.row(i) + l(i) * dl.row(j));
  }
  return d;
}

double Tet10Gradients(const Tet10Nodes& x, const Eigen::Vector3d& xi, Tet10Nodes* grad) {
  return PhysicalGradients<10>(x, Tet10NaturalGradients(xi), grad);
}

Tet10BMatrix Tet10StrainDisplacement(const Tet10Nodes& grad) { return SmallStrainB<10>(grad); }

Tet10Geometry ComputeTet10Geometry(const Tet10Nodes& x) {
  Tet10Geometry g;
  const auto& rule = Tet10StiffnessRule();
  g.min_jacobian = kInfinity;
  for (int q = 0; q < 4; ++q) {
    const double det = Tet10Gradients(x, rule[q].xi, &g.grad[q]);
    if (det == 0) g.grad[q].setZero();
    g.volume[q] = rule[q].weight * det;
    g.min_jacobian = std::min(g.min_jacobian, det);
  }
  return g;
}

Matrix30d Tet10Stiffness(const Tet10Nodes& x, const Matrix6d& d) {
  // |det J| as for the 4-node element, so that a consistently negatively
  // oriented element still gives its (positive) stiffness.
  const Tet10Geometry g = ComputeTet10Geometry(x);
  Matrix30d k = Matrix30d::Zero();
  for (int q = 0; q < 4; ++q) {
    const Tet10BMatrix b = Tet10StrainDisplacement(g.grad[q]);
    k.noalias() += std::abs(g.volume[q]) * b.transpose() * d * b;
  }
  return k;
}

Vector6d Tet10Strain(const Tet10Nodes& x, const Vector30d& u, const Eigen::Vector3d& xi) {
  Tet10Nodes grad;
  if (Tet10Gradients(x, xi, &grad) == 0)
    return Vector6d::Constant(std::numeric_limits<double>::quiet_NaN());
  return Tet10StrainDisplacement(grad) * u;
}

double Tet10Volume(const Tet10Nodes& x) {
  double volume = 0;
  for (const QuadraturePoint& p : Tet10MassRule())
    volume += p.weight * JacobianDeterminant(x, p.xi);
  return volume;
}

double Tet10JacobianRatio(const Tet10Nodes& x) {
  double lo = kInfinity, hi = -kInfinity;
  const auto sample = [&](const Eigen::Vector3d& xi) {
    const double det = JacobianDeterminant(x, xi);
    lo = std::min(lo, det);
    hi = std::max(hi, det);
  };
  sample(Eigen::Vector3d::Zero());
  for (int c = 0; c < 3; ++c) sample(Eigen::Vector3d::Unit(c));
  for (const QuadraturePoint& p : Tet10StiffnessRule()) sample(p.xi);
  if (!(hi > 0)) return -1;
  return lo / hi;
}

}  // namespace pba
