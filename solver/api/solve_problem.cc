// SolveProblem: the free-body check, the dispatch to the analysis, then
// the results every analysis shares (nodal fields, reactions, maxima,
// profiles, timing).
#include "api/solve_problem.h"

#include <algorithm>
#include <cstdio>

#include "analysis/profiles.h"
#include "analysis/rigid_modes.h"
#include "analysis/static_analysis.h"
#include "analysis/time_history.h"
#include "core/format.h"
#include "explicit/dynamic_relaxation.h"
#include "explicit/explicit_dynamics.h"
#include "fem/element_kind.h"
#include "linear/petsc_runtime.h"
#include "material/factory.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;

// The element the summary names: the explicit engine's own one-point forms.
std::string ElementSummaryName(const Problem& problem) {
  const bool engine = problem.analysis == AnalysisSpec::Type::kExplicitDynamic ||
                      problem.analysis == AnalysisSpec::Type::kDynamicRelaxation;
  return engine ? KindOf(problem.element).explicit_form : ElementName(problem.element);
}

// Above this bulk over shear modulus an element with a volume constraint
// per integration point locks: it answers far too stiff (K / mu = 1e7,
// nu = 0.4999999, made plain TET4 7,700 times too stiff). The tissue
// library's entries sit at 1e3 (material/tissue_library.cc).
constexpr double kLockingBulkOverShear = 1e3;

// A warning for the summary when an element that locks when nearly
// incompressible meets a material that is; empty otherwise.
std::string LockingNote(const Problem& problem) {
  // The element as resolved (ResolvedElement): never kDefault here. TET10
  // locks less than TET4 but still does at K / mu = 1e6 (tet10_model.h).
  const ElementType element = problem.element;
  if (!Locks(KindOf(element))) return "";
  double worst = 0;
  std::string label;
  const SceneMaterials& materials = problem.model.materials;
  for (std::size_t k = 0; k < materials.specs.size(); ++k) {
    const MaterialSpec& m = materials.specs[k];
    if (m.kind == MaterialSpec::Kind::kOrthotropicElastic || m.kind == MaterialSpec::Kind::kNone) {
      continue;  // no single K / mu
    }
    const double nu = InitialElasticModuli(m).poissons_ratio;
    const double ratio = 2 * (1 + nu) / (3 * (1 - 2 * nu));  // K / mu of (E, nu)
    if (ratio > worst) worst = ratio, label = materials.labels[k];
  }
  if (!(worst > kLockingBulkOverShear)) return "";
  const bool linear = problem.analysis == AnalysisSpec::Type::kLinearStatic;
  return Format(
      "warning: %s locks when nearly incompressible, and %s has K / mu = %.3g (over %g): the "
      "answer can be far too stiff (displacements too small, stresses wrong). Elements that do "
      "not lock: %s",
      ElementName(element), label.c_str(), worst, kLockingBulkOverShear,
      linear ? "HEX8 (mean dilatation) on a primitive, or TET4_ANP and TET10_MD with "
               "analysis.type NONLINEAR_STATIC"
             : "TET4_ANP, TET10_MD and HEX8 (mean dilatation, primitives only)");
}

}  // namespace

Status ResolveForSolve(const SceneSpec& scene, const SolveOptions& options, Problem* problem,
                       BuildModelOptions* build) {
  PBA_RETURN_IF_ERROR(ResolveProblem(scene, problem));
  problem->threads = ThreadContext(options.threads);
  problem->linear_solver.threads = problem->threads;
  *build = BuildModelOptions();
  build->atlas_cache_dir = options.atlas_cache_dir;
  build->atlas_cache_max_bytes = options.atlas_cache_max_bytes;
  return Status::Ok();
}

Status SolveProblem(const Problem& problem, PhaseClock* clock, Solution* solution) {
  Summary& summary = solution->summary;
  const Model& model = problem.model;
  const Mesh& mesh = model.mesh;
  const DofMap& dofs = model.dofs;
  // A body in motion need not be held.
  const bool dynamic = problem.analysis == AnalysisSpec::Type::kExplicitDynamic;
  const std::string free_modes = dynamic ? "" : DescribeFreeRigidModes(mesh, dofs);
  if (!free_modes.empty()) {
    return Status::FailedPrecondition("the boundary conditions leave the body free to move: " +
                                      free_modes + "; hold it with further conditions");
  }
  const std::string loose = dynamic ? "" : DescribeLoosePieces(mesh, dofs);
  if (!loose.empty()) {
    return Status::FailedPrecondition(
        loose +
        ". A piece nothing holds makes the stiffness singular; hold it, leave its structures out "
        "(geometry.atlas.structures), or mesh so that it joins the rest by faces");
  }
  summary.scene_name = problem.name;
  summary.geometry = problem.geometry;
  summary.element_type = ElementSummaryName(problem);
  summary.nodes = mesh.num_nodes();
  summary.elements = mesh.num_elements();
  summary.dofs = dofs.num_free();
  summary.constrained_dofs = dofs.num_dofs() - dofs.num_free();
  const MaterialSpec& material = model.materials.specs[0];
  summary.material = model.materials.labels[0] + ": " + DescribeMaterial(material);
  summary.options = EffectiveOptions(problem);
  summary.notes.push_back("mesh: " + model.mesh_description +
                          Format(" (element size %g mm)", problem.element_size_m / kMm));
  if (const std::string note = LockingNote(problem); !note.empty()) summary.notes.push_back(note);

  StaticResult result;
  switch (problem.analysis) {
    case AnalysisSpec::Type::kLinearStatic:
      PBA_RETURN_IF_ERROR(SolveLinearStatic(problem, clock, solution, &result));
      break;
    case AnalysisSpec::Type::kNonlinearStatic:
      PBA_RETURN_IF_ERROR(SolveNonlinearStatic(problem, clock, solution, &result));
      break;
    case AnalysisSpec::Type::kQuasiStatic:
      PBA_RETURN_IF_ERROR(SolveQuasiStatic(problem, clock, solution, &result));
      break;
    case AnalysisSpec::Type::kExplicitDynamic:
      PBA_RETURN_IF_ERROR(SolveExplicitDynamic(problem, clock, solution, &result));
      break;
    case AnalysisSpec::Type::kDynamicRelaxation:
      PBA_RETURN_IF_ERROR(SolveDynamicRelaxation(problem, clock, solution, &result));
      break;
  }

  for (const std::string& name : problem.outputs.reaction_sets) {
    Reaction reaction{name, {0, 0, 0}};
    for (int node : mesh.face_sets.at(name).nodes) {
      for (int c = 0; c < 3; ++c) {
        reaction.force_n[c] += result.internal_force(3 * node + c);
        if (result.external_force.size() > 0) {
          reaction.force_n[c] -= result.external_force(3 * node + c);
        }
      }
    }
    summary.reactions.push_back(reaction);
  }

  const StructureProbe structures(problem.outputs.structure_displacements, mesh);
  for (std::size_t i = 0; i < structures.size(); ++i) {
    summary.structure_displacements.push_back(structures.Measure(i, result.u));
  }

  // Fields in the units of result.h5: mm for lengths and displacements.
  const int n = mesh.num_nodes(), ne = mesh.num_elements();
  solution->nodes_mm.resize(3 * static_cast<std::size_t>(n));
  solution->displacement_mm.resize(3 * static_cast<std::size_t>(n));
  int max_node = 0;
  double max_u = -1;
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      solution->nodes_mm[3 * i + c] = mesh.nodes(i, c) / kMm;
      solution->displacement_mm[3 * i + c] = result.u(3 * i + c) / kMm;
    }
    const double norm = result.u.segment<3>(3 * i).norm();
    if (norm > max_u) max_u = norm, max_node = i;
  }
  const int per_element = ShapeInfo(mesh.shape()).nodes;
  solution->nodes_per_element = per_element;
  solution->tets.resize(per_element * static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) {
    const NodeList nodes = mesh.ElementNodes(e);
    std::copy(nodes.begin(), nodes.end(), solution->tets.begin() + per_element * e);
  }
  solution->region_names = mesh.region_names;
  solution->element_region.assign(mesh.element_region.begin(), mesh.element_region.end());
  summary.max_displacement_mm = max_u / kMm;
  for (int c = 0; c < 3; ++c) summary.max_displacement_at_mm[c] = mesh.nodes(max_node, c) / kMm;
  summary.max_von_mises_pa =
      solution->von_mises_pa.empty()
          ? 0
          : *std::max_element(solution->von_mises_pa.begin(), solution->von_mises_pa.end());
  summary.strain_energy_j = result.strain_energy_j;

  // Line profiles, from the fields just filled in.
  PBA_RETURN_IF_ERROR(SampleProfiles(problem.outputs.profiles, *solution, &solution->profiles));
  summary.profiles = SummariseProfiles(solution->profiles);
  for (const ProfileSummary& profile : summary.profiles) {
    if (profile.inside == profile.points) continue;
    summary.notes.push_back(Format(
        "profile %s: %d of its %d points lie outside the body (reference configuration); their "
        "values in profile_%s.csv are empty",
        profile.name.c_str(), profile.points - profile.inside, profile.points,
        profile.name.c_str()));
  }
  summary.threads = problem.threads.threads();
  summary.ranks = CurrentRanks().size;
  summary.wall_time_s = clock->elapsed_s();
  return Status::Ok();
}

}  // namespace pba
