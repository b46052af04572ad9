// Scenes the integration tests share.
//
// A linear block on 1 mm elements, held at the bottom and pushed 1 mm down
// at the top: the tests' long-running solve. At 50 mm it has about 400k
// unknowns (tens of seconds of factorisation or conjugate gradients on two
// cores), at 30 mm about 85k (a few seconds, 880 MB): time to cancel it or
// kill its process.
#pragma once

#include <sstream>
#include <string>

namespace pba::testing {

inline std::string BlockSceneYaml(const std::string& name, int size_mm) {
  const std::string size = std::to_string(size_mm);
  return "name: " + name + "\ngeometry: {box: {size_mm: [" + size + ", " + size + ", " + size +
         "]}}\nmesh: {element_size_mm: 1}\n"
         "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
         "boundary_conditions:\n  - {set: bottom, fixed: {}}\n"
         "  - {set: top, displacement: {z_mm: -1}}\n";
}

// A 10 mm linear block on 5 mm elements, held at the bottom and pushed
// 1 mm down at the top: a job of a fraction of a second.
inline std::string SmallBlockSceneYaml(const std::string& name) {
  return "name: " + name +
         "\ngeometry: {box: {size_mm: [10, 10, 10]}}\nmesh: {element_size_mm: 5}\n"
         "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
         "boundary_conditions:\n  - {set: bottom, fixed: {}}\n"
         "  - {set: top, displacement: {z_mm: -1}}\n";
}

// A small QUASI_STATIC hold of a viscoelastic cube, held until `end_s`,
// meshed at `size_mm`.
inline std::string HoldSceneYaml(double end_s, double size_mm = 5) {
  std::ostringstream s;
  s << "name: hold\n"
       "geometry: {box: {size_mm: [10, 10, 10]}}\n"
       "mesh: {element: TET4_ANP, element_size_mm: "
    << size_mm
    << "}\n"
       "material:\n"
       "  neo_hookean: {shear_modulus_pa: 2200, bulk_modulus_pa: 2.2e6}\n"
       "  viscoelastic: {prony: {g: [0.5], tau_s: [2]}}\n"
       "boundary_conditions:\n"
       "  - {set: bottom, symmetry: {}}\n"
       "  - {set: x_min, symmetry: {}}\n"
       "  - {set: y_min, symmetry: {}}\n"
       "  - {set: top, displacement: {z_mm: -1}}\n"
       "analysis:\n"
       "  type: QUASI_STATIC\n"
       "  time:\n"
       "    end_time_s: "
    << end_s
    << "\n"
       "    curve: [{time_s: 0, amplitude: 0}, {time_s: 1, amplitude: 1}, {time_s: "
    << end_s
    << ", amplitude: 1}]\n"
       "outputs: {reaction_sets: [top]}\n";
  return s.str();
}

}  // namespace pba::testing
