#include "api/adaptive_solve.h"

#include <algorithm>
#include <cmath>

#include "api/solve_problem.h"
#include "core/format.h"
#include "core/phase_clock.h"
#include "core/thread_context.h"
#include "mesh/refine.h"
#include "scene/formulation.h"
#include "scene/problem.h"

namespace pba {
namespace {

// The mean edge length of the mesh's smallest element (by that measure)
// [m]: how fine the finest part of the mesh is.
double FinestMeanEdge(const Mesh& mesh) {
  double finest = INFINITY;
  for (const auto& t : mesh.tets) {
    double sum = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) sum += (mesh.nodes.row(t[a]) - mesh.nodes.row(t[b])).norm();
    finest = std::min(finest, sum / 6);
  }
  return finest;
}

// Each cycle bisects the marked elements three times: their edges halve,
// as in one uniform refinement, so a cycle is worth its solve.
constexpr int kBisectionsPerCycle = 3;

// The adaptation's bounds, defaults filled in.
Adaptation Bounds(const AdaptSpec& spec) {
  Adaptation a;
  a.adapted = true;
  a.target_error = spec.target_error_percent / 100;
  a.max_elements = spec.max_elements > 0 ? spec.max_elements : kDefaultAdaptMaxElements;
  a.max_cycles = spec.max_cycles > 0 ? spec.max_cycles : kDefaultAdaptCycles;
  a.refine_fraction = spec.refine_fraction > 0 ? spec.refine_fraction : kDefaultAdaptFraction;
  return a;
}

}  // namespace

Status SolveAdaptive(const SceneSpec& scene, const SolveOptions& options, Solution* solution) {
  Adaptation adaptation = Bounds(scene.mesh.adapt);
  Problem resolved;
  BuildModelOptions build;
  PBA_RETURN_IF_ERROR(ResolveForSolve(scene, options, &resolved, &build));

  BaseMesh base;
  double first_finest_edge = 0;
  Solution current;
  Summary previous;                // the cycle before's, for the change of its results
  std::vector<PhaseTime> earlier;  // a phase per cycle before the last
  double earlier_wall_s = 0;
  int refinements = 0;
  for (int cycle = 0;; ++cycle) {
    // Each cycle reports its progress within its share of the whole, and
    // writes no checkpoint: a restart would need the cycle's mesh.
    SolveOptions cycle_options = options;
    cycle_options.checkpoint_dir.clear();
    if (options.progress) {
      const double share = 1.0 / adaptation.max_cycles;
      cycle_options.progress = [&options, cycle, share](const ProgressEvent& event) {
        ProgressEvent scaled = event;
        scaled.fraction = share * (cycle + event.fraction);
        scaled.message = Format("mesh.adapt cycle %d: ", cycle + 1) + event.message;
        options.progress(scaled);
      };
    }
    current = Solution();
    PhaseClock clock(cycle_options, &current.summary.phases);
    clock.Begin("mesh", 0.0, 0.05,
                cycle == 0 ? "meshing the " + resolved.geometry
                           : Format("building the model on %d elements", base.mesh.num_elements()));
    Problem problem = resolved;
    {
      // CGAL and the atlas code do not take a context.
      const LibraryThreadScope bounded(resolved.threads);
      if (cycle == 0) {
        PBA_RETURN_IF_ERROR(BuildProblemBaseMesh(scene, build, &base));
        first_finest_edge = FinestMeanEdge(base.mesh);
      }
      PBA_RETURN_IF_ERROR(BuildProblemModelOn(scene, base, &problem));
    }
    // Contact penalties and tolerances stay those of the scene's own mesh
    // (ResolveProblem): every cycle solves the same problem, so the cycles
    // differ by their meshes alone.
    clock.End();
    if (clock.cancelled()) return Status::Cancelled("cancelled during mesh");
    const int elements = problem.model.mesh.num_elements();
    PBA_RETURN_IF_ERROR(
        SolveProblem(problem, &clock, &current)
            .WithContext(Format("mesh.adapt cycle %d (%d elements): ", cycle + 1, elements)));
    const Summary& summary = current.summary;
    if (!summary.error.estimated ||
        current.error_indicator.size() != static_cast<std::size_t>(base.mesh.num_elements())) {
      return Status::Internal(
          Format("mesh.adapt cycle %d: the solve gave no error estimate of "
                 "its %d elements (%s)",
                 cycle + 1, base.mesh.num_elements(), summary.error.note.c_str()));
    }
    AdaptCycle record;
    record.elements = summary.elements;
    record.nodes = summary.nodes;
    record.dofs = summary.dofs;
    record.relative_error = summary.error.relative_error;
    record.wall_time_s = summary.wall_time_s;
    if (cycle > 0) {
      record.change = LargestRelativeDifference(previous, summary, &record.changed_quantity);
    }
    adaptation.cycles.push_back(record);

    // Whether to go on, and the mesh to go on with.
    const double error = record.relative_error;
    if (error <= adaptation.target_error) {
      adaptation.reached = true;
      adaptation.stop_reason =
          Format("estimated error %.3g %% within the target of %g %% after %d solve%s", 100 * error,
                 100 * adaptation.target_error, cycle + 1, cycle == 0 ? "" : "s");
      break;
    }
    if (cycle + 1 >= adaptation.max_cycles) {
      adaptation.stop_reason = Format(
          "%d solves ran (mesh.adapt.max_cycles); the estimated error is %.3g %%, the "
          "target %g %%",
          cycle + 1, 100 * error, 100 * adaptation.target_error);
      break;
    }
    const std::vector<char> marked =
        MarkLargestShare(current.error_indicator, adaptation.refine_fraction);
    Mesh refined;
    RefineReport report;
    PBA_RETURN_IF_ERROR(RefineTetsRepeatedly(base.mesh, marked, kBisectionsPerCycle, &refined,
                                             &report, adaptation.max_elements));
    if (report.elements > adaptation.max_elements) {
      adaptation.stop_reason = Format(
          "refining again would give over %lld elements, more than mesh.adapt.max_elements "
          "(%lld); the estimated error is %.3g %%, the target %g %%",
          static_cast<long long>(report.elements), static_cast<long long>(adaptation.max_elements),
          100 * error, 100 * adaptation.target_error);
      break;
    }
    if (clock.cancelled()) return Status::Cancelled("cancelled between mesh.adapt cycles");
    adaptation.cycles.back().marked = report.marked;
    base.mesh = std::move(refined);
    ++refinements;
    earlier.push_back({Format("mesh.adapt: cycle %d", cycle + 1), summary.wall_time_s});
    earlier_wall_s += summary.wall_time_s;
    previous = current.summary;
  }

  *solution = std::move(current);
  Summary& summary = solution->summary;
  for (const PhaseTime& p : earlier) summary.phases.push_back(p);
  summary.wall_time_s += earlier_wall_s;
  if (refinements > 0) {
    summary.notes.push_back(Format(
        "mesh.adapt: the mesh was refined %d time%s by longest-edge bisection where the "
        "estimated error was largest, from %lld to %lld elements (finest elements' mean edge "
        "%.3g mm, from %.3g mm)",
        refinements, refinements == 1 ? "" : "s",
        static_cast<long long>(adaptation.cycles.front().elements),
        static_cast<long long>(adaptation.cycles.back().elements), FinestMeanEdge(base.mesh) * 1e3,
        first_finest_edge * 1e3));
  }
  if (!adaptation.reached) {
    summary.notes.push_back("warning: mesh.adapt did not reach its target: " +
                            adaptation.stop_reason);
  }
  if (!options.checkpoint_dir.empty()) {
    summary.notes.push_back(
        "mesh.adapt: no checkpoints were written (each cycle solves the scene anew on its own "
        "mesh)");
  }
  // The bounds as run, defaults included, beside the other options.
  summary.options.emplace_back("mesh.adapt.target_error_percent",
                               Format("%g %%", 100 * adaptation.target_error));
  summary.options.emplace_back("mesh.adapt.max_elements",
                               Format("%lld", static_cast<long long>(adaptation.max_elements)));
  summary.options.emplace_back("mesh.adapt.max_cycles", Format("%d", adaptation.max_cycles));
  summary.options.emplace_back("mesh.adapt.refine_fraction",
                               Format("%g", adaptation.refine_fraction));
  summary.adaptation = std::move(adaptation);
  return Status::Ok();
}

}  // namespace pba
