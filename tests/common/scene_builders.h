// Small builders for SceneSpec in tests and benchmarks.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "pba/scene.h"

namespace pba::testing {

// A boundary condition on face set `set`; `value` holds the prescribed
// displacement components [mm] of a kDisplacement condition.
inline BoundaryConditionSpec Condition(const std::string& set, BoundaryConditionSpec::Kind kind,
                                       std::array<std::optional<double>, 3> value = {}) {
  BoundaryConditionSpec bc;
  bc.set = set;
  bc.kind = kind;
  bc.displacement_mm = value;
  return bc;
}

}  // namespace pba::testing
