// The 4-node linear tetrahedron: constant shape-function gradients, constant
// strain. Voigt order xx yy zz yz xz xy with engineering shear strains.
#pragma once

#include <Eigen/Core>

#include "material/voigt.h"

namespace pba {

using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Vector12d = Eigen::Matrix<double, 12, 1>;
using BMatrix = Eigen::Matrix<double, 6, 12>;

struct Tet4Geometry {
  // Row a = gradient of shape function N_a with respect to x, y, z [1/m].
  Eigen::Matrix<double, 4, 3> grad;
  double volume = 0;  // signed [m^3]; positive for a positively oriented element
};

// Gradients and volume from the four corner positions (rows of x, [m]).
Tet4Geometry ComputeTet4Geometry(const Eigen::Matrix<double, 4, 3>& x);

// Strain-displacement matrix: strain = B u_e, u_e = (u0x u0y u0z u1x ...).
BMatrix StrainDisplacement(const Tet4Geometry& g);

// Element stiffness B^T D B V (small strain), D the 6 x 6 elasticity matrix.
Matrix12d Tet4Stiffness(const Tet4Geometry& g, const Matrix6d& d);

}  // namespace pba
