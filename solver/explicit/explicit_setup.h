// What the explicit analyses (EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION) make of
// a problem before their time loop: the TLED elements with every element's
// material, the prescribed motion of every unknown and the loads.
#pragma once

#include <memory>
#include <vector>

#include "assembly/external_loads.h"
#include "explicit/tled_model.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

// How one unknown moves: free, or its displacement [m] or velocity [m/s]
// at a(t) = 1 prescribed (times a(t)).
struct PrescribedDof {
  enum Kind : char { kFree, kDisplacement, kVelocity };
  Kind kind = kFree;
  double value = 0;
};

struct ExplicitSetup {
  std::unique_ptr<TledModel> tled;
  TledOptions options;
  std::vector<PrescribedDof> prescribed;  // 3 per node
  std::unique_ptr<ExternalLoads> loads;   // pressure, traction, gravity at a(t) = 1
  bool has_loads = false;
  double time_step_factor = ExplicitOptions::kTimeStepFactor;
};

// Builds the setup of a problem. DYNAMIC_RELAXATION takes the instantaneous
// elastic materials (its options carry no bulk viscosity). What the engine
// cannot take (10-node elements, full hexahedra, growth) the scene's
// validation refuses; reaching it here is an internal error.
Status MakeExplicitSetup(const Problem& problem, ExplicitSetup* out);

}  // namespace pba
