#include "fem/tet4.h"

#include <Eigen/LU>

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

BMatrix StrainDisplacement(const Tet4Geometry& g) {
  BMatrix b = BMatrix::Zero();
  for (int a = 0; a < 4; ++a) {
    const double dx = g.grad(a, 0), dy = g.grad(a, 1), dz = g.grad(a, 2);
    const int c = 3 * a;
    b(0, c) = dx;
    b(1, c + 1) = dy;
    b(2, c + 2) = dz;
    b(3, c + 1) = dz;  // gamma_yz
    b(3, c + 2) = dy;
    b(4, c) = dz;  // gamma_xz
    b(4, c + 2) = dx;
    b(5, c) = dy;  // gamma_xy
    b(5, c + 1) = dx;
  }
  return b;
}

Matrix12d Tet4Stiffness(const Tet4Geometry& g, const Matrix6d& d) {
  const BMatrix b = StrainDisplacement(g);
  return std::abs(g.volume) * b.transpose() * d * b;
}

}  // namespace pba
