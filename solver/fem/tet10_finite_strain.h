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
// Tet10FiniteStrainMeanDilatation (TET10_MD) integrates the isochoric energy
// at the same four points and the volumetric energy once per element on its
// mean dilatation theta, the variational mean-dilatation method of the brick
// (fem/hex8_finite_strain.h: Nagtegaal, Parks & Rice 1974; Simo, Taylor &
// Pister 1985, CMAME 51:177), with V = sum_q dV_q:
//
//   v       = sum_q det F_q dV_q,  theta = v / V
//   Pi      = sum_q W_iso(F_q) dV_q + V U(theta)
//   f       = sum_q B_NL^T S_iso dV_q + U'(theta) dv/dx
//   K       = sum_q [B_NL^T C_iso B_NL + (G_a . S_iso G_b) I] dV_q
//             + (U''(theta) / V) (dv/dx) (dv/dx)^T + U'(theta) d2v/dx2
//   dv/dx_a = sum_q cof(F_q) G_a dV_q
//   d2v/dx_a dx_b = -sum_q [F_q (G_a x G_b)]_x dV_q      ([w]_x y = w x y)
//
// (derivation in fem/finite_strain_element.h). v is the 4-point rule's
// current volume, not the exact one (det F is cubic on a straight element,
// the rule exact to degree 2); the constraint is on that v, consistently in
// energy, force and tangent. It is the quadratic-displacement, constant-
// pressure pair P2/P0, which satisfies the inf-sup condition in 3D as well
// as in 2D (Boffi, Brezzi & Fortin, Mixed Finite Element Methods and
// Applications, 2013, the P2-P0 element): one volume constraint per element
// instead of four, so it does not lock when nearly incompressible where the
// plain element does (tests/hard/near_incompressibility_test.cc).
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
  // Mean dilatation v / V: Tet10FiniteStrainMeanDilatation's volume
  // constraint; Tet10FiniteStrain reports it for information.
  double theta = 1;
  // The mean-dilatation element's volume constraint, whose stiffness is the
  // tangent's term (U''(theta) / V) (dv/dx) (dv/dx)^T: dv/dx [m^2],
  // volumetric_weight = U''(theta) / V [Pa/m^3] and V [m^3]. A solver that
  // takes the constraint's pressure as an unknown (VolumetricSplit) needs
  // them apart. Set by Tet10FiniteStrainMeanDilatation only; zero otherwise.
  Vector30d volume_gradient = Vector30d::Zero();
  double volumetric_weight = 0;
  double reference_volume = 0;
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

// The mean-dilatation element of the header; arguments and failures as for
// Tet10FiniteStrain. With `drop_pressure_stiffness` the tangent leaves out
// U'(theta) d2v/dx2, the initial-stress stiffness of the element pressure
// (as Hex8FiniteStrain does); force and energy are unchanged, and at u = 0
// the two tangents agree. On a homogeneous deformation it gives
// Tet10FiniteStrain's energy and force.
bool Tet10FiniteStrainMeanDilatation(const Tet10Geometry& reference, const Vector30d& u,
                                     const HyperelasticMaterial& material, bool with_tangent,
                                     Tet10FiniteStrainResult* result,
                                     bool drop_pressure_stiffness = false);

// The same from the reference node coordinates (10 x 3 [m]).
bool Tet10FiniteStrainMeanDilatation(const Tet10Nodes& reference, const Vector30d& u,
                                     const HyperelasticMaterial& material, bool with_tangent,
                                     Tet10FiniteStrainResult* result,
                                     bool drop_pressure_stiffness = false);

}  // namespace pba
