#include "fem/tet4.h"

#include <Eigen/LU>

#include "fem/strain_displacement.h"

namespace pba {

Tet4Geometry ComputeTet4Geometry(const Eigen::Matrix<double, 4, 3>& x) {
  // J = [x1 - x0, x2 - x0, x3 - x0] maps reference to physical coordinates;
  // grad N_a = J^-T grad_ref N_a with grad_ref N = (-1 -1 -1; I).
  Eigen::Matrix3d jacobian;
  for (int c = 0; c < 3; ++c) jacobian.col(c) = (x.row(c + 1) - x.row(0)).transpose();
  Tet4Geometry g;
  const double det = jacobian.determinant();
  g.volume = det / 6.0;
  const Eigen::Matrix3d inv_t = jacobian.inverse().transpose();
  Eigen::Matrix<double, 4, 3> ref;
  ref << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  g.grad = (inv_t * ref.transpose()).transpose();
  return g;
}

BMatrix StrainDisplacement(const Tet4Geometry& g) { return SmallStrainB<4>(g.grad); }

Matrix12d Tet4Stiffness(const Tet4Geometry& g, const Matrix6d& d) {
  const BMatrix b = StrainDisplacement(g);
  return std::abs(g.volume) * b.transpose() * d * b;
}

}  // namespace pba
