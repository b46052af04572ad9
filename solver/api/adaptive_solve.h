// Solving a scene with `mesh.adapt` (pba/scene.h, AdaptSpec): solve,
// estimate each element's error, bisect the elements that carry the
// largest share of it (mesh/refine.h), and solve again on the refined mesh,
// until the estimate is within the target, another refinement would pass
// max_elements, or max_cycles solves have run. Every cycle solves the whole
// scene from the start (its steps, contacts and relaxation), on a mesh that
// keeps the coarser one's nodes. The solution is the last cycle's, with
// each cycle in Summary::adaptation; when the target is not reached the
// summary says so in a warning.
#pragma once

#include "pba/solve.h"

namespace pba {

Status SolveAdaptive(const SceneSpec& scene, const SolveOptions& options, Solution* solution);

}  // namespace pba
