// The 10-node quadratic tetrahedron (C3D10, fem/tet10.h) as a finite-strain
// model: total Lagrangian, four integration points per element
// (fem/tet10_finite_strain.h). Quadratic displacements carry the linear
// strain fields the 4-node element lacks, which eases its volumetric and
// bending locking, and curved edges follow a curved boundary. Four volume
// constraints per element are still too many when nearly incompressible: at
// K / mu = 1e6 it locks (tests/hard/near_incompressibility_test.cc).
//
// MakeTet10MdModel is the same element with mean dilatation (TET10_MD,
// Tet10FiniteStrainMeanDilatation): the volumetric energy once per element
// on its mean dilatation, one volume constraint per element (the P2/P0
// pair), so it does not lock; the tangent stays element by element.
#pragma once

#include <memory>

#include "analysis/finite_strain_model.h"

namespace pba {

// `mesh` must be quadratic (Mesh::quadratic(), e.g. from MakeQuadratic);
// unknowns are 3 per node, corners and mid-edge nodes alike, in node order
// [m, N]. `mesh` and `material` must outlive the model.
std::unique_ptr<FiniteStrainModel> MakeTet10Model(const Mesh& mesh,
                                                  const HyperelasticMaterial& material);
std::unique_ptr<FiniteStrainModel> MakeTet10Model(const Mesh& mesh, const MaterialField& field,
                                                  const ThreadContext& threads);

// The mean-dilatation 10-node element, on the same terms as MakeTet10Model.
std::unique_ptr<FiniteStrainModel> MakeTet10MdModel(const Mesh& mesh,
                                                    const HyperelasticMaterial& material);
std::unique_ptr<FiniteStrainModel> MakeTet10MdModel(const Mesh& mesh, const MaterialField& field,
                                                    const ThreadContext& threads);

}  // namespace pba
