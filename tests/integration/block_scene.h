// A linear block on 1 mm elements, held at the bottom and pushed 1 mm down
// at the top: the tests' long-running solve. At 50 mm it has about 400k
// unknowns (tens of seconds of factorisation or conjugate gradients on two
// cores), at 30 mm about 85k (a few seconds, 880 MB): time to cancel it or
// kill its process.
#pragma once

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

}  // namespace pba::testing
