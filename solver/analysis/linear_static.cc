// LINEAR_STATIC: small-strain linear elasticity on 4- or 10-node tetrahedra
// or 8-node hexahedra (B-bar), K_ff u_f = f_f - K_fp u_p, with a
// Zienkiewicz-Zhu error estimate.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/error_estimator.h"
#include "analysis/static_analysis.h"
#include "assembly/assembler.h"
#include "core/format.h"
#include "fem/hex8.h"
#include "linear/linear_solver.h"
#include "material/factory.h"
#include "material/linear_elastic.h"
#include "mesh/quadratic.h"
#include "scene/materials.h"

namespace pba {
namespace {

// Beyond this strain the small-strain answer is no longer a fair model of
// soft tissue, which has no linear range (DOMAIN.md section 2).
constexpr double kSmallStrainLimit = 0.05;

// One element's recovered fields: the volume averages of its strain and
// stress over its integration points (exact values for the constant-strain
// tetrahedron; strain varies within a 10-node element or a brick).
struct ElementRecovery {
  Vector6d strain = Vector6d::Zero(), stress = Vector6d::Zero();
  double volume = 0, energy = 0, max_strain = 0;
};

// Recovers element fields from `points` integration points, point(q, &dv)
// giving B at point q and its share of volume dv, and adds the element's
// internal force B^T sigma dV to `internal` at `nodes` (elements of one
// colour share no node, so concurrent calls do not collide).
template <int N, typename PointB>
ElementRecovery RecoverElement(const std::array<int, N>& nodes,
                               const Eigen::Matrix<double, 3 * N, 1>& ue, int points,
                               const PointB& point, const Matrix6d& d, Eigen::VectorXd* internal) {
  ElementRecovery r;
  Eigen::Matrix<double, 3 * N, 1> force = Eigen::Matrix<double, 3 * N, 1>::Zero();
  for (int q = 0; q < points; ++q) {
    double dv = 0;
    const Eigen::Matrix<double, 6, 3 * N> b = point(q, &dv);
    const Vector6d strain = b * ue, stress = d * strain;
    r.strain += dv * strain;
    r.stress += dv * stress;
    force += dv * b.transpose() * stress;
    r.energy += 0.5 * dv * stress.dot(strain);
    r.max_strain = std::max(r.max_strain, strain.cwiseAbs().maxCoeff());
    r.volume += dv;
  }
  r.strain /= r.volume;
  r.stress /= r.volume;
  for (int a = 0; a < N; ++a)
    internal->template segment<3>(3 * nodes[a]) += force.template segment<3>(3 * a);
  return r;
}

}  // namespace

Status SolveLinearStatic(const Problem& problem, PhaseClock* clock_ptr, Solution* solution,
                         StaticResult* result) {
  PhaseClock& clock = *clock_ptr;
  const Model& model = problem.model;
  Summary& summary = solution->summary;
  const Mesh& mesh = model.mesh;
  const DofMap& dofs = model.dofs;
  auto cancelled = [&] {
    return Status::Cancelled("cancelled during " + summary.phases.back().phase);
  };
  // Each element's own material, in the global frame (an orthotropic
  // material's axes already applied).
  const ElasticityField elasticity = MakeElasticityField(model.materials);
  clock.Begin("assemble", 0.05, 0.25,
              Format("assembling %d elements, %d unknowns", mesh.num_elements(), dofs.num_free()));
  const auto colours = ColourElements(mesh);
  LinearSystem system;
  // Bricks with the plain B (full integration) instead of B-bar.
  const bool full_bricks = problem.element == ElementType::kHex8Full;
  const auto keep_going = [&](double f) {
    clock.Update(f);
    return !clock.cancelled();
  };
  PBA_RETURN_IF_ERROR(
      mesh.quadratic()
          ? AssembleLinearSystemTet10(mesh, elasticity, dofs, colours, keep_going, &system)
      : full_bricks
          ? AssembleLinearSystemHex8Full(mesh, elasticity, dofs, colours, keep_going, &system)
      : mesh.hexahedral()
          ? AssembleLinearSystemHex8(mesh, elasticity, dofs, colours, keep_going, &system)
          : AssembleLinearSystem(mesh, elasticity, dofs, colours, keep_going, &system));
  const ExternalLoads loads = BuildLoads(problem);
  Eigen::VectorXd external;
  if (!loads.empty()) {
    external = loads.Force(Eigen::VectorXd::Zero(dofs.num_dofs()));
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      const int f = dofs.free_index(dof);
      if (f >= 0) system.rhs(f) += external(dof);
    }
    const Eigen::Vector3d total = loads.ReferenceResultant();
    summary.notes.push_back(
        Format("applied loads: resultant (%.6g, %.6g, %.6g) N", total.x(), total.y(), total.z()));
  }
  clock.End();

  // PCG looks at the cancel flag every iteration (a direct factorisation cannot).
  LinearSolverOptions linear_solver = problem.linear_solver;
  linear_solver.cancel = clock.options().cancel;
  auto solver = CreateLinearSolver(linear_solver);
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
  // Recovery needs neither the matrix nor its factorisation, only the
  // solver's name (for the summary): both are released here rather than
  // held through recovery and the error estimate.
  const std::string solver_name = solver->Name();
  solver.reset();
  system = LinearSystem();
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
      ElementRecovery r;
      if (mesh.quadratic()) {
        const Tet10Geometry g = ComputeTet10Geometry(Tet10Coordinates(mesh, e));
        r = RecoverElement<10>(
            Tet10NodeIndices(mesh, e), GatherElementTet10(mesh, e, u), 4,
            [&](int q, double* dv) {
              *dv = g.volume[q];
              return Tet10StrainDisplacement(g.grad[q]);
            },
            elasticity.D(e), &internal);
      } else if (mesh.hexahedral()) {
        const Hex8Geometry g = ComputeHex8Geometry(Hex8Coordinates(mesh, e));
        r = RecoverElement<8>(
            mesh.hexes[e], GatherElementHex8(mesh, e, u), 8,
            [&](int q, double* dv) {
              *dv = g.volume[q];
              return full_bricks ? Hex8StrainDisplacement(g.grad[q])
                                 : Hex8StrainDisplacementBar(g.grad[q], g.mean_grad);
            },
            elasticity.D(e), &internal);
      } else {
        const Tet4Geometry g = ComputeTet4Geometry(TetCorners(mesh, e));
        r = RecoverElement<4>(
            mesh.tets[e], GatherElement(mesh, e, u), 1,
            [&](int, double* dv) {
              *dv = g.volume;
              return StrainDisplacement(g);
            },
            elasticity.D(e), &internal);
      }
      Eigen::Map<Vector6d>(&solution->strain[6 * e]) = r.strain;
      Eigen::Map<Vector6d>(&solution->stress_pa[6 * e]) = r.stress;
      solution->von_mises_pa[e] = VonMises(r.stress);
      volume[e] = r.volume;
      energy += r.energy;
      max_strain = std::max(max_strain, r.max_strain);
    }
  }
  clock.End();

  clock.Begin("estimate", 0.9, 0.95, "Zienkiewicz-Zhu error estimate");
  const ErrorEstimateResult estimate =
      mesh.quadratic()
          ? EstimateZzErrorTet10(
                mesh,
                [&](int e, const Eigen::Vector3d& xi) -> Vector6d {
                  return elasticity.D(e) *
                         Tet10Strain(Tet10Coordinates(mesh, e), GatherElementTet10(mesh, e, u), xi);
                },
                elasticity)
      : mesh.hexahedral() ? EstimateZzErrorHex8(
                                mesh,
                                [&](int e, const Eigen::Vector3d& xi) -> Vector6d {
                                  const Hex8Nodes x = Hex8Coordinates(mesh, e);
                                  const Vector24d ue = GatherElementHex8(mesh, e, u);
                                  return elasticity.D(e) * (full_bricks ? Hex8StrainFull(x, ue, xi)
                                                                        : Hex8Strain(x, ue, xi));
                                },
                                elasticity)
                          : EstimateZzError(mesh, solution->stress_pa, volume, elasticity);
  solution->error_indicator = estimate.element_share;
  summary.error.estimated = true;
  summary.error.method =
      mesh.quadratic()    ? "Zienkiewicz-Zhu stress recovery (nodal averaging, quadratic)"
      : mesh.hexahedral() ? "Zienkiewicz-Zhu stress recovery (nodal averaging, trilinear)"
                          : "Zienkiewicz-Zhu stress recovery (nodal averaging)";
  summary.error.relative_error = estimate.relative_error;
  for (const RegionError& r : ErrorByRegion(mesh, estimate, "body")) {
    summary.error.regions.push_back({r.name, r.elements, r.relative_error, r.share});
  }
  summary.error.note =
      "estimated discretisation error in the energy norm, relative to the solution's energy norm; "
      "refine the mesh (mesh.element_size_mm) to reduce it";
  clock.Update(1.0);
  clock.End();

  const bool initial_moduli =
      std::any_of(model.materials.specs.begin(), model.materials.specs.end(),
                  [](const MaterialSpec& m) { return m.hyperelastic(); });
  summary.analysis = initial_moduli ? "linear static (small strain, the materials' initial moduli)"
                                    : "linear static (small strain)";
  for (const std::string& note : model.materials.notes) summary.notes.push_back(note);
  summary.linear_solver = solver_name;
  if (max_strain > kSmallStrainLimit) {
    summary.notes.push_back(
        Format("the largest strain component is %.1f %%: beyond a few percent small-strain linear "
               "elasticity misjudges soft tissue, which is nonlinear and nearly incompressible; "
               "use analysis.type NONLINEAR_STATIC with a hyperelastic material",
               100 * max_strain));
  }
  summary.relative_residual = residual;
  result->u = std::move(u);
  result->internal_force = std::move(internal);
  result->external_force = std::move(external);
  result->strain_energy_j = energy;
  result->max_strain = max_strain;
  return Status::Ok();
}

}  // namespace pba
