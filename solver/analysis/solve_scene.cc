// SolveScene: validate, mesh, hold, dispatch to the analysis, then the
// results every analysis shares (nodal fields, reactions, maxima, timing).
#include <omp.h>

#include <algorithm>
#include <cstdio>

#include "analysis/auto_formulation.h"
#include "analysis/profiles.h"
#include "analysis/rigid_modes.h"
#include "analysis/static_analysis.h"
#include "analysis/time_history.h"
#include "atlas/structure_set.h"
#include "core/format.h"
#include "explicit/dynamic_relaxation.h"
#include "explicit/explicit_dynamics.h"
#include "material/factory.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;

std::string DescribeGeometry(const GeometrySpec& g) {
  if (g.kind == GeometrySpec::Kind::kBox) {
    return Format("box %g x %g x %g mm", g.box.size_mm[0], g.box.size_mm[1], g.box.size_mm[2]);
  }
  if (g.kind == GeometrySpec::Kind::kSphericalShell) {
    return Format("spherical shell octant, radii %g and %g mm", g.spherical_shell.inner_radius_mm,
                  g.spherical_shell.outer_radius_mm);
  }
  if (g.kind == GeometrySpec::Kind::kAtlas) {
    const std::string& source = g.atlas.source;
    if (source.empty() || source == "synthetic") return "synthetic atlas";
    // A snapshot of the atlas store (staged by the server, or exported) is
    // named as such: the staging path means nothing to the reader.
    StructureSet set;
    if (IsStructureSetDir(source) && ReadStructureSet(source, &set).ok() && !set.project.empty() &&
        set.snapshot > 0) {
      return Format("atlas of snapshot %lld of project %s (%zu structures)",
                    static_cast<long long>(set.snapshot), set.project.c_str(),
                    set.structures.size());
    }
    return "atlas from " + source;
  }
  if (g.kind == GeometrySpec::Kind::kEllipsoid) {
    return Format("ellipsoid, semi-axes %g, %g and %g mm", g.ellipsoid.semi_axes_mm[0],
                  g.ellipsoid.semi_axes_mm[1], g.ellipsoid.semi_axes_mm[2]);
  }
  return Format("cylinder r = %g mm, h = %g mm", g.cylinder.radius_mm, g.cylinder.height_mm);
}

// The element of the explicit engine (explicit/tled_model.h).
std::string ExplicitElementName(const SceneSpec& scene, const Mesh& mesh) {
  if (mesh.hexahedral()) return "HEX8 (one point, hourglass control)";
  return scene.mesh.element == ElementType::kTet4 ? "TET4" : "TET4_ANP";
}

}  // namespace

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
  Summary& summary = solution->summary;
  PhaseClock clock(options, &summary.phases);

  clock.Begin("mesh", 0.0, 0.05, "meshing the " + DescribeGeometry(scene.geometry));
  Model model;
  BuildModelOptions build;
  build.atlas_cache_dir = options.atlas_cache_dir;
  build.atlas_cache_max_bytes = options.atlas_cache_max_bytes;
  PBA_RETURN_IF_ERROR(BuildModel(scene, &model, build));
  const Mesh& mesh = model.mesh;
  const DofMap& dofs = model.dofs;
  // A body in motion need not be held.
  const bool dynamic = scene.analysis.type == AnalysisSpec::Type::kExplicitDynamic;
  const std::string free_modes = dynamic ? "" : DescribeFreeRigidModes(mesh, dofs);
  if (!free_modes.empty()) {
    return Status::FailedPrecondition("the boundary conditions leave the body free to move: " +
                                      free_modes + "; hold it with further conditions");
  }
  clock.End();
  if (clock.cancelled()) return Status::Cancelled("cancelled during mesh");

  summary.scene_name = scene.name;
  summary.geometry = DescribeGeometry(scene.geometry);
  // A nonlinear analysis may refine this.
  summary.element_type =
      mesh.quadratic()    ? (scene.mesh.element == ElementType::kTet10Md ? "TET10_MD" : "TET10")
      : mesh.hexahedral() ? (scene.mesh.element == ElementType::kHex8Full ? "HEX8_FULL" : "HEX8")
                          : "TET4";
  summary.nodes = mesh.num_nodes();
  summary.elements = mesh.num_elements();
  summary.dofs = dofs.num_free();
  summary.constrained_dofs = dofs.num_dofs() - dofs.num_free();
  summary.material = (scene.material.name.empty() ? std::string("material") : scene.material.name) +
                     ": " + DescribeMaterial(scene.material);
  summary.notes.push_back(
      "mesh: " + model.mesh_description +
      Format(" (element size %g mm)", EffectiveElementSize(scene.geometry, scene.mesh)));

  StaticResult result;
  switch (scene.analysis.type) {
    case AnalysisSpec::Type::kLinearStatic:
      PBA_RETURN_IF_ERROR(SolveLinearStatic(scene, model, &clock, solution, &result));
      break;
    case AnalysisSpec::Type::kNonlinearStatic:
      PBA_RETURN_IF_ERROR(SolveNonlinearStatic(scene, model, &clock, solution, &result));
      break;
    case AnalysisSpec::Type::kQuasiStatic:
      PBA_RETURN_IF_ERROR(SolveQuasiStatic(scene, model, &clock, solution, &result));
      break;
    case AnalysisSpec::Type::kExplicitDynamic:
      summary.element_type = ExplicitElementName(scene, mesh);
      PBA_RETURN_IF_ERROR(SolveExplicitDynamic(scene, model, &clock, solution, &result));
      break;
    case AnalysisSpec::Type::kDynamicRelaxation:
      summary.element_type = ExplicitElementName(scene, mesh);
      PBA_RETURN_IF_ERROR(SolveDynamicRelaxation(scene, model, &clock, solution, &result));
      break;
  }

  for (const std::string& name : ReactionSetNames(scene)) {
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

  const StructureProbe structures(scene.outputs.structure_displacements, mesh);
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
  const int per_element = mesh.quadratic() ? 10 : mesh.hexahedral() ? 8 : 4;
  solution->nodes_per_element = per_element;
  solution->tets.resize(per_element * static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) {
    if (mesh.hexahedral()) {
      for (int a = 0; a < 8; ++a) solution->tets[8 * e + a] = mesh.hexes[e][a];
      continue;
    }
    for (int a = 0; a < 4; ++a) solution->tets[per_element * e + a] = mesh.tets[e][a];
    if (mesh.quadratic()) {
      for (int k = 0; k < 6; ++k) solution->tets[10 * e + 4 + k] = mesh.midside[e][k];
    }
  }
  summary.max_displacement_mm = max_u / kMm;
  for (int c = 0; c < 3; ++c) summary.max_displacement_at_mm[c] = mesh.nodes(max_node, c) / kMm;
  summary.max_von_mises_pa =
      solution->von_mises_pa.empty()
          ? 0
          : *std::max_element(solution->von_mises_pa.begin(), solution->von_mises_pa.end());
  summary.strain_energy_j = result.strain_energy_j;

  // Line profiles, from the fields just filled in.
  PBA_RETURN_IF_ERROR(SampleProfiles(scene, *solution, &solution->profiles));
  summary.profiles = SummariseProfiles(solution->profiles);
  for (const ProfileSummary& profile : summary.profiles) {
    if (profile.inside == profile.points) continue;
    summary.notes.push_back(Format(
        "profile %s: %d of its %d points lie outside the body (reference configuration); their "
        "values in profile_%s.csv are empty",
        profile.name.c_str(), profile.points - profile.inside, profile.points,
        profile.name.c_str()));
  }
  summary.threads = omp_get_max_threads();
  summary.wall_time_s = clock.elapsed_s();
  return Status::Ok();
}

}  // namespace pba
