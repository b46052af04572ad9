// LINEAR_STATIC: small-strain linear elasticity on 4- or 10-node tetrahedra
// or 8-node hexahedra (B-bar), K_ff u_f = f_f - K_fp u_p, with a
// Zienkiewicz-Zhu error estimate.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "analysis/element_fields.h"
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

// One LINEAR_STATIC solve in its steps, each one or two phases of the
// clock; what a step makes is kept here for the next one.
class LinearStaticRun {
 public:
  LinearStaticRun(const Problem& problem, PhaseClock* clock, Solution* solution)
      : problem_(problem),
        clock_(*clock),
        solution_(*solution),
        summary_(solution->summary),
        mesh_(problem.model.mesh),
        dofs_(problem.model.dofs),
        elasticity_(MakeElasticityField(problem.model.materials)),
        full_bricks_(problem.element == ElementType::kHex8Full) {}

  // K_ff and f_f - K_fp u_p, the external loads added.
  Status Assemble();
  // u_f, then releases the matrix and the solver.
  Status Solve();
  // Element strain, stress and energy, and the internal force.
  void Recover();
  void EstimateError();
  // The summary's analysis, notes and solver, and `result`.
  void Finish(StaticResult* result);

 private:
  Status Cancelled() const {
    return Status::Cancelled("cancelled during " + summary_.phases.back().phase);
  }
  // Element e's fields from u_, its internal force added to `internal`.
  Status AssembleStiffness(const std::function<bool(double)>& keep_going);
  ElementRecovery RecoverOne(int e, Eigen::VectorXd* internal) const;
  // Element e's stress at natural point xi (the error estimate's sample);
  // a 4-node element's is constant, the one Recover wrote.
  Vector6d StressAt(int e, const Eigen::Vector3d& xi) const;

  const Problem& problem_;
  PhaseClock& clock_;
  Solution& solution_;
  Summary& summary_;
  const Mesh& mesh_;
  const DofMap& dofs_;
  // Each element's own material, in the global frame (an orthotropic
  // material's axes already applied).
  const ElasticityField elasticity_;
  // Bricks with the plain B (full integration) instead of B-bar.
  const bool full_bricks_;

  std::vector<std::vector<int>> colours_;
  LinearSystem system_;
  Eigen::VectorXd external_;
  std::string solver_name_;
  Eigen::VectorXd u_free_;
  double residual_ = 0;
  Eigen::VectorXd u_, internal_;
  double energy_ = 0, max_strain_ = 0;
};

Status LinearStaticRun::Assemble() {
  clock_.Begin(
      "assemble", 0.05, 0.25,
      Format("assembling %d elements, %d unknowns", mesh_.num_elements(), dofs_.num_free()));
  colours_ = ColourElements(mesh_);
  const auto keep_going = [&](double f) {
    clock_.Update(f);
    return !clock_.cancelled();
  };
  PBA_RETURN_IF_ERROR(AssembleStiffness(keep_going));
  const ExternalLoads loads = BuildLoads(problem_);
  if (!loads.empty()) {
    external_ = loads.Force(Eigen::VectorXd::Zero(dofs_.num_dofs()));
    for (int dof = 0; dof < dofs_.num_dofs(); ++dof) {
      const int f = dofs_.free_index(dof);
      if (f >= 0) system_.rhs(f) += external_(dof);
    }
    const Eigen::Vector3d total = loads.ReferenceResultant();
    summary_.notes.push_back(
        Format("applied loads: resultant (%.6g, %.6g, %.6g) N", total.x(), total.y(), total.z()));
  }
  clock_.End();
  return Status::Ok();
}

Status LinearStaticRun::Solve() {
  // PCG looks at the cancel flag every iteration (a direct factorisation cannot).
  LinearSolverOptions linear_solver = problem_.linear_solver;
  linear_solver.cancel = clock_.options().cancel;
  const UnknownLayout layout = MakeUnknownLayout(dofs_, mesh_.nodes);
  linear_solver.layout = &layout;
  auto solver = CreateLinearSolver(linear_solver);
  if (dofs_.num_free() > 0) {
    clock_.Begin("factorize", 0.25, 0.75,
                 Format("%s of %d unknowns, %lld stored entries", solver->Name().c_str(),
                        dofs_.num_free(), static_cast<long long>(system_.k.nonZeros())));
    PBA_RETURN_IF_ERROR(solver->Factorize(system_.k));
    clock_.End();
    if (clock_.cancelled()) return Cancelled();
    clock_.Begin("solve", 0.75, 0.8, "forward and back substitution");
    PBA_RETURN_IF_ERROR(solver->Solve(system_.rhs, &u_free_));
    const double scale = system_.rhs.norm();
    residual_ = (system_.k * u_free_ - system_.rhs).norm() / (scale > 0 ? scale : 1.0);
    clock_.End();
  }
  // Recovery needs neither the matrix nor its factorisation, only the
  // solver's name (for the summary): both are released here rather than
  // held through recovery and the error estimate.
  solver_name_ = solver->Name();
  solver.reset();
  system_ = LinearSystem();
  if (clock_.cancelled()) return Cancelled();
  return Status::Ok();
}

// The stiffness of the mesh's elements into system_.
Status LinearStaticRun::AssembleStiffness(const std::function<bool(double)>& keep_going) {
  const ThreadContext& threads = problem_.threads;
  switch (mesh_.shape()) {
    case ElementShape::kTet10:
      return AssembleLinearSystemTet10(mesh_, elasticity_, dofs_, colours_, keep_going, &system_,
                                       threads);
    case ElementShape::kHex8:
      return full_bricks_ ? AssembleLinearSystemHex8Full(mesh_, elasticity_, dofs_, colours_,
                                                         keep_going, &system_, threads)
                          : AssembleLinearSystemHex8(mesh_, elasticity_, dofs_, colours_,
                                                     keep_going, &system_, threads);
    case ElementShape::kTet4:
      break;
  }
  return AssembleLinearSystem(mesh_, elasticity_, dofs_, colours_, keep_going, &system_, threads);
}

ElementRecovery LinearStaticRun::RecoverOne(int e, Eigen::VectorXd* internal) const {
  switch (mesh_.shape()) {
    case ElementShape::kTet10: {
      const Tet10Geometry g = ComputeTet10Geometry(Tet10Coordinates(mesh_, e));
      return RecoverElement<10>(
          Tet10NodeIndices(mesh_, e), GatherElementTet10(mesh_, e, u_), 4,
          [&](int q, double* dv) {
            *dv = g.volume[q];
            return Tet10StrainDisplacement(g.grad[q]);
          },
          elasticity_.D(e), internal);
    }
    case ElementShape::kHex8: {
      const Hex8Geometry g = ComputeHex8Geometry(Hex8Coordinates(mesh_, e));
      return RecoverElement<8>(
          mesh_.hexes[e], GatherElementHex8(mesh_, e, u_), 8,
          [&](int q, double* dv) {
            *dv = g.volume[q];
            return full_bricks_ ? Hex8StrainDisplacement(g.grad[q])
                                : Hex8StrainDisplacementBar(g.grad[q], g.mean_grad);
          },
          elasticity_.D(e), internal);
    }
    case ElementShape::kTet4:
      break;
  }
  const Tet4Geometry g = ComputeTet4Geometry(TetCorners(mesh_, e));
  return RecoverElement<4>(
      mesh_.tets[e], GatherElement(mesh_, e, u_), 1,
      [&](int, double* dv) {
        *dv = g.volume;
        return StrainDisplacement(g);
      },
      elasticity_.D(e), internal);
}

void LinearStaticRun::Recover() {
  clock_.Begin("recover", 0.8, 0.9, "element strain and stress, reactions");
  u_.resize(dofs_.num_dofs());
  for (int dof = 0; dof < dofs_.num_dofs(); ++dof) {
    u_(dof) = dofs_.prescribed(dof) ? dofs_.prescribed_value(dof) : u_free_(dofs_.free_index(dof));
  }
  StartSmallStrainFields(mesh_.num_elements(), &solution_);
  Eigen::VectorXd internal = Eigen::VectorXd::Zero(dofs_.num_dofs());
  double energy = 0, max_strain = 0;  // locals: OpenMP reduces variables, not members
  for (const auto& colour : colours_) {
#pragma omp parallel for reduction(+ : energy) reduction(max : max_strain) schedule(static) \
    num_threads(problem_.threads.threads()) if (problem_.threads.Parallel(colour.size()))
    for (std::size_t k = 0; k < colour.size(); ++k) {
      const int e = colour[k];
      const ElementRecovery r = RecoverOne(e, &internal);
      WriteSmallStrainFields(e, r.strain, r.stress, &solution_);
      energy += r.energy;
      max_strain = std::max(max_strain, r.max_strain);
    }
  }
  internal_ = std::move(internal);
  energy_ = energy;
  max_strain_ = max_strain;
  clock_.End();
}

Vector6d LinearStaticRun::StressAt(int e, const Eigen::Vector3d& xi) const {
  switch (mesh_.shape()) {
    case ElementShape::kTet10:
      return elasticity_.D(e) *
             Tet10Strain(Tet10Coordinates(mesh_, e), GatherElementTet10(mesh_, e, u_), xi);
    case ElementShape::kHex8: {
      const Hex8Nodes x = Hex8Coordinates(mesh_, e);
      const Vector24d ue = GatherElementHex8(mesh_, e, u_);
      return elasticity_.D(e) * (full_bricks_ ? Hex8StrainFull(x, ue, xi) : Hex8Strain(x, ue, xi));
    }
    case ElementShape::kTet4:
      break;
  }
  return Eigen::Map<const Vector6d>(&solution_.stress_pa[6 * static_cast<std::size_t>(e)]);
}

void LinearStaticRun::EstimateError() {
  clock_.Begin("estimate", 0.9, 0.95, "Zienkiewicz-Zhu error estimate");
  const ErrorEstimateResult estimate = EstimateZzError(
      mesh_, [this](int e, const Eigen::Vector3d& xi) { return StressAt(e, xi); }, elasticity_,
      problem_.threads);
  solution_.error_indicator = estimate.element_share;
  summary_.error.estimated = true;
  summary_.error.method = ZzMethod(mesh_);
  summary_.error.relative_error = estimate.relative_error;
  for (const RegionError& r : ErrorByRegion(mesh_, estimate, "body")) {
    summary_.error.regions.push_back({r.name, r.elements, r.relative_error, r.share});
  }
  summary_.error.note =
      "estimated discretisation error in the energy norm, relative to the solution's energy norm; "
      "refine the mesh (mesh.element_size_mm) to reduce it";
  clock_.Update(1.0);
  clock_.End();
}

void LinearStaticRun::Finish(StaticResult* result) {
  const SceneMaterials& materials = problem_.model.materials;
  const bool initial_moduli = std::any_of(materials.specs.begin(), materials.specs.end(),
                                          [](const MaterialSpec& m) { return m.hyperelastic(); });
  summary_.analysis = initial_moduli ? "linear static (small strain, the materials' initial moduli)"
                                     : "linear static (small strain)";
  for (const std::string& note : materials.notes) summary_.notes.push_back(note);
  summary_.linear_solver = solver_name_;
  if (max_strain_ > kSmallStrainLimit) {
    summary_.notes.push_back(
        Format("the largest strain component is %.1f %%: beyond a few percent small-strain linear "
               "elasticity misjudges soft tissue, which is nonlinear and nearly incompressible; "
               "use analysis.type NONLINEAR_STATIC with a hyperelastic material",
               100 * max_strain_));
  }
  summary_.relative_residual = residual_;
  result->u = std::move(u_);
  result->internal_force = std::move(internal_);
  result->external_force = std::move(external_);
  result->strain_energy_j = energy_;
  result->max_strain = max_strain_;
}

}  // namespace

Status SolveLinearStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                         StaticResult* result) {
  LinearStaticRun run(problem, clock, solution);
  PBA_RETURN_IF_ERROR(run.Assemble());
  PBA_RETURN_IF_ERROR(run.Solve());
  run.Recover();
  run.EstimateError();
  run.Finish(result);
  return Status::Ok();
}

}  // namespace pba
