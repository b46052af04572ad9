// The material-point kernel: from a deformation gradient F to the first
// Piola-Kirchhoff stress P at one point, in the arrays the element kernels
// keep (row-major 3 x 3). Every engine goes through the same pieces:
//
//   S_iso      HyperelasticMaterial::Isochoric (any model),
//   S_visc     ViscousStep::Relax over the point's Prony state
//              (material/viscoelastic.h), when the material relaxes,
//   P          F S_visc + p cof F, p the pressure: U'(J) of the point, or
//              its nodal average (average nodal pressure), less any bulk
//              viscosity.
//
// The implicit analyses take the same S_iso and ViscousStep through
// MaterialField's per-element response (material/material_field.h), where
// the stress within a step is alpha S_iso + offset and the tangent follows.
// Neo-Hookean tissue without relaxation has the closed form
//   P = a F + (p - a I1 / (3 J)) cof F,  a = mu J^-2/3,
// which needs no inverse (NeoHookeanFirstPiola; material_point_test checks
// it against the general path).
#pragma once

#include <Eigen/Core>

#include "material/hyperelastic.h"
#include "material/viscoelastic.h"

namespace pba {

// cof F = det(F) F^-T, row-major 3 x 3.
inline void Cofactor(const double* f, double* c) {
  c[0] = f[4] * f[8] - f[5] * f[7];
  c[1] = f[5] * f[6] - f[3] * f[8];
  c[2] = f[3] * f[7] - f[4] * f[6];
  c[3] = f[2] * f[7] - f[1] * f[8];
  c[4] = f[0] * f[8] - f[2] * f[6];
  c[5] = f[1] * f[6] - f[0] * f[7];
  c[6] = f[1] * f[5] - f[2] * f[4];
  c[7] = f[2] * f[3] - f[0] * f[5];
  c[8] = f[0] * f[4] - f[1] * f[3];
}

// det F of a row-major 3 x 3.
inline double Determinant(const double* f) {
  return f[0] * (f[4] * f[8] - f[5] * f[7]) - f[1] * (f[3] * f[8] - f[5] * f[6]) +
         f[2] * (f[3] * f[7] - f[4] * f[6]);
}

// Neo-Hookean P with shear modulus mu and pressure p at F (cof F, J and
// J^(1/3) given, as the caller has them).
inline void NeoHookeanFirstPiola(double mu, double p, const double* f, const double* cof, double j,
                                 double cbrt_j, double* pk) {
  double i1 = 0;
  for (int k = 0; k < 9; ++k) i1 += f[k] * f[k];
  const double a = mu / (cbrt_j * cbrt_j);
  const double b = p - a * i1 / (3 * j);
  for (int k = 0; k < 9; ++k) pk[k] = a * f[k] + b * cof[k];
}

// P of any model at F with pressure p: S_iso of `model`, relaxed over the
// step when `step` is given (advancing `state`, PronyStateSize numbers),
// then F S + p cof F.
inline void FirstPiola(const HyperelasticMaterial& model, const ViscousStep* step, double* state,
                       const double* fe, const double* cof, double p, double* pk) {
  const Eigen::Matrix3d f = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(fe);
  Vector6d s_iso;
  model.Isochoric(f, nullptr, &s_iso, nullptr);
  if (step != nullptr) s_iso = step->Relax(s_iso, state);
  const Eigen::Matrix3d p_iso = f * VoigtToSymmetric(s_iso);
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) pk[3 * i + k] = p_iso(i, k) + p * cof[3 * i + k];
  }
}

}  // namespace pba
