// Voigt notation for symmetric tensors: stress and strain as 6-vectors in
// the order xx yy zz yz xz xy (engineering shear strains), the elasticity
// tensor as a 6 x 6 matrix. Materials compute in these; elements use them.
#pragma once

#include <Eigen/Core>

namespace pba {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

}  // namespace pba
