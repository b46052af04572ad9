#include "explicit/dynamic_relaxation.h"

#include <algorithm>
#include <cmath>

#include "analysis/step_observer.h"
#include "core/format.h"
#include "explicit/explicit_setup.h"

namespace pba {
namespace {

// Steps over which the loads rise to their full value.
constexpr int kRampSteps = 200;
// Steps over which the convergence rate is measured.
constexpr int kRateWindow = 20;
constexpr int64_t kMaxSteps = 200000;
// The fictitious time step (the answer does not depend on it).
constexpr double kDt = 1;

double RampAmplitude(int64_t step) { return std::min(1.0, static_cast<double>(step) / kRampSteps); }

// One DYNAMIC_RELAXATION run: fictitious masses, then per step the forces,
// Underwood's damping and the convergence measures, and the damped step.
class DynamicRelaxationRun {
 public:
  DynamicRelaxationRun(const Problem& problem, PhaseClock* clock, Solution* solution)
      : problem_(problem),
        clock_(clock),
        solution_(solution),
        n_dofs_(3 * problem.model.mesh.num_nodes()),
        tolerance_(problem.explicit_dynamics.relaxation_tolerance) {}

  Status Setup();
  Status Relax();
  Status Finish(StaticResult* result);

 private:
  void SetFictitiousMasses();
  Status Forces(double amplitude);
  double Balance();
  double DistanceToAnswer() const;
  double Move();

  const Problem& problem_;
  PhaseClock* clock_;
  Solution* solution_;
  const int n_dofs_;
  const double tolerance_;
  ExplicitSetup setup_;
  TledModel* tled_ = nullptr;
  Eigen::VectorXd mass_;  // per node [kg, fictitious]

  Eigen::VectorXd u_, v_, f_int_, f_int_prev_, du_prev_, f_ext_;
  std::vector<double> increments_;  // largest |du| per step
  int64_t step_ = 0;
  double damping_ = 0, residual_ = 1, estimate_ = 0;
  double largest_u_ = 0;  // of the free unknowns at this step
  double loop_s_ = 0;
};

// Every element's stable step 1 / factor (the scene's time_step_factor,
// else ExplicitOptions::kRelaxationTimeStepFactor).
void DynamicRelaxationRun::SetFictitiousMasses() {
  TledModel& tled = *tled_;
  const double factor = problem_.explicit_dynamics.time_step_factor;
  mass_ = Eigen::VectorXd::Zero(problem_.model.mesh.num_nodes());
  for (int e = 0; e < tled.num_elements(); ++e) {
    const TledMaterial& m = tled.material(e);
    const double l = tled.characteristic_length(e);
    const double rho = (m.bulk + 4 * m.mu / 3) * (kDt / (factor * l)) * (kDt / (factor * l));
    const int npe = tled.nodes_per_element();
    for (int a = 0; a < npe; ++a) {
      mass_(tled.element_nodes(e)[a]) += rho * tled.reference_volume(e) / npe;
    }
  }
  tled.SetLumpedMass(mass_);
  tled.SetTimeStep(kDt);
}

Status DynamicRelaxationRun::Setup() {
  clock_->Begin("setup", 0.05, 0.1, "explicit model, fictitious masses");
  PBA_RETURN_IF_ERROR(MakeExplicitSetup(problem_, &setup_));
  tled_ = setup_.tled.get();
  SetFictitiousMasses();
  solution_->history_columns = {
      "step", "amplitude", "relative_residual", "estimated_error", "kinetic", "damping_per_step"};
  clock_->End();
  return Status::Ok();
}

// Prescribed displacements and loads at the ramp's amplitude; the internal
// force of the current displacements.
Status DynamicRelaxationRun::Forces(double amplitude) {
  const std::vector<PrescribedDof>& prescribed = setup_.prescribed;
  for (int i = 0; i < n_dofs_; ++i) {
    if (prescribed[i].kind == PrescribedDof::kDisplacement) {
      u_(i) = prescribed[i].value * amplitude;
    }
  }
  const TledEvaluation eval = tled_->InternalForce(u_, v_, &f_int_);
  if (eval.inverted_element >= 0) {
    return Status::Numerical(
        Format("dynamic relaxation stopped at step %lld (load %.0f %%): element %d inverted; the "
               "deformation is too large for this mesh",
               static_cast<long long>(step_), 100 * amplitude, eval.inverted_element));
  }
  if (setup_.has_loads) {
    f_ext_ = amplitude * (setup_.loads->follows_deformation() ? setup_.loads->Force(u_)
                                                              : setup_.loads->dead_force());
  }
  return Status::Ok();
}

// Underwood's damping, omega_min^2 from the Rayleigh quotient with the
// diagonal stiffness of the last step's change; returns the largest
// out-of-balance force on a free unknown relative to the largest load or
// reaction.
double DynamicRelaxationRun::Balance() {
  const std::vector<PrescribedDof>& prescribed = setup_.prescribed;
  double num = 0, den = 0, largest_r = 0, largest_load = 0;
  largest_u_ = 0;
  for (int i = 0; i < n_dofs_; ++i) {
    const double m = mass_(i / 3);
    if (prescribed[i].kind != PrescribedDof::kFree) {
      largest_load = std::max(largest_load, std::abs(f_int_(i) - f_ext_(i)));
      continue;
    }
    largest_load = std::max(largest_load, std::abs(f_ext_(i)));
    largest_r = std::max(largest_r, std::abs(f_ext_(i) - f_int_(i)));
    largest_u_ = std::max(largest_u_, std::abs(u_(i)));
    if (step_ > 0 && du_prev_(i) != 0) {
      const double k = (f_int_(i) - f_int_prev_(i)) / du_prev_(i);
      num += u_(i) * u_(i) * k;
      den += u_(i) * u_(i) * m;
    }
  }
  if (den > 0 && num > 0) damping_ = std::min(2 * std::sqrt(num / den), 1.9 / kDt);
  return largest_load > 0 ? largest_r / largest_load : largest_r;
}

// The distance to the answer from the rate the increments shrink:
// |u* - u^n| <= rho / (1 - rho) |u^n - u^(n-1)|; infinite until the rate is
// known and below 1.
double DynamicRelaxationRun::DistanceToAnswer() const {
  const std::size_t k = increments_.size();
  if (k > kRateWindow && increments_[k - 1 - kRateWindow] > 0) {
    const double rate =
        std::pow(increments_[k - 1] / increments_[k - 1 - kRateWindow], 1.0 / kRateWindow);
    if (rate < 1) return rate / (1 - rate) * increments_[k - 1];
  }
  return INFINITY;
}

// v^(n+1/2) = ((2 - c dt) v^(n-1/2) + 2 dt r / m) / (2 + c dt); the
// prescribed unknowns move to the next step's ramp. Returns the largest
// increment of a free unknown.
double DynamicRelaxationRun::Move() {
  const std::vector<PrescribedDof>& prescribed = setup_.prescribed;
  const double c = damping_;
  double largest_du = 0;
  for (int i = 0; i < n_dofs_; ++i) {
    double du;
    if (prescribed[i].kind == PrescribedDof::kFree && mass_(i / 3) > 0) {
      v_(i) = ((2 - c * kDt) * v_(i) + 2 * kDt * (f_ext_(i) - f_int_(i)) / mass_(i / 3)) /
              (2 + c * kDt);
      du = kDt * v_(i);
    } else {
      const double next = prescribed[i].kind == PrescribedDof::kDisplacement
                              ? prescribed[i].value * RampAmplitude(step_ + 1)
                              : u_(i);
      du = next - u_(i);
      v_(i) = du / kDt;
    }
    du_prev_(i) = du;
    if (prescribed[i].kind == PrescribedDof::kFree) largest_du = std::max(largest_du, std::abs(du));
    u_(i) += du;
  }
  return largest_du;
}

Status DynamicRelaxationRun::Relax() {
  clock_->Begin("relax", 0.1, 0.9, "dynamic relaxation");
  u_ = Eigen::VectorXd::Zero(n_dofs_);
  v_ = Eigen::VectorXd::Zero(n_dofs_);
  f_int_.resize(n_dofs_);
  f_int_prev_ = Eigen::VectorXd::Zero(n_dofs_);
  du_prev_ = Eigen::VectorXd::Zero(n_dofs_);
  f_ext_ = Eigen::VectorXd::Zero(n_dofs_);
  bool converged = false;
  double amplitude = 0, relative_estimate = 0;
  HistoryObserver history(&solution_->history, 50, 0, [&](const StepState& s) {
    double kinetic = 0;
    for (int i = 0; i < n_dofs_; ++i) kinetic += 0.5 * mass_(i / 3) * v_(i) * v_(i);
    return std::vector<double>{static_cast<double>(s.step), amplitude, residual_,
                               relative_estimate,           kinetic,   damping_ * kDt};
  });
  // The fraction: how far the out-of-balance force has come down to the
  // tolerance, on a log scale.
  ProgressObserver progress(clock_, 200, "dynamic relaxation", [&](const StepState& s) {
    return Format("step %lld, out of balance %.3g", static_cast<long long>(s.step), residual_);
  });
  const LoopThroughput throughput;
  for (; step_ < kMaxSteps; ++step_) {
    amplitude = RampAmplitude(step_);
    PBA_RETURN_IF_ERROR(Forces(amplitude));
    residual_ = Balance();
    estimate_ = DistanceToAnswer();
    relative_estimate = largest_u_ > 0 ? estimate_ / largest_u_ : estimate_;
    PBA_RETURN_IF_ERROR(history.AfterStep({step_, static_cast<double>(step_), 0, false}));
    if (step_ > kRampSteps && residual_ <= tolerance_ && relative_estimate <= tolerance_) {
      converged = true;
      break;
    }
    const double largest_du = Move();
    if (!std::isfinite(largest_du)) {
      return Status::Numerical(
          Format("dynamic relaxation stopped at step %lld: the motion is no longer finite",
                 static_cast<long long>(step_)));
    }
    increments_.push_back(largest_du);
    f_int_prev_ = f_int_;
    const double fraction =
        std::min(0.99, std::log10(std::max(residual_, tolerance_)) / std::log10(tolerance_));
    PBA_RETURN_IF_ERROR(progress.AfterStep({step_, static_cast<double>(step_), fraction, false}));
  }
  loop_s_ = throughput.Seconds();
  if (!converged) {
    return Status::Numerical(Format(
        "dynamic relaxation did not converge in %lld steps: out-of-balance force %.3g of the "
        "largest load or reaction, estimated distance to the answer %.3g of the largest "
        "displacement (tolerance %g); try NONLINEAR_STATIC, or a looser "
        "analysis.explicit_dynamics.relaxation_tolerance",
        static_cast<long long>(kMaxSteps), residual_, estimate_, tolerance_));
  }
  clock_->End();
  return Status::Ok();
}

Status DynamicRelaxationRun::Finish(StaticResult* result) {
  clock_->Begin("recover", 0.9, 0.95, "finite-strain fields");
  TledModel& tled = *tled_;
  tled.RecordStress(true);
  tled.InternalForce(u_, v_, &f_int_);
  const double max_strain = tled.RecoverFields(u_, solution_);
  Summary& summary = solution_->summary;
  ExplicitSummary& run = summary.explicit_run;
  run.ran = true;
  run.steps = step_;
  run.converged = true;
  run.relative_residual = residual_;
  run.element_updates_per_s =
      loop_s_ > 0 ? static_cast<double>(step_) * tled.num_elements() / loop_s_ : 0;
  summary.relative_residual = residual_;
  summary.error.note =
      "dynamic relaxation does not estimate the discretisation error; compare meshes with pba "
      "study convergence";
  summary.analysis = "dynamic relaxation (explicit, total Lagrangian, adaptive damping)";
  summary.notes.push_back(
      Format("dynamic relaxation: converged in %lld steps (loads ramped over the first %d), "
             "out-of-balance force %.3g of the largest load or reaction, estimated distance to the "
             "answer %.3g of the largest displacement (tolerance %g); %.3g element updates/s",
             static_cast<long long>(step_), kRampSteps, residual_,
             std::isfinite(estimate_) ? estimate_ : 0.0, tolerance_, run.element_updates_per_s));
  result->u = u_;
  result->internal_force = f_int_;
  result->external_force = f_ext_;
  double energy = 0;
  for (int e = 0; e < tled.num_elements(); ++e) {
    energy +=
        tled.reference_volume(e) * tled.material(e).model->Energy(tled.DeformationGradient(e));
  }
  result->strain_energy_j = energy;
  result->max_strain = max_strain;
  clock_->End();
  return Status::Ok();
}

}  // namespace

Status SolveDynamicRelaxation(const Problem& problem, PhaseClock* clock, Solution* solution,
                              StaticResult* result) {
  DynamicRelaxationRun run(problem, clock, solution);
  PBA_RETURN_IF_ERROR(run.Setup());
  PBA_RETURN_IF_ERROR(run.Relax());
  return run.Finish(result);
}

}  // namespace pba
