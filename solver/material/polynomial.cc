#include "material/polynomial.h"

#include <cmath>

namespace pba {
namespace {

// x^n and its first two derivatives for integer n >= 0.
struct Power {
  double value, first, second;
};
Power IntegerPower(double x, int n) {
  auto pow = [x](int k) { return k < 0 ? 0.0 : std::pow(x, k); };
  return {pow(n), n * pow(n - 1), n * (n - 1) * pow(n - 2)};
}

std::string CoefficientName(int i, int j) { return "c" + std::to_string(i) + std::to_string(j); }

}  // namespace

Status PolynomialCoefficients::Validate(const std::string& path) const {
  if (order < 1 || order > 3) {
    return Status::InvalidArgument(path + ".order",
                                   "must be 1, 2 or 3, got " + std::to_string(order));
  }
  for (int i = 0; i <= 3; ++i) {
    for (int j = 0; i + j <= 3 && j <= 3; ++j) {
      const std::string field = path + "." + CoefficientName(i, j);
      PBA_RETURN_IF_ERROR(RequireFinite(c[i][j], field));
      if ((i + j == 0 || i + j > order) && c[i][j] != 0) {
        return Status::InvalidArgument(
            field, "a polynomial of order " + std::to_string(order) + " has no such term");
      }
    }
  }
  if (!(ShearModulus() > 0)) {
    return Status::InvalidArgument(path + ".c10",
                                   "the initial shear modulus 2 (C10 + C01) must be > 0, got " +
                                       ShortNumber(ShearModulus()) + " Pa");
  }
  return volumetric.Validate(path, order);
}

PolynomialCoefficients NeoHookeanCoefficients(double mu, double bulk_modulus) {
  PolynomialCoefficients p;
  p.c[1][0] = mu / 2;
  p.volumetric.d = {2 / bulk_modulus, 0, 0};
  return p;
}

PolynomialCoefficients MooneyRivlinCoefficients(double c10, double c01, double bulk_modulus) {
  PolynomialCoefficients p;
  p.c[1][0] = c10;
  p.c[0][1] = c01;
  p.volumetric.d = {2 / bulk_modulus, 0, 0};
  return p;
}

PolynomialMaterial::PolynomialMaterial(const PolynomialCoefficients& coefficients)
    : p_(coefficients) {}

IsochoricInvariantEnergy PolynomialMaterial::Isochoric(double i1b, double i2b) const {
  IsochoricInvariantEnergy w;
  for (int i = 0; i <= p_.order; ++i) {
    for (int j = 0; i + j <= p_.order; ++j) {
      const double cij = p_.c[i][j];
      if (cij == 0) continue;
      const Power x = IntegerPower(i1b - 3, i);
      const Power y = IntegerPower(i2b - 3, j);
      w.w += cij * x.value * y.value;
      w.w1 += cij * x.first * y.value;
      w.w2 += cij * x.value * y.first;
      w.w11 += cij * x.second * y.value;
      w.w12 += cij * x.first * y.first;
      w.w22 += cij * x.value * y.second;
    }
  }
  return w;
}

double PolynomialMaterial::Energy(const Eigen::Matrix3d& f) const {
  if (!IsAdmissible(f)) return INFINITY;
  const InvariantState s = ComputeInvariants(f);
  return Isochoric(s.i1b, s.i2b).w + VolumetricEnergy(p_.volumetric, s.j).value;
}

Vector6d PolynomialMaterial::Stress(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "PolynomialMaterial::Stress");
  const InvariantState s = ComputeInvariants(f);
  Vector6d stress;
  InvariantResponse(s, Isochoric(s.i1b, s.i2b), VolumetricEnergy(p_.volumetric, s.j), &stress,
                    nullptr);
  return stress;
}

Matrix6d PolynomialMaterial::Tangent(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "PolynomialMaterial::Tangent");
  const InvariantState s = ComputeInvariants(f);
  Matrix6d tangent;
  InvariantResponse(s, Isochoric(s.i1b, s.i2b), VolumetricEnergy(p_.volumetric, s.j), nullptr,
                    &tangent);
  return tangent;
}

void PolynomialMaterial::Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                                   Matrix6d* tangent) const {
  CheckAdmissible(f, "PolynomialMaterial::Isochoric");
  const InvariantState s = ComputeInvariants(f);
  const IsochoricInvariantEnergy w = Isochoric(s.i1b, s.i2b);
  if (energy) *energy = w.w;
  if (stress || tangent) InvariantResponse(s, w, ScalarDerivatives(), stress, tangent);
}

std::string PolynomialMaterial::Describe() const {
  const std::string bulk = ", K = " + ShortNumber(BulkModulus()) + " Pa";
  if (p_.order == 1 && p_.c[0][1] == 0 && p_.volumetric.d[1] == 0) {
    return "neo-Hookean, mu = " + ShortNumber(ShearModulus()) + " Pa" + bulk;
  }
  if (p_.order == 1) {
    return "Mooney-Rivlin, C10 = " + ShortNumber(p_.c[1][0]) +
           " Pa, C01 = " + ShortNumber(p_.c[0][1]) + " Pa" + bulk;
  }
  std::string text = "polynomial N = " + std::to_string(p_.order);
  for (int i = 0; i <= p_.order; ++i) {
    for (int j = 0; i + j <= p_.order; ++j) {
      if (p_.c[i][j] != 0) {
        text +=
            ", C" + std::to_string(i) + std::to_string(j) + " = " + ShortNumber(p_.c[i][j]) + " Pa";
      }
    }
  }
  for (int i = 0; i < p_.order; ++i) {
    if (p_.volumetric.d[i] != 0) {
      text += ", D" + std::to_string(i + 1) + " = " + ShortNumber(p_.volumetric.d[i]) + " /Pa";
    }
  }
  return text + " (K = " + ShortNumber(BulkModulus()) + " Pa)";
}

}  // namespace pba
