// The solver's front door (pba/solve.h): a scene is validated and resolved
// into a Problem (scene/problem.h), meshed, and handed to SolveProblem;
// `formulation: AUTO` goes through SolveAuto first, `mesh.adapt` through
// SolveAdaptive (both call back here or share its steps). Nothing past
// these files reads the scene.
#include "api/adaptive_solve.h"
#include "api/auto_formulation.h"
#include "api/solve_problem.h"
#include "core/phase_clock.h"
#include "core/thread_context.h"
#include "linear/petsc_runtime.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

Status JoinRanks(SolveRanks* ranks) {
  ProcessRanks process;
  PBA_RETURN_IF_ERROR(StartRanks(&process));
  *ranks = {process.rank, process.size, process.on_node};
  return Status::Ok();
}

void EndRanksWith(int code) { AbortOtherRanks(code); }

Status SolveScene(const SceneSpec& scene, const SolveOptions& options, Solution* solution) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  if (!options.restart_from.empty() && scene.analysis.type != AnalysisSpec::Type::kQuasiStatic) {
    return Status::InvalidArgument("restart_from",
                                   "only a QUASI_STATIC analysis restarts from a checkpoint");
  }
  if (scene.formulation == Formulation::kAuto) return SolveAuto(scene, options, solution);
  if (scene.mesh.adapt.enabled()) {
    if (!options.restart_from.empty()) {
      return Status::InvalidArgument("restart_from",
                                     "a scene with mesh.adapt does not restart from a "
                                     "checkpoint: each cycle solves anew on its own mesh");
    }
    return SolveAdaptive(scene, options, solution);
  }
  *solution = Solution();
  PhaseClock clock(options, &solution->summary.phases);

  Problem problem;
  BuildModelOptions build;
  PBA_RETURN_IF_ERROR(ResolveForSolve(scene, options, &problem, &build));
  clock.Begin("mesh", 0.0, 0.05, "meshing the " + problem.geometry);
  {
    // The mesh phase runs CGAL and the atlas code, which do not take a
    // context.
    const LibraryThreadScope bounded(problem.threads);
    PBA_RETURN_IF_ERROR(BuildProblemModel(scene, build, &problem));
  }
  clock.End();
  if (clock.cancelled()) return Status::Cancelled("cancelled during mesh");
  return SolveProblem(problem, &clock, solution);
}

}  // namespace pba
