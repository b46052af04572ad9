// Total-Lagrangian 8-node hexahedron with mean dilatation: internal force,
// consistent tangent and stored energy from a hyperelastic material with the
// uncoupled energy W = W_iso(C_bar) + U(J) of material/hyperelastic.h.
//
// The isochoric energy is integrated with the 2 x 2 x 2 rule of fem/hex8.h,
// the volumetric energy once per element on its mean dilatation theta (the
// variational form of the mean-dilatation method: Nagtegaal, Parks & Rice
// 1974; Simo, Taylor & Pister 1985, CMAME 51:177, with the element pressure
// and dilatation condensed out; Bonet & Wood, Nonlinear Continuum Mechanics
// for FEA, 2nd ed., the mean dilatation technique). With G_a = dN_a/dX and dV_q = w_q det J_q
// at point q, V = sum_q dV_q:
//
//   F_q     = I + sum_a u_a (x) G_a
//   v       = sum_q det F_q dV_q          (the current volume; exact for a
//                                          trilinear brick, det of its
//                                          Jacobian being of degree 2 in
//                                          each natural coordinate)
//   theta   = v / V
//   Pi      = sum_q W_iso(F_q) dV_q + V U(theta)
//   f       = sum_q B_NL(F_q)^T S_iso(F_q) dV_q + U'(theta) dv/dx
//   K       = sum_q [B_NL^T C_iso B_NL + (G_a . S_iso G_b) I] dV_q
//             + (U''(theta) / V) (dv/dx) (dv/dx)^T + U'(theta) d2v/dx2
//   dv/dx_a = sum_q cof(F_q) G_a dV_q
//   d2v/dx_a dx_b = -sum_q [F_q (G_a x G_b)]_x dV_q      ([w]_x y = w x y)
//
// (derivation in fem/finite_strain_element.h). One volume constraint per element
// instead of eight removes the volumetric locking of the fully integrated
// brick; at u = 0 the tangent is the B-bar stiffness of fem/hex8.h.
//
// Hex8FiniteStrainFull is the plain, fully integrated brick (C3D8 of Abaqus
// and CalculiX): the whole energy W(F_q) at each of the eight points,
//
//   Pi = sum_q W(F_q) dV_q,  f = sum_q B_NL^T S_q dV_q,
//   K  = sum_q [B_NL^T C_q B_NL + (G_a . S_q G_b) I] dV_q,
//
// with S, C the material's full stress and tangent. Eight volume constraints
// per element: it locks when nearly incompressible; at u = 0 its tangent is
// Hex8StiffnessFull. On a homogeneous deformation the two elements give the
// same energy and force.
//
// Reference configuration, Voigt order xx yy zz yz xz xy with engineering
// shear strains, node order and natural coordinates as in fem/hex8.h.
#pragma once

#include <Eigen/Core>
#include <array>

#include "fem/hex8.h"

namespace pba {

class HyperelasticMaterial;

struct Hex8FiniteStrainResult {
  Vector24d force;    // internal force [N]
  Matrix24d tangent;  // d force / d u [N/m], only when asked for
  double energy = 0;  // stored energy [J]
  // Deformation gradient at each point of Hex8Rule().
  std::array<Eigen::Matrix3d, 8> f;
  // Mean dilatation v / V: Hex8FiniteStrain's volume constraint;
  // Hex8FiniteStrainFull reports it for information.
  double theta = 1;
  // The mean-dilatation element's volume constraint, whose stiffness is the
  // tangent's term (U''(theta) / V) (dv/dx) (dv/dx)^T: dv/dx [m^2],
  // volumetric_weight = U''(theta) / V [Pa/m^3] and V [m^3]. A solver that
  // takes the constraint's pressure as an unknown (VolumetricSplit) needs
  // them apart. Set by Hex8FiniteStrain only; zero otherwise.
  Vector24d volume_gradient = Vector24d::Zero();
  double volumetric_weight = 0;
  double reference_volume = 0;
};

// Force, energy and (when `with_tangent`) tangent of one element with
// reference geometry `reference` (ComputeHex8Geometry) and displacement `u`
// (24: u0x u0y u0z u1x ... [m]). Returns false, leaving `result`
// unspecified, when the reference element is inverted (det J <= 0 at an
// integration point) or F is not admissible (det F <= 0 or not finite) at
// one; the material is then not called.
//
// With `drop_pressure_stiffness` the tangent leaves out U'(theta) d2v/dx2,
// the initial-stress stiffness of the element pressure: it is what makes the
// consistent tangent indefinite when a nearly incompressible body is far
// from equilibrium (K |theta - 1| >> mu), and what remains is the positive
// semi-definite approximation Newton falls back on. Force and energy are
// unchanged; at u = 0 (U'(1) = 0) the two tangents agree.
bool Hex8FiniteStrain(const Hex8Geometry& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness = false);

// The same from the reference node coordinates (8 x 3 [m]).
bool Hex8FiniteStrain(const Hex8Nodes& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness = false);

// The fully integrated element of the header, arguments and failures as for
// Hex8FiniteStrain. With `drop_pressure_stiffness` the tangent leaves out
// U'(J_q) d2J_q/dx2 at every point, as fem/tet10_finite_strain.h does: the
// material part is the isochoric tangent plus U''(J) J^2 C^-1 (x) C^-1, the
// geometric part that of the isochoric stress S_iso. Force and energy are
// unchanged; at u = 0 the two tangents agree.
bool Hex8FiniteStrainFull(const Hex8Geometry& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness = false);

// The same from the reference node coordinates (8 x 3 [m]).
bool Hex8FiniteStrainFull(const Hex8Nodes& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness = false);

}  // namespace pba
