// NONLINEAR_STATIC: finite strain, total Lagrangian, Newton-Raphson with load
// stepping (analysis/newton_static.h), then the finite-strain fields per
// element: Green-Lagrange and Euler-Almansi strain, second Piola-Kirchhoff
// and Cauchy stress, J, von Mises of the Cauchy stress.
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <optional>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/checkpoint.h"
#include "analysis/element_fields.h"
#include "analysis/error_estimator.h"
#include "analysis/finite_strain_model.h"
#include "analysis/newton_static.h"
#include "analysis/rigid_contact.h"
#include "analysis/static_analysis.h"
#include "analysis/time_history.h"
#include "core/format.h"
#include "fem/element_kind.h"
#include "fem/hex8.h"
#include "fem/point_kinematics.h"
#include "fem/tet4_finite_strain.h"
#include "linear/linear_solver.h"
#include "linear/petsc_runtime.h"
#include "material/factory.h"
#include "material/hyperelastic.h"
#include "material/linear_elastic.h"
#include "material/material_field.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"
#include "scene/materials.h"
#include "scene/time_curve.h"

namespace pba {
namespace {

NewtonOptions OptionsOf(const NonlinearOptions& nonlinear) {
  NewtonOptions options;
  options.initial_increments = nonlinear.increments;
  options.max_iterations = nonlinear.max_iterations;
  options.residual_tolerance = nonlinear.residual_tolerance;
  options.displacement_tolerance = nonlinear.displacement_tolerance;
  options.min_increment = nonlinear.min_increment;
  options.max_increment = std::max(options.max_increment, 1.0 / options.initial_increments);
  options.line_search = nonlinear.line_search;
  return options;
}

}  // namespace

namespace {

// The problem's rigid contacts, each placed touching the tissue when it
// asks (noted in `notes`). The penalty is DefaultContactPenalty of the
// tissue's shear modulus over the finest element size (an atlas's region
// of interest is where a punch presses).
Status MakeContacts(const Problem& problem, double shear_modulus_pa,
                    std::vector<std::unique_ptr<RigidContact>>* contacts,
                    std::vector<std::string>* notes) {
  const Mesh& mesh = problem.model.mesh;
  for (std::size_t k = 0; k < problem.contacts.size(); ++k) {
    const Contact& c = problem.contacts[k];
    RigidBody rigid = c.body;
    const FaceSet& set = mesh.face_sets.at(c.set);
    if (c.start_touching) {
      const Status placed = PlaceTouching(mesh, set, &rigid);
      if (!placed.ok()) {
        return Status::FailedPrecondition(Format("contacts[%zu].start_touching: ", k) +
                                          placed.message());
      }
      notes->push_back(Format("contact %s placed touching the tissue at (%.4g, %.4g, %.4g) mm",
                              c.name.c_str(), rigid.position.x() * 1e3, rigid.position.y() * 1e3,
                              rigid.position.z() * 1e3));
    }
    const double penalty =
        DefaultContactPenalty(shear_modulus_pa, problem.finest_element_size_m, c.penalty_factor);
    contacts->push_back(std::make_unique<RigidContact>(mesh, set, rigid, penalty, c.friction,
                                                       c.penetration_tolerance_m));
  }
  return Status::Ok();
}

// The Zienkiewicz-Zhu estimate of the second Piola-Kirchhoff stress at u,
// measured with each element's initial compliance; solution->pk2_stress_pa
// must hold the element means.
ErrorEstimateResult EstimateFiniteStrainError(const Problem& problem, const MaterialField& field,
                                              const Eigen::VectorXd& u, const Solution& solution) {
  const Mesh& mesh = problem.model.mesh;
  const bool full_bricks = problem.element == ElementType::kHex8Full;
  const bool tet10_md = problem.element == ElementType::kTet10Md;
  const auto mean = [&](int e) -> Vector6d {
    return Eigen::Map<const Vector6d>(&solution.pk2_stress_pa[6 * static_cast<std::size_t>(e)]);
  };
  // The recovery samples the stress at an element's nodes, outside its
  // integration points: under heavy compression F there may be inverted
  // although the element is sound where it is integrated. There it takes
  // the element's mean stress.
  const auto stress_or_mean = [&](int e, const Eigen::Matrix3d& f) -> Vector6d {
    if (IsAdmissible(f)) return field.At(e).Stress(f);
    return mean(e);
  };
  const auto stress = [&](int e, const Eigen::Vector3d& xi) -> Vector6d {
    switch (mesh.shape()) {
      case ElementShape::kTet10: {
        const Tet10Nodes x = Tet10Coordinates(mesh, e);
        const Vector30d ue = GatherElementTet10(mesh, e, u);
        Tet10Nodes grad;
        Tet10Gradients(x, xi, &grad);
        const Eigen::Matrix3d f = DeformationGradientTet10(grad, ue);
        if (!tet10_md || !IsAdmissible(f)) return stress_or_mean(e, f);
        return stress_or_mean(e, MeanDilatationF(f, MeanDilatation(ComputeTet10Geometry(x), ue)));
      }
      case ElementShape::kHex8: {
        const Hex8Nodes x = Hex8Coordinates(mesh, e);
        const Vector24d ue = GatherElementHex8(mesh, e, u);
        Hex8Nodes grad;
        Hex8Gradients(x, xi, &grad);
        const Eigen::Matrix3d f = DeformationGradientHex8(grad, ue);
        if (full_bricks || !IsAdmissible(f)) return stress_or_mean(e, f);
        return stress_or_mean(e, MeanDilatationF(f, MeanDilatation(ComputeHex8Geometry(x), ue)));
      }
      case ElementShape::kTet4:
        break;
    }
    // A 4-node element's stress is constant: its mean, as recovered.
    return mean(e);
  };
  // Each element's stress measured with its own material's initial compliance.
  return EstimateZzError(mesh, stress, MakeElasticityField(problem.model.materials),
                         problem.threads);
}

// The Newton report's notes for the summary: substitute tangents,
// unstable equilibria, cut increments.
void NoteNewtonReport(const NewtonReport& report, Summary* summary) {
  if (report.approximate_iterations > 0) {
    summary->notes.push_back(
        Format("%d Newton iteration(s) met a tangent that was not positive definite (far from "
               "equilibrium) and stepped with it less the pressure's initial-stress terms",
               report.approximate_iterations));
  }
  if (report.modified_iterations > 0) {
    summary->notes.push_back(
        Format("%d Newton iteration(s) met a tangent that was not positive definite (far from "
               "equilibrium) and stepped with the last positive definite one instead",
               report.modified_iterations));
  }
  int unstable = 0, most_negative = 0;
  for (const IncrementRecord& r : report.increments) {
    if (r.negative_eigenvalues > 0) ++unstable;
    most_negative = std::max(most_negative, r.negative_eigenvalues);
  }
  if (unstable > 0) {
    summary->notes.push_back(Format(
        "%d increment(s) converged to an equilibrium whose tangent stiffness has up to %d "
        "negative eigenvalue(s): the load path passed a bifurcation (buckling, or a spurious mode "
        "of the element) and follows the fundamental branch, which is unstable there; "
        "%d Newton iteration(s) stepped with that indefinite tangent (LDL^T)",
        unstable, most_negative, report.indefinite_iterations));
  }
  if (report.cuts > 0) {
    summary->notes.push_back(Format("%d load increment(s) were cut back and retried; first: %s",
                                    report.cuts, report.cut_reasons.front().c_str()));
  }
  if (report.partitioned_tangents > 0) {
    summary->notes.push_back(Format(
        "%d of %d tangent stiffnesses were assembled partitioned between the %d MPI ranks (each "
        "rank the columns of its share of the nodes, with the elements that touch them; the "
        "others whole: the first ones, while AUTO chose its solver, and any a substitute needed)",
        report.partitioned_tangents, report.tangents, CurrentRanks().size));
  }
}

// Both finite-strain analyses: NONLINEAR_STATIC ramps the loads with the
// load factor, QUASI_STATIC follows them through time. The run builds the
// element model with its contacts, wires Newton's observers (history,
// checkpoints, progress) and recovers the fields and the error estimate.
class FiniteStrainRun {
 public:
  FiniteStrainRun(const Problem& problem, PhaseClock* clock, Solution* solution)
      : problem_(problem),
        clock_(*clock),
        solution_(solution),
        summary_(solution->summary),
        mesh_(problem.model.mesh),
        dofs_(problem.model.dofs),
        timed_(problem.analysis == AnalysisSpec::Type::kQuasiStatic),
        one_point_(KindOf(problem.element).keeps_history) {}

  Status Run(StaticResult* result);

 private:
  Status MakeModel();
  void MakeNewtonOptions();
  Status StartHistory();
  Status Solve();
  Status Recover(StaticResult* result);
  Status StoredEnergy(double* energy);
  void Estimate();
  void Summarise();
  double Amplitude(double load) const {
    return timed_ ? curve_->Amplitude(load * duration_) : load;
  }

  const Problem& problem_;
  PhaseClock& clock_;
  Solution* solution_;
  Summary& summary_;
  const Mesh& mesh_;
  const DofMap& dofs_;
  const bool timed_, one_point_;

  std::unique_ptr<MaterialField> field_;
  std::unique_ptr<FiniteStrainModel> body_, touching_;
  const FiniteStrainModel* solid_ = nullptr;
  std::vector<std::unique_ptr<RigidContact>> contacts_;
  std::vector<std::pair<std::string, const RigidContact*>> named_contacts_;
  std::vector<double> peak_contact_force_;
  UnknownLayout layout_;  // the solvers' view of the unknowns (outlives them)
  std::unique_ptr<LinearSolver> solver_;
  std::string solver_name_;
  std::optional<TimeCurve> curve_;
  double duration_ = 1;
  NewtonOptions options_;
  std::optional<ExternalLoads> loads_;
  std::optional<HistoryRecorder> history_;
  std::optional<Checkpointer> checkpoints_;
  std::optional<CheckpointObserver> checkpoint_observer_;
  StepObservers observers_;
  NewtonReport report_;
  Eigen::VectorXd u_;
};

// The element model for the problem's element type, with its contacts.
Status FiniteStrainRun::MakeModel() {
  field_ = MakeMaterialField(problem_.model.materials, problem_.relaxed_below_s,
                             problem_.frozen_above_s, problem_.threads);
  const MaterialField& field = *field_;
  summary_.element_type = ElementName(problem_.element);
  if (!one_point_ && ((timed_ && field.viscous()) || field.grows())) {
    // ValidateScene refuses these (scene_checks::ValidateHistoryElements).
    return Status::Internal(std::string(field.grows() ? "growth" : "viscoelastic relaxation") +
                            " reached a " + summary_.element_type +
                            " model, which keeps no history");
  }
  if (!timed_ && field.viscous()) {
    summary_.notes.push_back(
        "viscoelastic relaxation is not used by a static analysis: the instantaneous "
        "(hyperelastic) response is solved; QUASI_STATIC follows it through time");
  }
  for (const std::string& note : problem_.model.materials.notes) summary_.notes.push_back(note);
  body_ = MakeFiniteStrainModel(problem_.element, mesh_, field, problem_.threads);
  // One-point elements keep the field's history (MaterialField).
  if (one_point_) body_->KeepHistoryIn(field_.get(), &mesh_, problem_.threads);
  PBA_RETURN_IF_ERROR(
      MakeContacts(problem_, field.Base(0).ShearModulus(), &contacts_, &summary_.notes));
  std::vector<const RigidContact*> contact_views;
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    contact_views.push_back(contacts_[i].get());
    named_contacts_.emplace_back(problem_.contacts[i].name, contacts_[i].get());
  }
  if (!contacts_.empty()) touching_ = WithContact(*body_, contact_views);
  solid_ = touching_ ? touching_.get() : body_.get();
  peak_contact_force_.assign(contacts_.size(), 0.0);
  return Status::Ok();
}

// Newton's options and its observers: time steps, the field's and the
// contacts' step, contact augmentation, what each converged increment
// records.
void FiniteStrainRun::MakeNewtonOptions() {
  options_ = OptionsOf(problem_.nonlinear);
  // Time: the load factor is t / T and the loads follow a(t); a static
  // analysis is the ramp a = load factor with instantaneous steps.
  TimeOptions unit_ramp;
  unit_ramp.end_s = 1;
  curve_.emplace(timed_ ? problem_.time : unit_ramp);
  duration_ = curve_->end_s();
  if (timed_) summary_.notes.push_back(SetTimeSteps(problem_.time, *curve_, *field_, &options_));
  options_.amplitude = [this](double load) { return Amplitude(load); };
  options_.begin_increment = [this](double from, double to) {
    field_->BeginStep(timed_ ? (to - from) * duration_ : 0.0, Amplitude(to));
    for (auto& contact : contacts_) contact->SetAmplitude(Amplitude(to));
    return Status::Ok();
  };
  if (!contacts_.empty()) {
    options_.augment = [this](const Eigen::VectorXd& u) {
      bool changed = false;
      for (auto& contact : contacts_) changed = contact->Augment(u) || changed;
      return changed;
    };
  }
  loads_.emplace(BuildLoads(problem_));
  history_.emplace(problem_, timed_ ? duration_ : 0.0, named_contacts_);
  options_.on_increment = [this](double load, const Eigen::VectorXd& u) {
    solution_->step_load_factor.push_back(timed_ ? Amplitude(load) : load);
    if (timed_) solution_->step_time_s.push_back(load * duration_);
    for (int i = 0; i < u.size(); ++i) solution_->step_displacement_mm.push_back(u(i) / 1e-3);
    body_->CommitHistory(u);
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      contacts_[i]->Commit(u);
      peak_contact_force_[i] =
          std::max(peak_contact_force_[i], contacts_[i]->Measure(u).force.norm());
    }
    if (timed_) history_->Record(*solid_, &*loads_, load, Amplitude(load), u, solution_);
  };
}

// Checkpoints (QUASI_STATIC only): a restart takes up the state of a
// converged step; later ones are written after converged steps. A fresh
// timed run's history starts at t = 0 with the state before any step.
Status FiniteStrainRun::StartHistory() {
  std::vector<RigidContact*> contact_state;
  for (auto& contact : contacts_) contact_state.push_back(contact.get());
  checkpoints_.emplace(clock_.options(), problem_.name, duration_, mesh_, dofs_, body_.get(),
                       *field_, contact_state);
  if (timed_ && checkpoints_->restarts()) {
    PBA_RETURN_IF_ERROR(checkpoints_->Restore(solution_, &options_, &peak_contact_force_));
    summary_.notes.push_back(
        Format("restarted from a checkpoint at t = %g s", checkpoints_->restored_time_s()));
  } else if (timed_) {
    for (auto& contact : contacts_) contact->SetAmplitude(Amplitude(0));
    field_->BeginStep(0, Amplitude(0));
    history_->Record(*solid_, &*loads_, 0, Amplitude(0), Eigen::VectorXd::Zero(dofs_.num_dofs()),
                     solution_);
  }
  if (timed_ && checkpoints_->writes()) {
    checkpoint_observer_.emplace(&*checkpoints_, solution_, &report_, &peak_contact_force_);
    observers_.Add(&*checkpoint_observer_);
    options_.observers = &observers_;
  }
  return Status::Ok();
}

Status FiniteStrainRun::Solve() {
  clock_.Begin(
      "newton", 0.05, 0.85,
      timed_ ? Format("Newton-Raphson on %d unknowns through %g s", dofs_.num_free(), duration_)
             : Format("Newton-Raphson on %d unknowns, %d initial increments", dofs_.num_free(),
                      options_.initial_increments));
  if (!loads_->empty()) {
    const Eigen::Vector3d total = loads_->ReferenceResultant();
    summary_.notes.push_back(
        Format("applied loads: resultant (%.6g, %.6g, %.6g) N on the reference configuration%s",
               total.x(), total.y(), total.z(),
               loads_->follows_deformation() ? "; pressure follows the deformed surface" : ""));
  }
  const Status status = SolveNewtonStatic(
      *solid_, &*loads_, dofs_, options_, solver_.get(),
      [this](const NewtonProgress& p) {
        const std::string where = timed_ ? Format("t = %.4g s", p.load_factor * duration_)
                                         : Format("load factor %.3g", p.load_factor);
        clock_.Update(p.load_factor, p.iteration == 0
                                         ? where + " reached"
                                         : Format("%s, iteration %d, relative residual %.2g",
                                                  where.c_str(), p.iteration, p.relative_residual));
        return !clock_.cancelled();
      },
      &u_, &report_);
  // The factorisation (with PCG, a copy of the matrix and its incomplete
  // factor) would otherwise stay resident through recovery and the error
  // estimate; only the solver's name is wanted after Newton.
  solver_name_ = solver_->Name();
  solver_.reset();
  checkpoints_->Merge(&report_);
  summary_.newton_iterations = report_.total_iterations;
  summary_.increment_cuts = report_.cuts;
  summary_.newton_assembly_s = report_.assembly_s;
  summary_.newton_linear_solve_s = report_.linear_solve_s;
  summary_.newton_residual_s = report_.residual_s;
  for (const IncrementRecord& r : report_.increments) {
    summary_.increments.push_back({timed_ ? Amplitude(r.load_factor) : r.load_factor, r.iterations,
                                   r.relative_residual, r.negative_eigenvalues});
    if (timed_) {
      summary_.time_steps.push_back({r.load_factor * duration_, r.step * duration_,
                                     Amplitude(r.load_factor), r.iterations, r.relative_residual});
    }
  }
  if (status.code() == Status::Code::kNumerical && timed_) {
    return Status::Numerical(
        status.message() + Format(" (load factor = t / %g s)", duration_) +
        "; the motion or load may be too large or too fast for this mesh - try a finer mesh, "
        "smaller steps (analysis.time.initial_step_s, min_step_s) or a smaller displacement or "
        "load");
  }
  if (status.code() == Status::Code::kNumerical) {
    return Status::Numerical(status.message() +
                             "; the prescribed deformation or load may be too large for this "
                             "mesh (elements invert) - try a finer mesh, more increments "
                             "(analysis.nonlinear.increments) or a smaller displacement or load");
  }
  PBA_RETURN_IF_ERROR(status);
  clock_.End();
  return Status::Ok();
}

// The tissue's stored energy: the body's own (a contact's penalty
// potential is no strain energy) and, where it relaxes through time, its
// long-term part (MaterialField::LongTermResponse; what a step's Newton
// iterations minimise is an incremental potential, not a stored energy).
Status FiniteStrainRun::StoredEnergy(double* energy) {
  std::optional<MaterialField::LongTermResponse> relaxed;
  if (timed_ && field_->viscous()) {
    relaxed.emplace(field_.get());
    summary_.notes.push_back(
        "strain energy of relaxing tissue: its long-term part, U + g_inf W_iso (the energy it "
        "keeps once relaxed), without the share of the terms still relaxing: a lower bound of "
        "the stored energy");
  }
  Eigen::VectorXd force;
  *energy = 0;
  if (!body_->InternalForce(u_, &force, energy)) {
    return Status::Internal("an element inverted after a converged solve");
  }
  return Status::Ok();
}

Status FiniteStrainRun::Recover(StaticResult* result) {
  clock_.Begin("recover", 0.85, 0.95, "finite-strain fields, reactions");
  result->max_strain = body_->RecoverFields(u_, solution_);
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const ContactMeasure m = contacts_[i]->Measure(u_);
    ContactSummary c;
    c.name = problem_.contacts[i].name;
    for (int k = 0; k < 3; ++k) c.force_n[k] = m.force(k);
    c.peak_force_n = peak_contact_force_[i];
    c.area_mm2 = m.area * 1e6;
    c.max_penetration_mm = m.penetration * 1e3;
    c.penalty_pa_per_mm = contacts_[i]->penalty() * 1e-3;
    c.augmentations = report_.augmentations;
    summary_.contacts.push_back(c);
  }
  if (!solid_->InternalForce(u_, &result->internal_force, nullptr)) {
    return Status::Internal("an element inverted after a converged solve");
  }
  PBA_RETURN_IF_ERROR(StoredEnergy(&result->strain_energy_j));
  if (!loads_->empty()) result->external_force = loads_->Force(u_);
  clock_.End();
  return Status::Ok();
}

void FiniteStrainRun::Estimate() {
  clock_.Begin("estimate", 0.95, 0.99, "Zienkiewicz-Zhu error estimate");
  const ErrorEstimateResult estimate = EstimateFiniteStrainError(problem_, *field_, u_, *solution_);
  solution_->error_indicator = estimate.element_share;
  summary_.error.estimated = true;
  summary_.error.method = ZzMethod(mesh_, ZzStress::kSecondPiolaKirchhoff);
  summary_.error.relative_error = estimate.relative_error;
  for (const RegionError& r : ErrorByRegion(mesh_, estimate, "body")) {
    summary_.error.regions.push_back({r.name, r.elements, r.relative_error, r.share});
  }
  summary_.error.note =
      "estimated discretisation error in the energy norm, relative to the solution's; at large "
      "strain the initial-compliance norm makes it an indicator rather than a bound; refine the "
      "mesh (mesh.element_size_mm) to reduce it, and measure the error of a quantity that "
      "matters with a mesh-convergence study (pba study convergence)";
  clock_.Update(1.0);
  clock_.End();
}

void FiniteStrainRun::Summarise() {
  summary_.analysis = timed_ ? Format(
                                   "quasi-static through %g s (finite strain, total Lagrangian, "
                                   "Newton-Raphson in %zu adaptive time steps)",
                                   duration_, report_.increments.size())
                             : "nonlinear static (finite strain, total Lagrangian, Newton-Raphson)";
  summary_.linear_solver = solver_name_;
  summary_.notes.push_back("elements: " + solid_->Describe());
  NoteNewtonReport(report_, &summary_);
  summary_.relative_residual =
      report_.increments.empty() ? 0 : report_.increments.back().relative_residual;
}

Status FiniteStrainRun::Run(StaticResult* result) {
  PBA_RETURN_IF_ERROR(MakeModel());
  // PCG looks at the cancel flag every iteration (a direct factorisation cannot).
  LinearSolverOptions linear_solver = problem_.linear_solver;
  linear_solver.cancel = clock_.options().cancel;
  layout_ = MakeUnknownLayout(dofs_, mesh_.nodes);
  linear_solver.layout = &layout_;
  solver_ = CreateLinearSolver(linear_solver);
  MakeNewtonOptions();
  PBA_RETURN_IF_ERROR(StartHistory());
  PBA_RETURN_IF_ERROR(Solve());
  PBA_RETURN_IF_ERROR(Recover(result));
  Estimate();
  Summarise();
  result->u = std::move(u_);
  return Status::Ok();
}

Status SolveFiniteStrain(const Problem& problem, PhaseClock* clock, Solution* solution,
                         StaticResult* result) {
  FiniteStrainRun run(problem, clock, solution);
  return run.Run(result);
}

}  // namespace

Status SolveNonlinearStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                            StaticResult* result) {
  return SolveFiniteStrain(problem, clock, solution, result);
}

Status SolveQuasiStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                        StaticResult* result) {
  return SolveFiniteStrain(problem, clock, solution, result);
}

}  // namespace pba
