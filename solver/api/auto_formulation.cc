// formulation: AUTO (pba/scene.h, scene/formulation.h): decide what to
// reduce, measure what the reduction costs from coarse runs of the reduced
// and the full model, and solve the reduced scene only when that is within
// formulation_tolerance; otherwise the scene as written.
#include "api/auto_formulation.h"

#include <algorithm>
#include <cmath>

#include "core/format.h"
#include "scene/formulation.h"

namespace pba {
namespace {

// The largest strain of a solution: its components as a tensor (the shear
// entries are engineering strains, twice the tensor's).
double LargestStrain(const Solution& solution) {
  double largest = 0;
  for (std::size_t i = 0; i < solution.strain.size(); ++i) {
    const double scale = i % 6 < 3 ? 1.0 : 0.5;
    largest = std::max(largest, scale * std::abs(solution.strain[i]));
  }
  return largest;
}

}  // namespace

Status SolveAuto(const SceneSpec& scene, const SolveOptions& options, Solution* solution) {
  SceneSpec full = scene;
  full.formulation = Formulation::kAsWritten;
  full.formulation_tolerance = 0;  // read below, from `scene`
  SceneSpec reduced = full;
  std::vector<ModelDecision> decisions;
  ReduceViscoelasticity(full, &reduced, &decisions);
  ReduceStructures(full, &reduced, &decisions);

  // Side runs report no progress of their own (the job's progress is the
  // final solve's) but stop when asked to; checkpoints and restarts are
  // the final solve's alone.
  SolveOptions side = options;
  side.progress = nullptr;
  side.checkpoint_dir.clear();
  side.restart_from.clear();
  std::vector<PhaseTime> side_phases;
  std::optional<double> strain;
  if (full.analysis.type == AnalysisSpec::Type::kNonlinearStatic &&
      FiniteStrainRequiredBy(full).empty()) {
    Solution cheap;
    const Status status = SolveScene(CheapStrainScene(reduced), side, &cheap);
    if (status.code() == Status::Code::kCancelled) return status;
    if (status.ok()) {
      strain = LargestStrain(cheap);
      side_phases.push_back({"auto: strain check", cheap.summary.wall_time_s});
    } else {
      decisions.push_back({"finite strain", "kept",
                           "the cheap linear solve failed (" + status.message() + ")", false});
    }
  }
  ReduceFiniteStrain(full, strain, &reduced, &decisions);

  const AutoFormulationOptions auto_options = AutoFormulationOptions::FromScene(scene);
  const bool reduces = std::any_of(decisions.begin(), decisions.end(),
                                   [](const ModelDecision& d) { return d.reduces; });
  // What the reduction costs, measured before anything is kept: the reduced
  // and the full scene on meshes twice as coarse.
  ReductionEstimate estimate;
  estimate.tolerance = auto_options.tolerance;
  if (!reduces) {
    estimate.note = "nothing was reduced: the scene's own model was solved";
  } else {
    Solution coarse_reduced, coarse_full;
    Status status = SolveScene(Coarsened(reduced), side, &coarse_reduced);
    if (status.ok()) status = SolveScene(Coarsened(full), side, &coarse_full);
    if (status.code() == Status::Code::kCancelled) return status;
    if (!status.ok()) {
      estimate.note =
          "the reduction could not be checked (a coarse run failed: " + status.message() +
          "), so the scene was solved as written";
    } else {
      estimate.estimated = true;
      estimate.relative_difference = LargestRelativeDifference(
          coarse_full.summary, coarse_reduced.summary, &estimate.quantity);
      estimate.reduced_coarse_s = coarse_reduced.summary.wall_time_s;
      estimate.full_coarse_s = coarse_full.summary.wall_time_s;
      estimate.kept = estimate.relative_difference <= auto_options.tolerance;
      const std::string measured =
          (estimate.quantity.empty()
               ? std::string("on meshes twice as coarse no shared result of the reduced model "
                             "differs from the full one's")
               : Format("on meshes twice as coarse the reduced model differs from the full one "
                        "by %.3g %% (%s)",
                        100 * estimate.relative_difference, estimate.quantity.c_str())) +
          Format(" and took %.3g s against %.3g s", estimate.reduced_coarse_s,
                 estimate.full_coarse_s);
      estimate.note =
          measured + (estimate.kept
                          ? Format("; within the tolerance of %g %%, the reduced model was solved",
                                   100 * auto_options.tolerance)
                          : Format("; beyond the tolerance of %g %% (formulation_tolerance), the "
                                   "scene was solved as written",
                                   100 * auto_options.tolerance));
      side_phases.push_back({"auto: coarse reduced", estimate.reduced_coarse_s});
      side_phases.push_back({"auto: coarse full", estimate.full_coarse_s});
    }
    if (!estimate.kept) {
      // The decisions stand as proposals that were not taken.
      for (ModelDecision& d : decisions) {
        if (!d.reduces) continue;
        d.decision = "as written (proposed: " + d.decision + ")";
        d.reduces = false;
      }
    }
  }

  PBA_RETURN_IF_ERROR(SolveScene(estimate.kept ? reduced : full, options, solution));
  Summary& summary = solution->summary;
  summary.decisions = decisions;
  summary.reduction = estimate;
  summary.options.emplace_back("formulation_tolerance", Format("%g", auto_options.tolerance));
  for (const PhaseTime& p : side_phases) {
    summary.phases.push_back(p);
    summary.wall_time_s += p.seconds;
  }
  for (const ModelDecision& d : decisions) {
    summary.notes.push_back("auto: " + d.aspect + ": " + d.decision + " (" + d.reason + ")");
  }
  summary.notes.push_back("auto: " + summary.reduction.note);
  return Status::Ok();
}

}  // namespace pba
