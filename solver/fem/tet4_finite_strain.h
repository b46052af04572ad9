// Total-Lagrangian 4-node tetrahedron: deformation gradient, internal force
// and consistent tangent from a hyperelastic material (Bathe, Finite Element
// Procedures, 2nd ed., section 6.3.2; Bonet & Wood, Nonlinear Continuum
// Mechanics for FEA, chapter 9). Reference configuration, Voigt order
// xx yy zz yz xz xy with engineering shear strains.
#pragma once

#include <Eigen/Core>

#include "fem/tet4.h"

namespace pba {

class HyperelasticMaterial;

// F = I + sum_a u_a (x) grad N_a, from the element displacement u_e (12).
Eigen::Matrix3d DeformationGradient(const Tet4Geometry& reference, const Vector12d& u);

// Nonlinear strain-displacement matrix: delta E (Voigt) = B_NL(F) delta u_e.
BMatrix GreenLagrangeVariation(const Tet4Geometry& reference, const Eigen::Matrix3d& f);

struct Tet4FiniteStrainResult {
  Vector12d force;    // internal force, integral of B_NL^T S dV_0 [N]
  Matrix12d tangent;  // material + geometric stiffness [N/m]
  double energy = 0;  // stored energy W V_0 [J]
  double jacobian = 1;  // det F
};

// Internal force, energy and (when `with_tangent`) tangent of one element.
// Returns false (leaving `result` unspecified) when the element is inverted
// (det F <= 0).
bool Tet4FiniteStrain(const Tet4Geometry& reference, const Vector12d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Tet4FiniteStrainResult* result);

}  // namespace pba
