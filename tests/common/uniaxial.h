// The homogeneous uniaxial stress of the uncoupled compressible neo-Hookean
// solid, W = mu/2 (I1b - 3) + K/2 (J - 1)^2, in closed form: the reference
// of the frictionless cube compression in the hard cases and the benchmarks.
#pragma once

#include <cmath>

namespace pba::testing {

// At axial stretch l, lateral stretch a, J = a^2 l. With bb = J^(-2/3) b the
// Cauchy stress is sigma = (mu / J) dev(bb) + K (J - 1) I, so
//   sigma_xx = mu J^(-5/3) (a^2 - l^2) / 3 + K (J - 1) = 0
// fixes a, and then sigma_zz = sigma_zz - sigma_xx = mu J^(-5/3) (l^2 - a^2),
//   P_zz = J sigma_zz / l = mu J^(-2/3) (l^2 - a^2) / l.
// As K / mu -> infinity, a^2 -> 1 / l and P_zz -> mu (l - l^-2).
struct UniaxialAnswer {
  double lateral_stretch = 0;
  double nominal_stress = 0;  // P_zz [Pa]
};

inline UniaxialAnswer CompressibleUniaxial(double mu, double bulk, double l) {
  const auto lateral_stress = [&](double a) {
    const double j = a * a * l;
    return mu * std::pow(j, -5.0 / 3) * (a * a - l * l) / 3 + bulk * (j - 1);
  };
  // sigma_xx < 0 as a -> 0 (J -> 0) and > 0 for a large: bisect.
  double lo = 1e-3, hi = 10;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (lateral_stress(mid) < 0 ? lo : hi) = mid;
  }
  const double a = 0.5 * (lo + hi), j = a * a * l;
  return {a, mu * std::pow(j, -2.0 / 3) * (l * l - a * a) / l};
}

inline double IncompressibleUniaxial(double mu, double l) { return mu * (l - 1 / (l * l)); }

}  // namespace pba::testing
