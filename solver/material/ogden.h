// Ogden hyperelasticity with the uncoupled split, in the Abaqus convention:
//   W = sum_p (2 mu_p / alpha_p^2)(lb1^alpha_p + lb2^alpha_p + lb3^alpha_p - 3) + U(J)
// with lb_a = J^-1/3 lambda_a the isochoric principal stretches and U the
// volumetric energy of VolumetricParams. Initial shear modulus sum mu_p.
// The brain fit mu = 842 Pa, alpha = -4.7 is one term.
//
// Stress and tangent come from the spectral form (Holzapfel, Nonlinear Solid
// Mechanics, section 6.4, eqs. 6.196-6.200); coincident principal stretches
// use the limit of the spin term.
#pragma once

#include <vector>

#include "material/hyperelastic.h"

namespace pba {

struct OgdenTerm {
  double mu = 0;     // [Pa]
  double alpha = 0;  // [-], nonzero
};

struct OgdenCoefficients {
  std::vector<OgdenTerm> terms;  // 1..3 terms
  VolumetricParams volumetric;

  // Names bad fields as path + ".terms[1].alpha", ".d1" etc.
  Status Validate(const std::string& path) const;
  double ShearModulus() const;
};

class OgdenMaterial final : public HyperelasticMaterial {
 public:
  // `coefficients` must have passed Validate().
  explicit OgdenMaterial(const OgdenCoefficients& coefficients);

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
  void Response(const Eigen::Matrix3d& f, bool volumetric, Vector6d* stress,
                Matrix6d* tangent) const;
  double IsochoricEnergy(const Eigen::Matrix3d& f) const;
  OgdenCoefficients p_;
};

}  // namespace pba
