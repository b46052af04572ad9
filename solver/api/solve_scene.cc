// The solver's front door (pba/solve.h): a scene is validated and resolved
// into a Problem (scene/problem.h), meshed, and handed to SolveProblem;
// `formulation: AUTO` goes through SolveAuto first. Nothing past this file
// reads the scene.
#include <omp.h>

#include "analysis/solve_problem.h"
#include "api/auto_formulation.h"
#include "core/phase_clock.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

const char* SolverVersion() { return PBA_VERSION; }

Status SolveScene(const SceneSpec& scene, const SolveOptions& options, Solution* solution) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  if (!options.restart_from.empty() && scene.analysis.type != AnalysisSpec::Type::kQuasiStatic) {
    return Status::InvalidArgument("restart_from",
                                   "only a QUASI_STATIC analysis restarts from a checkpoint");
  }
  if (scene.formulation == Formulation::kAuto) return SolveAuto(scene, options, solution);
  if (options.threads > 0) omp_set_num_threads(options.threads);
  // CHOLMOD's supernodal factorisation asks OpenMP for a fixed team of 4
  // threads (its compile-time default); on fewer cores that oversubscribes
  // and the factorisations of a Newton solve spend their time waking
  // threads. Dynamic teams let the runtime give it what the machine has.
  // The explicit analyses have no factorisation, and a dynamic team would
  // shrink to one thread as soon as the solve itself loads the machine.
  const bool explicit_engine = scene.analysis.type == AnalysisSpec::Type::kExplicitDynamic ||
                               scene.analysis.type == AnalysisSpec::Type::kDynamicRelaxation;
  omp_set_dynamic(explicit_engine ? 0 : 1);
  *solution = Solution();
  PhaseClock clock(options, &solution->summary.phases);

  Problem problem;
  PBA_RETURN_IF_ERROR(ResolveProblem(scene, &problem));
  clock.Begin("mesh", 0.0, 0.05, "meshing the " + problem.geometry);
  BuildModelOptions build;
  build.atlas_cache_dir = options.atlas_cache_dir;
  build.atlas_cache_max_bytes = options.atlas_cache_max_bytes;
  PBA_RETURN_IF_ERROR(BuildProblemModel(scene, build, &problem));
  clock.End();
  if (clock.cancelled()) return Status::Cancelled("cancelled during mesh");
  return SolveProblem(problem, &clock, solution);
}

}  // namespace pba
