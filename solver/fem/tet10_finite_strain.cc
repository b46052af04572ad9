#include "fem/tet10_finite_strain.h"

#include "fem/finite_strain_element.h"

// The algebra is in fem/finite_strain_element.h, shared with the 8-node
// brick.

namespace pba {

bool Tet10FiniteStrain(const Tet10Geometry& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return finite_strain_element::FullIntegration<10, 4>(reference, u, material, with_tangent, result,
                                                       drop_pressure_stiffness);
}

bool Tet10FiniteStrain(const Tet10Nodes& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result) {
  return Tet10FiniteStrain(ComputeTet10Geometry(reference), u, material, with_tangent, result);
}

bool Tet10FiniteStrainMeanDilatation(const Tet10Geometry& reference, const Vector30d& u,
                                     const HyperelasticMaterial& material, bool with_tangent,
                                     Tet10FiniteStrainResult* result,
                                     bool drop_pressure_stiffness) {
  return finite_strain_element::MeanDilatation<10, 4>(reference, u, material, with_tangent, result,
                                                      drop_pressure_stiffness);
}

bool Tet10FiniteStrainMeanDilatation(const Tet10Nodes& reference, const Vector30d& u,
                                     const HyperelasticMaterial& material, bool with_tangent,
                                     Tet10FiniteStrainResult* result,
                                     bool drop_pressure_stiffness) {
  return Tet10FiniteStrainMeanDilatation(ComputeTet10Geometry(reference), u, material, with_tangent,
                                         result, drop_pressure_stiffness);
}

}  // namespace pba
