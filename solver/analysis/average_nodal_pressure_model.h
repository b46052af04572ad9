// The 4-node tetrahedron with average nodal pressure (Bonet & Burton 1998,
// Commun. Numer. Meth. Eng. 14:437), in its variational (nodal volume) form
// for implicit Newton solves: the isochoric energy is integrated per element,
// the volumetric energy per node, on the node's share of volume,
//
//   Pi = sum_e V_e W_iso(F_e) + sum_a V_a U(J_a),
//   V_a = sum_{e ∋ a} V_e / 4,  v_a = sum_{e ∋ a} v_e / 4,  J_a = v_a / V_a.
//
// One volumetric constraint per node instead of per element removes the
// volumetric locking of the plain tetrahedron when K / mu is 1e3..1e6
// (brain tissue). Force and tangent are the exact first and second
// derivatives of Pi; the tangent couples every pair of nodes that share a
// node's patch (a wider pattern than element by element).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "analysis/finite_strain_model.h"
#include "material/material_field.h"

namespace pba {

// `mesh` and `material` must outlive the model.
std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(
    const Mesh& mesh, const HyperelasticMaterial& material);

// With a material per element (material/material_field.h), which must
// outlive the model; its current step is read at every evaluation. A node
// shared by elements of different materials has one volumetric constraint
// per material, over that material's elements around it (the pressure
// jumps at an interface; a growing inclusion is not held to the volume of
// the incompressible tissue around it):
//   Pi_vol = sum_a sum_m V_am U_m(v_am / V_am),
//   V_am, v_am = sum over the elements e ∋ a of material m of V_e / 4, v_e / 4.
std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(const Mesh& mesh,
                                                                     const MaterialField& field,
                                                                     const ThreadContext& threads);

// Each element's pressure and volume ratio at `u` as the model sees them:
// the means over its corners of U_m'(J_am) and of J_am = v_am / V_am, m the
// element's material.
void AverageNodalPressures(const Mesh& mesh, const MaterialField& field, const Eigen::VectorXd& u,
                           std::vector<double>* pressure, std::vector<double>* volume_ratio);

}  // namespace pba
