// Isotropic and orthotropic small-strain linear elasticity (DOMAIN.md
// eq. 2.21), Voigt order xx yy zz yz xz xy (in a material frame: 11 22 33 23
// 13 12) with engineering shear strains, gamma_yz = 2 eps_yz.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "material/voigt.h"
#include "pba/scene.h"

namespace pba {

// Elasticity matrix D: stress = D strain [Pa].
Matrix6d IsotropicElasticity(double youngs_modulus, double poissons_ratio);

// Its inverse, the compliance matrix [1/Pa].
Matrix6d IsotropicCompliance(double youngs_modulus, double poissons_ratio);

// Orthotropic compliance in the material frame [1/Pa]:
//   [ 1/E1      -nu21/E2  -nu31/E3                      ]
//   [ -nu12/E1  1/E2      -nu32/E3                      ]
//   [ -nu13/E1  -nu23/E2  1/E3                          ]
//   [                               1/G23               ]
//   [                                     1/G13         ]
//   [                                           1/G12   ]
// symmetric because nu_ji / E_j = nu_ij / E_i (Jones, Mechanics of Composite
// Materials, 2nd ed. 1999, sec. 2.3).
Matrix6d OrthotropicCompliance(const OrthotropicElasticParams& params);

// Its inverse, the elasticity matrix D in the material frame [Pa]. Needs
// params.Validate() to pass (a positive definite compliance).
Matrix6d OrthotropicElasticity(const OrthotropicElasticParams& params);

// Orthonormal material frame from the two axes of OrthotropicElasticParams:
// column 0 = a = axis_1 / |axis_1|, column 1 = b = the part of axis_2
// orthogonal to a, normalised, column 2 = c = a x b. A proper rotation Q
// taking material components to global ones, v_global = Q v_material.
Eigen::Matrix3d MaterialFrame(const std::array<double, 3>& axis_1,
                              const std::array<double, 3>& axis_2);

// Bond stress transformation: the Voigt image M of sigma -> Q sigma Q^T, so
// sigma_global = M sigma_material. Entry (I, J), I = (i, j), J = (k, l):
// Q_ik Q_jl + Q_il Q_jk when k != l, Q_ik Q_jk when k == l. With engineering
// shear strains, eps_material = M^T eps_global (Bond 1943, Bell Syst. Tech.
// J. 22:1, the 6 x 6 "Bond matrices").
Matrix6d StressRotation(const Eigen::Matrix3d& frame);

// A material-frame elasticity matrix in the global frame, D_global =
// M D M^T, and a material-frame compliance, S_global = M^-T S M^-1 (with
// M^-1 the Bond matrix of Q^T), so that S_global = D_global^-1 when S = D^-1.
Matrix6d RotateElasticity(const Matrix6d& d_material, const Eigen::Matrix3d& frame);
Matrix6d RotateCompliance(const Matrix6d& s_material, const Eigen::Matrix3d& frame);

// The small-strain elasticity of every element of a model: one elasticity
// matrix D [Pa] and compliance S = D^-1 [1/Pa] per distinct material, both in
// the global frame, and the material of each element. Assembly, recovery
// and the energy norms of the error estimators all read it, so a body of
// several materials (regions, inclusions, a tissue library) is one model in
// each of them.
class ElasticityField {
 public:
  // `d[k]` and `compliance[k]` of material k; `of_element[e]` in range.
  ElasticityField(std::vector<Matrix6d> d, std::vector<Matrix6d> compliance,
                  std::vector<int> of_element);
  // Every element with elasticity `d` (compliance by inversion).
  static ElasticityField Uniform(const Matrix6d& d, int elements);

  const Matrix6d& D(int e) const { return d_[of_element_[e]]; }
  const Matrix6d& Compliance(int e) const { return compliance_[of_element_[e]]; }
  int num_elements() const { return static_cast<int>(of_element_.size()); }
  int num_materials() const { return static_cast<int>(d_.size()); }
  int material_of(int e) const { return of_element_[e]; }

 private:
  std::vector<Matrix6d> d_, compliance_;
  std::vector<int> of_element_;
};

// von Mises equivalent stress of a Voigt stress vector [Pa].
double VonMises(const Vector6d& stress);

}  // namespace pba
