// Solving a scene with `formulation: AUTO`: the reduced scene of
// scene/formulation.h, its decisions and the estimate of what it costs in
// accuracy, in the solution's summary.
#pragma once

#include "pba/solve.h"

namespace pba {

Status SolveAuto(const SceneSpec& scene, const SolveOptions& options, Solution* solution);

}  // namespace pba
