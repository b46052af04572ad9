#include "material/linear_elastic.h"

#include <cmath>

namespace pba {

Matrix6d IsotropicElasticity(double e, double nu) {
  const double lambda = e * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = e / (2 * (1 + nu));
  Matrix6d d = Matrix6d::Zero();
  d.topLeftCorner<3, 3>().setConstant(lambda);
  for (int i = 0; i < 3; ++i) {
    d(i, i) = lambda + 2 * mu;
    d(i + 3, i + 3) = mu;
  }
  return d;
}

Matrix6d IsotropicCompliance(double e, double nu) {
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().setConstant(-nu / e);
  for (int i = 0; i < 3; ++i) {
    c(i, i) = 1 / e;
    c(i + 3, i + 3) = 2 * (1 + nu) / e;
  }
  return c;
}

double VonMises(const Vector6d& s) {
  const double a = s(0) - s(1), b = s(1) - s(2), c = s(2) - s(0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3 * (s(3) * s(3) + s(4) * s(4) + s(5) * s(5)));
}

}  // namespace pba
