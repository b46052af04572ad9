// The matrices every isoparametric solid element builds from its shape
// function gradients, for N nodes (rows of `grad`: dN_a/dX [1/m]); Voigt
// order xx yy zz yz xz xy with engineering shear strains, element unknowns
// u_e = (u0x u0y u0z u1x ...).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace pba {

// Small strain: strain = B u_e.
template <int N>
Eigen::Matrix<double, 6, 3 * N> SmallStrainB(const Eigen::Matrix<double, N, 3>& grad) {
  Eigen::Matrix<double, 6, 3 * N> b = Eigen::Matrix<double, 6, 3 * N>::Zero();
  for (int a = 0; a < N; ++a) {
    const double dx = grad(a, 0), dy = grad(a, 1), dz = grad(a, 2);
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

// Finite strain, total Lagrangian: delta E (Voigt) = B_NL(F) delta u_e with
// delta E_ij = (F_ki dN_a/dX_j + F_kj dN_a/dX_i) delta u_ak / 2, the shear
// rows carrying 2 delta E_ij (Bathe, Finite Element Procedures, 6.3.2).
template <int N>
Eigen::Matrix<double, 6, 3 * N> GreenLagrangeB(const Eigen::Matrix<double, N, 3>& grad,
                                               const Eigen::Matrix3d& f) {
  static constexpr int kPairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
  Eigen::Matrix<double, 6, 3 * N> b;
  for (int a = 0; a < N; ++a) {
    for (int row = 0; row < 6; ++row) {
      const int i = kPairs[row][0], j = kPairs[row][1];
      for (int k = 0; k < 3; ++k) {
        b(row, 3 * a + k) =
            i == j ? f(k, i) * grad(a, i) : f(k, i) * grad(a, j) + f(k, j) * grad(a, i);
      }
    }
  }
  return b;
}

// Physical gradients from natural ones at a point: J_ij = dX_i/dxi_j =
// sum_a X_ai dN_a/dxi_j, dN_a/dX = (dN_a/dxi) J^-1. Returns det J; `grad`
// is left unspecified when det J = 0.
template <int N>
double PhysicalGradients(const Eigen::Matrix<double, N, 3>& x,
                         const Eigen::Matrix<double, N, 3>& natural,
                         Eigen::Matrix<double, N, 3>* grad) {
  const Eigen::Matrix3d jacobian = x.transpose() * natural;
  const double det = jacobian.determinant();
  if (det != 0) *grad = natural * jacobian.inverse();
  return det;
}

}  // namespace pba
