// Hyperelastic materials: strain energy, stress and tangent at one material
// point, nothing else (in the manner of MFEM's HyperelasticModel). All models
// use the uncoupled split W(F) = W_iso(C_bar) + U(J) with C_bar = J^-2/3 C
// (DOMAIN.md eq. 2.32). Reference configuration; Voigt order xx yy zz yz xz xy
// with engineering shear strains, so S = dW/dE and C = dS/dE are the plain
// Voigt images of the tensors.
//
// Precondition of Stress and Tangent: det F > 0 (IsAdmissible). Callers check
// J first (Tet4FiniteStrain does); a call with det F <= 0 is a broken
// invariant and aborts with a message instead of returning NaN.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>

#include "core/number_format.h"
#include "material/voigt.h"
#include "pba/status.h"

namespace pba {

// U and its first and second derivatives with respect to J.
struct ScalarDerivatives {
  double value = 0;
  double first = 0;
  double second = 0;
};

class HyperelasticMaterial {
 public:
  virtual ~HyperelasticMaterial() = default;
  // Strain energy density W(F) [J/m^3 = Pa]; +infinity when det F <= 0, so
  // that a line search rejects an inverted state.
  virtual double Energy(const Eigen::Matrix3d& f) const = 0;
  // Second Piola-Kirchhoff stress S = dW/dE (Voigt xx yy zz yz xz xy) [Pa].
  virtual Vector6d Stress(const Eigen::Matrix3d& f) const = 0;
  // Material tangent C = dS/dE (6x6, Voigt, engineering shear in E) [Pa].
  virtual Matrix6d Tangent(const Eigen::Matrix3d& f) const = 0;
  // The isochoric part alone: W_iso, S_iso = dW_iso/dE and C_iso = dS_iso/dE
  // (any output may be null). Elements that treat the volume change
  // separately (average nodal pressure) combine it with Volumetric().
  virtual void Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                         Matrix6d* tangent) const = 0;
  // The volumetric energy U(J) with its first two derivatives.
  virtual ScalarDerivatives Volumetric(double j) const = 0;
  // Initial shear and bulk moduli (for time steps, penalties, reports) [Pa].
  virtual double ShearModulus() const = 0;
  virtual double BulkModulus() const = 0;
  // One line, e.g. "neo-Hookean, mu = 1000 Pa, K = 1e+06 Pa".
  virtual std::string Describe() const = 0;
};

// True when F is finite and det F > 0: the precondition of Stress and Tangent.
bool IsAdmissible(const Eigen::Matrix3d& f);

// Aborts with a message naming `where` unless IsAdmissible(f).
void CheckAdmissible(const Eigen::Matrix3d& f, const char* where);

// Volumetric energy U(J) = sum_{i=1..3} (1/D_i)(J-1)^{2i} (DOMAIN.md eq. 2.32,
// the Abaqus convention). D_1 > 0 is required (K = 2/D_1, eq. 2.34); D_i = 0
// for i > 1 means the term is absent.
struct VolumetricParams {
  std::array<double, 3> d = {2e-6, 0, 0};  // D_1..D_3 [1/Pa]

  // `path` is the owning material's path; fields are named path + ".d1" etc.
  // `max_terms` is the model's order N: D_i for i > N must be zero.
  Status Validate(const std::string& path, int max_terms) const;
  double BulkModulus() const { return 2 / d[0]; }
};

ScalarDerivatives VolumetricEnergy(const VolumetricParams& params, double j);

// Isochoric energy as a function of I1b = J^-2/3 I1 and I2b = J^-4/3 I2, with
// its first and second partial derivatives.
struct IsochoricInvariantEnergy {
  double w = 0;
  double w1 = 0, w2 = 0;             // dW/dI1b, dW/dI2b
  double w11 = 0, w12 = 0, w22 = 0;  // second derivatives
};

struct InvariantState {
  Eigen::Matrix3d c;  // right Cauchy-Green tensor C = F^T F
  double i1b = 3;
  double i2b = 3;
  double j = 1;
};
InvariantState ComputeInvariants(const Eigen::Matrix3d& f);

// S and C of W = w(I1b, I2b) + U(J) by the chain rule through (I1, I2, J)
// (Holzapfel, Nonlinear Solid Mechanics, eqs. 6.32 and 6.193). `tangent` may
// be null when only the stress is wanted.
void InvariantResponse(const InvariantState& state, const IsochoricInvariantEnergy& iso,
                       const ScalarDerivatives& vol, Vector6d* stress, Matrix6d* tangent);

// Voigt (xx yy zz yz xz xy) image of a symmetric 3x3 tensor, and back.
Vector6d SymmetricToVoigt(const Eigen::Matrix3d& t);
Eigen::Matrix3d VoigtToSymmetric(const Vector6d& v);

// Voigt 6x6 image of a fourth-order tensor with minor symmetries, given its
// components A_ijkl.
Matrix6d FourthOrderToVoigt(const std::function<double(int, int, int, int)>& component);

// Shared field checks for the models' Params::Validate; the returned Status
// names `field`.
Status RequireFinite(double value, const std::string& field);
Status RequirePositive(double value, const std::string& field);

}  // namespace pba
