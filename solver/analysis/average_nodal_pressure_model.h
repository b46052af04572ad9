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

#include <memory>

#include "analysis/finite_strain_model.h"

namespace pba {

// `mesh` and `material` must outlive the model.
std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(
    const Mesh& mesh, const HyperelasticMaterial& material);

}  // namespace pba
