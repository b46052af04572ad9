// Polynomial (generalised Mooney-Rivlin) hyperelasticity, DOMAIN.md eq. 2.32:
//   W = sum_{1 <= i+j <= N} C_ij (I1b-3)^i (I2b-3)^j + sum_{i=1..N} (1/D_i)(J-1)^{2i}
// N = 1 with C01 = 0 is neo-Hookean, N = 1 is two-parameter Mooney-Rivlin.
// Initial shear modulus mu0 = 2 (C10 + C01), bulk modulus K = 2 / D1.
#pragma once

#include <array>

#include "material/hyperelastic.h"

namespace pba {

struct PolynomialCoefficients {
  int order = 1;  // N, 1..3
  // c[i][j] = C_ij [Pa]; entries with i + j = 0 or i + j > order must be 0.
  std::array<std::array<double, 4>, 4> c{};
  VolumetricParams volumetric;

  // Names bad fields as path + ".c10", ".d1" etc.
  Status Validate(const std::string& path) const;
  double ShearModulus() const { return 2 * (c[1][0] + c[0][1]); }
};

// Neo-Hookean with initial shear modulus mu and bulk modulus K [Pa].
PolynomialCoefficients NeoHookeanCoefficients(double mu, double bulk_modulus);
// Mooney-Rivlin with C10, C01 and bulk modulus K [Pa].
PolynomialCoefficients MooneyRivlinCoefficients(double c10, double c01, double bulk_modulus);

class PolynomialMaterial final : public HyperelasticMaterial {
 public:
  // `coefficients` must have passed Validate().
  explicit PolynomialMaterial(const PolynomialCoefficients& coefficients);

  double Energy(const Eigen::Matrix3d& f) const override;
  Vector6d Stress(const Eigen::Matrix3d& f) const override;
  Matrix6d Tangent(const Eigen::Matrix3d& f) const override;
  void Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                 Matrix6d* tangent) const override;
  ScalarDerivatives Volumetric(double j) const override {
    return VolumetricEnergy(p_.volumetric, j);
  }
  double ShearModulus() const override { return p_.ShearModulus(); }
  double BulkModulus() const override { return p_.volumetric.BulkModulus(); }
  std::string Describe() const override;

 private:
  IsochoricInvariantEnergy Isochoric(double i1b, double i2b) const;
  PolynomialCoefficients p_;
};

}  // namespace pba
