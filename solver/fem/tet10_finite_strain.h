// Total-Lagrangian 10-node tetrahedron: internal force, consistent tangent
// and stored energy from a hyperelastic material, integrated with the
// 4-point rule of fem/tet10.h (Bathe, Finite Element Procedures, 2nd ed.,
// section 6.3.2; Bonet & Wood, Nonlinear Continuum Mechanics for FEA,
// chapter 9). Per integration point q, with G_a = dN_a/dX and dV_q = w_q det J_q:
//
//   F_q   = I + sum_a u_a (x) G_a
//   f     = sum_q B_NL(F_q)^T S(F_q) dV_q
//   K     = sum_q [B_NL^T C B_NL + (G_a . S G_b) I] dV_q   (material + geometric)
//   Pi    = sum_q W(F_q) dV_q
//
// Reference configuration, Voigt order xx yy zz yz xz xy with engineering
// shear strains, node order and natural coordinates as in fem/tet10.h.
#pragma once

#include <Eigen/Core>
#include <array>

#include "fem/tet10.h"

namespace pba {

class HyperelasticMaterial;

struct Tet10FiniteStrainResult {
  Vector30d force;    // internal force [N]
  Matrix30d tangent;  // d force / d u [N/m], only when asked for
  double energy = 0;  // stored energy [J]
  // Deformation gradient at each point of Tet10StiffnessRule().
  std::array<Eigen::Matrix3d, 4> f;
};

// Force, energy and (when `with_tangent`) tangent of one element with
// reference geometry `reference` (ComputeTet10Geometry) and displacement `u`
// (30: u0x u0y u0z u1x ... [m]). Returns false, leaving `result`
// unspecified, when the reference element is inverted (det J <= 0 at an
// integration point) or F is not admissible (det F <= 0 or not finite) at
// one.
//
// With `drop_pressure_stiffness` the tangent is the positive definite
// approximation Newton falls back on when the consistent one is indefinite
// (far from equilibrium, K (J - 1) >> mu): the isochoric material and
// geometric stiffness plus only the volumetric term U''(J) J^2 C^-1 (x) C^-1,
// without the pressure's initial-stress terms
// (J U'(J) (C^-1 (x) C^-1 - 2 I_C^-1) and the geometric stiffness of
// U'(J) J C^-1). The force and energy are unchanged.
bool Tet10FiniteStrain(const Tet10Geometry& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result, bool drop_pressure_stiffness = false);

// The same from the reference node coordinates (10 x 3 [m]).
bool Tet10FiniteStrain(const Tet10Nodes& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result);

}  // namespace pba
