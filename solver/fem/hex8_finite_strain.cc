#include "fem/hex8_finite_strain.h"

#include "fem/finite_strain_element.h"

// The algebra (and the derivation of the mean-dilatation terms) is in
// fem/finite_strain_element.h, shared with the 10-node tetrahedron.

namespace pba {

bool Hex8FiniteStrain(const Hex8Geometry& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return finite_strain_element::MeanDilatation<8, 8>(reference, u, material, with_tangent, result,
                                                     drop_pressure_stiffness);
}

bool Hex8FiniteStrain(const Hex8Nodes& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return Hex8FiniteStrain(ComputeHex8Geometry(reference), u, material, with_tangent, result,
                          drop_pressure_stiffness);
}

bool Hex8FiniteStrainFull(const Hex8Geometry& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return finite_strain_element::FullIntegration<8, 8>(reference, u, material, with_tangent, result,
                                                      drop_pressure_stiffness);
}

bool Hex8FiniteStrainFull(const Hex8Nodes& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return Hex8FiniteStrainFull(ComputeHex8Geometry(reference), u, material, with_tangent, result,
                              drop_pressure_stiffness);
}

}  // namespace pba
