// Solving a resolved problem (scene/problem.h): the analysis it names, then
// the results every analysis shares.
#pragma once

#include "core/phase_clock.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

// Refuses a body its conditions leave free to move (kFailedPrecondition,
// but for EXPLICIT_DYNAMIC, where inertia holds it), runs the analysis and
// fills `solution`: the element fields and the analysis's summary, then the
// nodal displacement, reactions, structure displacements, maxima, profiles
// and the wall time. `clock` times the phases (its options carry progress
// and cancellation).
Status SolveProblem(const Problem& problem, PhaseClock* clock, Solution* solution);

// ResolveProblem, with the threads of `options` bounding every loop and
// library of the solve (core/thread_context.h; no OpenMP state is set for
// good), and the model-build options (the atlas mesh cache) they give.
Status ResolveForSolve(const SceneSpec& scene, const SolveOptions& options, Problem* problem,
                       BuildModelOptions* build);

}  // namespace pba
