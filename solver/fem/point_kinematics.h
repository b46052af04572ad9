// Kinematics at one integration point of the multi-point elements, shared
// by their models' field recovery (analysis/element_model.h) and the
// finite-strain error estimate: F from the point's shape-function
// gradients, and the mean-dilatation F_bar.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

#include "fem/hex8.h"
#include "fem/tet10.h"

namespace pba {

// F = I + sum_a u_a (x) grad N_a for a 10-node element (rows of `grad`:
// dN_a/dX).
inline Eigen::Matrix3d DeformationGradientTet10(const Tet10Nodes& grad, const Vector30d& ue) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  for (int a = 0; a < 10; ++a) f += ue.segment<3>(3 * a) * grad.row(a);
  return f;
}

// F = I + sum_a u_a (x) grad N_a for an 8-node element.
inline Eigen::Matrix3d DeformationGradientHex8(const Hex8Nodes& grad, const Vector24d& ue) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  for (int a = 0; a < 8; ++a) f += ue.segment<3>(3 * a) * grad.row(a);
  return f;
}

// theta = v / V, the brick's current over reference volume.
inline double MeanDilatation(const Hex8Geometry& g, const Vector24d& ue) {
  double v = 0;
  for (int q = 0; q < 8; ++q) {
    v += g.volume[q] * DeformationGradientHex8(g.grad[q], ue).determinant();
  }
  return v / g.element_volume;
}

// theta = v / V for TET10_MD, by its 4-point rule (fem/tet10_finite_strain.h).
inline double MeanDilatation(const Tet10Geometry& g, const Vector30d& ue) {
  double v = 0, v0 = 0;
  for (int q = 0; q < 4; ++q) {
    v += g.volume[q] * DeformationGradientTet10(g.grad[q], ue).determinant();
    v0 += g.volume[q];
  }
  return v / v0;
}

// F_bar = (theta / det F)^(1/3) F: F's isochoric part with the element's
// mean volume ratio, the F a mean-dilatation element's stress comes from.
inline Eigen::Matrix3d MeanDilatationF(const Eigen::Matrix3d& f, double theta) {
  return std::cbrt(theta / f.determinant()) * f;
}

}  // namespace pba
