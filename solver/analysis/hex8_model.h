// The 8-node hexahedron (C3D8, fem/hex8.h) with mean dilatation as a
// finite-strain model: total Lagrangian, the isochoric energy at 2 x 2 x 2
// Gauss points, the volumetric energy once per element on its mean
// dilatation (fem/hex8_finite_strain.h). One volume constraint per element
// keeps a nearly incompressible body (brain tissue, K / mu = 1e3..1e6) from
// locking, and the tangent stays element by element (no wider pattern than
// the plain brick's, unlike the average nodal pressure tetrahedron).
//
// MakeHex8FullModel is the plain, fully integrated brick (C3D8 of Abaqus and
// CalculiX, Hex8FiniteStrainFull): the whole energy at the eight points. It
// locks when nearly incompressible; it is there to show that, and to compare
// with codes whose C3D8 is this element.
#pragma once

#include <memory>

#include "analysis/finite_strain_model.h"

namespace pba {

// `mesh` must be hexahedral (Mesh::hexahedral()); unknowns are 3 per node in
// node order [m, N]. `mesh` and `material` must outlive the model.
std::unique_ptr<FiniteStrainModel> MakeHex8Model(const Mesh& mesh,
                                                 const HyperelasticMaterial& material);
std::unique_ptr<FiniteStrainModel> MakeHex8Model(const Mesh& mesh, const MaterialField& field,
                                                 const ThreadContext& threads);

// The fully integrated brick, on the same terms as MakeHex8Model.
std::unique_ptr<FiniteStrainModel> MakeHex8FullModel(const Mesh& mesh,
                                                     const HyperelasticMaterial& material);
std::unique_ptr<FiniteStrainModel> MakeHex8FullModel(const Mesh& mesh, const MaterialField& field,
                                                     const ThreadContext& threads);

}  // namespace pba
