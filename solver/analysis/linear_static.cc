// SolveScene for LINEAR_STATIC: small-strain linear elasticity on linear
// tetrahedra, K_ff u_f = f_f - K_fp u_p, with a Zienkiewicz-Zhu error estimate.
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <set>

#include "analysis/error_estimator.h"
#include "analysis/rigid_modes.h"
#include "assembly/assembler.h"
#include "core/phase_clock.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "mesh/primitive_mesher.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;
// Beyond this strain the small-strain answer is no longer a fair model of
// soft tissue, which has no linear range (DOMAIN.md section 2).
constexpr double kSmallStrainLimit = 0.05;

std::string Format(const char* format, auto... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

std::string DescribeGeometry(const GeometrySpec& g) {
  if (g.kind == GeometrySpec::Kind::kBox) {
    return Format("box %g x %g x %g mm", g.box.size_mm[0], g.box.size_mm[1], g.box.size_mm[2]);
  }
  return Format("cylinder r = %g mm, h = %g mm", g.cylinder.radius_mm, g.cylinder.height_mm);
}

}  // namespace

const char* SolverVersion() { return PBA_VERSION; }

Status SolveScene(const SceneSpec& scene, const SolveOptions& options, Solution* solution) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  if (options.threads > 0) omp_set_num_threads(options.threads);
  *solution = Solution();
  Summary& summary = solution->summary;
  PhaseClock clock(options, &summary.phases);
  auto cancelled = [&] {
    return Status::Cancelled("cancelled during " + summary.phases.back().phase);
  };

  clock.Begin("mesh", 0.0, 0.05, "meshing the " + DescribeGeometry(scene.geometry));
  const Model model = BuildModel(scene);
  const Mesh& mesh = model.mesh;
  const DofMap& dofs = model.dofs;
  const std::string free_modes = DescribeFreeRigidModes(mesh, dofs);
  if (!free_modes.empty()) {
    return Status::FailedPrecondition("the boundary conditions leave the body free to move: " +
                                      free_modes + "; hold it with further conditions");
  }
  clock.End();
  if (clock.cancelled()) return cancelled();

  const LinearElasticParams& p = scene.material.linear_elastic;
  const Matrix6d d = IsotropicElasticity(p.youngs_modulus_pa, p.poissons_ratio);
  clock.Begin("assemble", 0.05, 0.25,
              Format("assembling %d elements, %d unknowns", mesh.num_elements(), dofs.num_free()));
  const auto colours = ColourElements(mesh);
  LinearSystem system;
  PBA_RETURN_IF_ERROR(AssembleLinearSystem(
      mesh, d, dofs, colours,
      [&](double f) {
        clock.Update(f);
        return !clock.cancelled();
      },
      &system));
  clock.End();

  const auto solver = CreateLinearSolver(scene.analysis.linear_solver);
  Eigen::VectorXd u_free;
  double residual = 0;
  if (dofs.num_free() > 0) {
    clock.Begin("factorize", 0.25, 0.75,
                Format("%s of %d unknowns, %lld stored entries", solver->Name().c_str(),
                       dofs.num_free(), static_cast<long long>(system.k.nonZeros())));
    PBA_RETURN_IF_ERROR(solver->Factorize(system.k));
    clock.End();
    if (clock.cancelled()) return cancelled();
    clock.Begin("solve", 0.75, 0.8, "forward and back substitution");
    PBA_RETURN_IF_ERROR(solver->Solve(system.rhs, &u_free));
    const double scale = system.rhs.norm();
    residual = (system.k * u_free - system.rhs).norm() / (scale > 0 ? scale : 1.0);
    clock.End();
  }
  if (clock.cancelled()) return cancelled();

  clock.Begin("recover", 0.8, 0.9, "element strain and stress, reactions");
  Eigen::VectorXd u(dofs.num_dofs());
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    u(dof) = dofs.prescribed(dof) ? dofs.prescribed_value(dof) : u_free(dofs.free_index(dof));
  }
  const int ne = mesh.num_elements();
  solution->strain.resize(6 * static_cast<std::size_t>(ne));
  solution->stress_pa.resize(6 * static_cast<std::size_t>(ne));
  solution->von_mises_pa.resize(ne);
  std::vector<double> volume(ne);
  Eigen::VectorXd internal = Eigen::VectorXd::Zero(dofs.num_dofs());
  double energy = 0, max_strain = 0;
  for (const auto& colour : colours) {
#pragma omp parallel for reduction(+ : energy) reduction(max : max_strain) schedule(static)
    for (std::size_t k = 0; k < colour.size(); ++k) {
      const int e = colour[k];
      const Tet4Geometry g = ComputeTet4Geometry(TetCorners(mesh, e));
      const BMatrix b = StrainDisplacement(g);
      const Vector6d strain = b * GatherElement(mesh, e, u);
      const Vector6d stress = d * strain;
      Eigen::Map<Vector6d>(&solution->strain[6 * e]) = strain;
      Eigen::Map<Vector6d>(&solution->stress_pa[6 * e]) = stress;
      solution->von_mises_pa[e] = VonMises(stress);
      volume[e] = g.volume;
      energy += 0.5 * g.volume * stress.dot(strain);
      max_strain = std::max(max_strain, strain.cwiseAbs().maxCoeff());
      const Vector12d force = g.volume * b.transpose() * stress;
      for (int a = 0; a < 4; ++a)
        internal.segment<3>(3 * mesh.tets[e][a]) += force.segment<3>(3 * a);
    }
  }
  for (const std::string& name : ReactionSetNames(scene)) {
    Reaction reaction{name, {0, 0, 0}};
    for (int node : mesh.face_sets.at(name).nodes) {
      for (int c = 0; c < 3; ++c) reaction.force_n[c] += internal(3 * node + c);
    }
    summary.reactions.push_back(reaction);
  }
  clock.End();

  clock.Begin("estimate", 0.9, 0.95, "Zienkiewicz-Zhu error estimate");
  const ErrorEstimateResult estimate =
      EstimateZzError(mesh, solution->stress_pa, volume,
                      IsotropicCompliance(p.youngs_modulus_pa, p.poissons_ratio));
  solution->error_indicator = estimate.element_share;
  summary.error.estimated = true;
  summary.error.method = "Zienkiewicz-Zhu stress recovery (nodal averaging)";
  summary.error.relative_error = estimate.relative_error;
  summary.error.note =
      "estimated discretisation error in the energy norm, relative to the solution's energy norm; "
      "refine the mesh (mesh.element_size_mm) to reduce it";
  clock.Update(1.0);
  clock.End();

  // Fields in the units of result.h5: mm for lengths and displacements.
  const int n = mesh.num_nodes();
  solution->nodes_mm.resize(3 * static_cast<std::size_t>(n));
  solution->displacement_mm.resize(3 * static_cast<std::size_t>(n));
  int max_node = 0;
  double max_u = -1;
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      solution->nodes_mm[3 * i + c] = mesh.nodes(i, c) / kMm;
      solution->displacement_mm[3 * i + c] = u(3 * i + c) / kMm;
    }
    const double norm = u.segment<3>(3 * i).norm();
    if (norm > max_u) max_u = norm, max_node = i;
  }
  solution->tets.resize(4 * static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) {
    for (int a = 0; a < 4; ++a) solution->tets[4 * e + a] = mesh.tets[e][a];
  }

  summary.scene_name = scene.name;
  summary.geometry = DescribeGeometry(scene.geometry);
  summary.element_type = "TET4";
  summary.nodes = n;
  summary.elements = ne;
  summary.dofs = dofs.num_free();
  summary.constrained_dofs = dofs.num_dofs() - dofs.num_free();
  summary.material =
      (scene.material.name.empty() ? std::string("material") : scene.material.name) +
      Format(": linear elastic, E = %g Pa, nu = %g", p.youngs_modulus_pa, p.poissons_ratio);
  summary.analysis = "linear static (small strain)";
  summary.linear_solver = solver->Name();
  summary.notes.push_back(
      "mesh: " + model.mesh_description +
      Format(" (element size %g mm)", EffectiveElementSize(scene.geometry, scene.mesh)));
  if (max_strain > kSmallStrainLimit) {
    summary.notes.push_back(
        Format("the largest strain component is %.1f %%: beyond a few percent small-strain linear "
               "elasticity "
               "misjudges soft tissue, which is nonlinear and nearly incompressible",
               100 * max_strain));
  }
  summary.max_displacement_mm = max_u / kMm;
  for (int c = 0; c < 3; ++c) summary.max_displacement_at_mm[c] = mesh.nodes(max_node, c) / kMm;
  summary.max_von_mises_pa =
      solution->von_mises_pa.empty()
          ? 0
          : *std::max_element(solution->von_mises_pa.begin(), solution->von_mises_pa.end());
  summary.strain_energy_j = energy;
  summary.relative_residual = residual;
  summary.threads = omp_get_max_threads();
  summary.wall_time_s = clock.elapsed_s();
  return Status::Ok();
}

}  // namespace pba
