#include "explicit/explicit_dynamics.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "analysis/step_observer.h"
#include "core/format.h"
#include "explicit/central_difference.h"
#include "explicit/energy_balance.h"
#include "explicit/explicit_setup.h"
#include "explicit/impactor.h"
#include "explicit/sensors.h"
#include "explicit/tled_model.h"
#include "scene/time_curve.h"
#include "signal/butterworth.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;
// Steps between recomputations of the stable step.
constexpr int kStepCheckInterval = 20;
// Largest energy-balance error, relative to the energies, before the run is
// taken as unstable.
constexpr double kBlowUpError = 0.1;

std::string ElementName(const Mesh& mesh, int e) {
  if (mesh.region_names.empty()) return Format("element %d", e);
  return Format("element %d (%s)", e, mesh.region_names[mesh.element_region[e]].c_str());
}

// One EXPLICIT_DYNAMIC run: the setup, then per step the forces at t^n
// (internal with erosion, loads, impactors), the step size, the
// central-difference step (explicit/central_difference.h), the energy
// balance and what is recorded (history rows, frames, sensors, progress).
class ExplicitDynamicRun {
 public:
  ExplicitDynamicRun(const Problem& problem, PhaseClock* clock, Solution* solution)
      : problem_(problem),
        mesh_(problem.model.mesh),
        options_(problem.explicit_dynamics),
        clock_(clock),
        solution_(solution),
        run_(solution->summary.explicit_run),
        curve_(problem.time),
        n_nodes_(mesh_.num_nodes()),
        n_dofs_(3 * n_nodes_) {}

  Status Setup();
  Status Integrate();
  Status Finish(StaticResult* result);

 private:
  Status ChooseFirstStep();
  void MakeImpactors();
  void PlanOutputs();
  void Start();
  Status Forces(bool last);
  void Erode(TledEvaluation* eval);
  void ImpactorForces(double amplitude);
  void AdaptStep();
  Status Stopped(const std::string& why) const;
  std::vector<double> HistoryRow(double dt_next, double error) const;
  void RecordFrame(double amplitude, double dt_next);
  void Summarise();

  const Problem& problem_;
  const Mesh& mesh_;
  const ExplicitOptions& options_;
  PhaseClock* clock_;
  Solution* solution_;
  ExplicitSummary& run_;
  const TimeCurve curve_;
  const int n_nodes_, n_dofs_;

  ExplicitSetup setup_;
  TledModel* tled_ = nullptr;
  double factor_ = 1, stable0_ = 0;
  std::vector<Impactor> impactors_;
  SensorArray sensors_;
  double frame_interval_ = 0;

  // The state: displacements at t^n, velocities at t^(n-1/2), the forces at
  // t^n, and the nodes eroded elements left without any.
  Eigen::VectorXd u_, v_, f_int_, f_ext_, f_contact_;
  std::vector<char> orphan_;
  TledEvaluation eval_;
  Energies energy_;
  double t_ = 0, dt_ = 0, dt_prev_ = 0, next_frame_ = 0;
  std::vector<Eigen::Vector3d> body_force_prev_, centre_prev_;
  int64_t step_ = 0;
  double max_scale_ = 0, max_error_ = 0;
  double max_strain_ = 0;
};

Status ExplicitDynamicRun::Setup() {
  clock_->Begin("setup", 0.05, 0.1, "explicit model: masses, gradients, stable step");
  PBA_RETURN_IF_ERROR(MakeExplicitSetup(problem_, &setup_));
  tled_ = setup_.tled.get();
  factor_ = setup_.time_step_factor;
  PBA_RETURN_IF_ERROR(ChooseFirstStep());
  MakeImpactors();
  PBA_RETURN_IF_ERROR(
      SensorArray::Locate(problem_.outputs.sensors.sensors, mesh_, *tled_, &sensors_));
  PlanOutputs();
  clock_->End();
  return Status::Ok();
}

Status ExplicitDynamicRun::ChooseFirstStep() {
  TledModel& tled = *tled_;
  if (options_.mass_scaling_step_s > 0) {
    const TledModel::MassScaling scaled = tled.ScaleMass(options_.mass_scaling_step_s / factor_);
    run_.mass_scaled_elements = scaled.elements;
    run_.added_mass_kg = scaled.added_mass;
    run_.model_mass_kg = scaled.model_mass;
    solution_->summary.notes.push_back(Format(
        "mass scaling: %d elements whose stable step was below %.3g us took mass, %.3g kg added "
        "to %.4g kg (%.3g %%)",
        scaled.elements, options_.mass_scaling_step_s / factor_ * 1e6, scaled.added_mass,
        scaled.model_mass, 100 * scaled.added_mass / scaled.model_mass));
  }
  int controlling = -1;
  double length = 0;
  stable0_ = tled.StableTimeStep(nullptr, nullptr, &controlling, &length);
  if (!(stable0_ > 0) || !std::isfinite(stable0_)) {
    return Status::Numerical(
        "explicit dynamics: no stable time step (is every element's wave "
        "speed finite and positive?)");
  }
  dt_ = factor_ * stable0_;
  tled.SetTimeStep(dt_);
  run_.ran = true;
  run_.stable_step_s = stable0_;
  run_.first_step_s = dt_;
  run_.controlling_element =
      ElementName(mesh_, controlling) + Format(", length %.3g mm", length / kMm);
  return Status::Ok();
}

void ExplicitDynamicRun::MakeImpactors() {
  for (const Contact& c : problem_.contacts) {
    std::vector<int> candidates = mesh_.face_sets.at(c.set).nodes;
    if (options_.erosion_strain > 0) {
      candidates.resize(n_nodes_);
      for (int n = 0; n < n_nodes_; ++n) candidates[n] = n;
    }
    impactors_.emplace_back(c, std::move(candidates), tled_->lumped_mass(), dt_);
  }
  if (impactors_.empty()) return;
  run_.contact_stiffness_min_n_per_m = std::numeric_limits<double>::infinity();
  for (const Impactor& imp : impactors_) {
    run_.contact_stiffness_min_n_per_m =
        std::min(run_.contact_stiffness_min_n_per_m, imp.min_stiffness());
    run_.contact_stiffness_max_n_per_m =
        std::max(run_.contact_stiffness_max_n_per_m, imp.max_stiffness());
  }
}

// The sensors record every step; their table is resampled every interval_s
// and filtered at that rate (the filter was checked with the scene,
// SensorOptions::Validate). History rows come every output interval, and at
// most a bounded number of displacement frames go into result.h5.
void ExplicitDynamicRun::PlanOutputs() {
  const double end_time = curve_.end_s();
  const int max_frames =
      static_cast<int>(std::clamp<double>(2.5e8 / (24.0 * std::max(1, n_nodes_)), 2,
                                          1 + std::ceil(end_time / options_.output_interval_s)));
  frame_interval_ = end_time / std::max(1, max_frames - 1);
  solution_->history_columns = {"time_s",          "step_s",      "kinetic_j", "internal_j",
                                "hourglass_j",     "contact_j",   "damping_j", "eroded_j",
                                "external_work_j", "energy_error"};
  for (const Impactor& imp : impactors_) {
    for (const char* axis : {"x", "y", "z"}) {
      solution_->history_columns.push_back(imp.name() + " force " + axis + " [N]");
    }
  }
}

// Prescribed displacements and velocities at a(0), the kinetic energy they
// give, the impactors where they start.
void ExplicitDynamicRun::Start() {
  u_ = Eigen::VectorXd::Zero(n_dofs_);
  v_ = Eigen::VectorXd::Zero(n_dofs_);
  f_int_.resize(n_dofs_);
  f_ext_ = Eigen::VectorXd::Zero(n_dofs_);
  f_contact_ = Eigen::VectorXd::Zero(n_dofs_);
  const std::vector<PrescribedDof>& prescribed = setup_.prescribed;
  const double a0 = curve_.Amplitude(0);
  for (int i = 0; i < n_dofs_; ++i) {
    if (prescribed[i].kind == PrescribedDof::kDisplacement) u_(i) = prescribed[i].value * a0;
    if (prescribed[i].kind == PrescribedDof::kVelocity) v_(i) = prescribed[i].value * a0;
  }
  const Eigen::VectorXd& node_mass = tled_->lumped_mass();
  for (int i = 0; i < n_dofs_; ++i) {
    energy_.initial_kinetic += 0.5 * node_mass(i / 3) * v_(i) * v_(i);
  }
  body_force_prev_.assign(impactors_.size(), Eigen::Vector3d::Zero());
  centre_prev_.resize(impactors_.size());
  for (std::size_t k = 0; k < impactors_.size(); ++k) {
    centre_prev_[k] = impactors_[k].Centre(curve_.Amplitude(0));
  }
}

// Elements strained past the erosion limit, or inverted, leave; so do the
// nodes left without an element, with their kinetic energy.
void ExplicitDynamicRun::Erode(TledEvaluation* eval) {
  TledModel& tled = *tled_;
  // Which elements go, in parallel; a cheap bound first: the largest
  // eigenvalue of C is at most its largest absolute row sum (Gershgorin), so
  // most elements need no eigenvalues.
  std::vector<char> erode(tled.num_elements(), 0);
  const double limit = 1 + 2 * options_.erosion_strain;  // on the eigenvalue of C
#pragma omp parallel for schedule(static) num_threads(setup_.options.threads.threads())
  for (int e = 0; e < tled.num_elements(); ++e) {
    if (tled.eroded(e)) continue;
    const Eigen::Matrix3d f = tled.DeformationGradient(e);
    if (!(f.determinant() > 0)) {
      erode[e] = 1;
      continue;
    }
    const Eigen::Matrix3d c = f.transpose() * f;
    if (c.cwiseAbs().rowwise().sum().maxCoeff() <= limit) continue;
    erode[e] = LargestPrincipalStrain(f) > options_.erosion_strain;
  }
  if (std::find(erode.begin(), erode.end(), 1) == erode.end()) return;
  // The energy the eroded elements take: the stored total's drop.
  const double stored_before = tled.StoredEnergy();
  for (int e = 0; e < tled.num_elements(); ++e) {
    if (!erode[e]) continue;
    tled.Erode(e);
    ++run_.eroded_elements;
    run_.eroded_mass_kg += tled.material(e).density * tled.reference_volume(e);
  }
  energy_.eroded_elements += stored_before - tled.StoredEnergy();
  orphan_.assign(n_nodes_, 0);
  const Eigen::VectorXd& node_mass = tled.lumped_mass();
  for (int n : tled.OrphanNodes()) {
    orphan_[n] = 1;
    energy_.orphan_kinetic += 0.5 * node_mass(n) * v_.segment<3>(3 * n).squaredNorm();
    v_.segment<3>(3 * n).setZero();
  }
  *eval = tled.InternalForce(u_, v_, &f_int_);  // without the eroded elements
}

void ExplicitDynamicRun::ImpactorForces(double amplitude) {
  f_contact_.setZero();
  for (std::size_t k = 0; k < impactors_.size(); ++k) {
    Impactor& imp = impactors_[k];
    imp.AddForces(mesh_, u_, amplitude, orphan_, &f_contact_);
    const Eigen::Vector3d centre = imp.Centre(amplitude);
    const Eigen::Vector3d force = imp.state().force_on_body;
    // The body's work on the tissue: -F_body . dc.
    energy_.body_work -= 0.5 * (force + body_force_prev_[k]).dot(centre - centre_prev_[k]);
    body_force_prev_[k] = force;
    centre_prev_[k] = centre;
  }
}

// The forces at t^n: internal (after erosion), loads at a(t^n), impactors.
Status ExplicitDynamicRun::Forces(bool last) {
  TledModel& tled = *tled_;
  tled.RecordStress(last);
  eval_ = tled.InternalForce(u_, v_, &f_int_);
  if (options_.erosion_strain > 0) Erode(&eval_);
  if (eval_.inverted_element >= 0) {
    return Stopped(Format(
        "%s inverted (det F <= 0)%s", ElementName(mesh_, eval_.inverted_element).c_str(),
        factor_ > 1
            ? Format("; the time step factor %g is above the stability limit 1", factor_).c_str()
            : "; the deformation is too large for this mesh (a finer mesh, erosion "
              "or a slower load)"));
  }
  energy_.hourglass = eval_.hourglass_energy;
  const double amplitude = curve_.Amplitude(t_);
  if (setup_.has_loads) {
    f_ext_ = amplitude * (setup_.loads->follows_deformation() ? setup_.loads->Force(u_)
                                                              : setup_.loads->dead_force());
  }
  if (!impactors_.empty()) ImpactorForces(amplitude);
  return Status::Ok();
}

// The next step: shrink if the current elements need it. An impactor
// crushes the elements at its tip within a few steps, so with one the check
// is made every step.
void ExplicitDynamicRun::AdaptStep() {
  if (step_ == 0 || (impactors_.empty() && step_ % kStepCheckInterval != 0)) return;
  TledModel& tled = *tled_;
  int e = -1;
  double l = 0;
  double stable;
  if (options_.mass_scaling_step_s > 0) {
    // Crushed elements take mass rather than shrink the step.
    const TledModel::MassScaling scaled =
        tled.RescaleMass(u_, &v_, options_.mass_scaling_step_s / factor_, &stable, &e, &l);
    run_.mass_scaled_elements += scaled.elements;
    run_.added_mass_kg += scaled.added_mass;
    energy_.mass_scaling += scaled.added_kinetic;
  } else {
    stable = tled.StableTimeStep(&u_, &v_, &e, &l);
  }
  if (factor_ * stable < dt_ * (1 - 1e-12)) {
    dt_ = factor_ * stable;
    tled.SetTimeStep(dt_);
    ++run_.step_reductions;
    run_.controlling_element = ElementName(mesh_, e) + Format(", length %.3g mm", l / kMm);
  }
}

Status ExplicitDynamicRun::Stopped(const std::string& why) const {
  return Status::Numerical(Format("explicit dynamics stopped at step %lld, t = %.6g s: %s",
                                  static_cast<long long>(step_), t_, why.c_str()));
}

// A history row (every output interval): the energies, the balance error
// relative to the largest energy so far, each impactor's force.
std::vector<double> ExplicitDynamicRun::HistoryRow(double dt_next, double error) const {
  std::vector<double> row = {t_,
                             dt_next,
                             energy_.kinetic,
                             energy_.Internal(),
                             energy_.hourglass,
                             energy_.Contact(),
                             energy_.damping.total,
                             energy_.Eroded(),
                             energy_.External(),
                             max_scale_ > 0 ? error / max_scale_ : 0.0};
  for (const Impactor& imp : impactors_) {
    for (int c = 0; c < 3; ++c) row.push_back(imp.state().force_on_body(c));
  }
  return row;
}

// A displacement frame every frame interval (at t^n: u^(n+1) less the step
// just taken).
void ExplicitDynamicRun::RecordFrame(double amplitude, double dt_next) {
  if (t_ >= next_frame_ - 1e-3 * dt_ && problem_.outputs.displacement) {
    solution_->step_time_s.push_back(t_);
    solution_->step_load_factor.push_back(amplitude);
    for (int i = 0; i < n_dofs_; ++i) {
      solution_->step_displacement_mm.push_back((u_(i) - dt_next * v_(i)) / kMm);
    }
    next_frame_ += frame_interval_;
  }
}

Status ExplicitDynamicRun::Integrate() {
  const double end_time = curve_.end_s();
  clock_->Begin("integrate", 0.1, 0.9,
                Format("central difference, step %.3g us (%.2f of the stable %.3g us)", dt_ * 1e6,
                       factor_, stable0_ * 1e6));
  Start();
  const CentralDifference integrator(tled_->lumped_mass(), setup_.prescribed,
                                     options_.mass_damping_per_s, setup_.options.threads);
  const std::string unstable =
      factor_ > 1 ? Format("; the time step factor %g is above the stability limit 1", factor_)
                  : "";
  // The history row of t^n is written after the step from t^n (its
  // balance error is known then), on the schedule of the step before it.
  double error = 0, dt_next = 0;
  HistoryObserver history(&solution_->history, 0, options_.output_interval_s,
                          [&](const StepState&) { return HistoryRow(dt_next, error); });
  ProgressObserver progress(clock_, 200, "explicit dynamics", [&](const StepState& s) {
    return Format("t = %.4g us of %.4g us, step %lld", t_ * 1e6, end_time * 1e6,
                  static_cast<long long>(s.step));
  });
  const LoopThroughput throughput;
  bool last = false;
  while (true) {
    history.SetStep(dt_);
    PBA_RETURN_IF_ERROR(Forces(last));
    if (last) break;
    AdaptStep();
    StepTimes times;
    times.dt_prev = dt_prev_;
    times.dt_next = dt_;
    if (t_ + times.dt_next >= end_time * (1 - 1e-12)) {
      times.dt_next = end_time - t_;
      last = true;
    }
    times.amplitude_half = curve_.Amplitude(t_ + 0.5 * times.dt_next);
    times.amplitude_next = curve_.Amplitude(t_ + times.dt_next);
    sensors_.Before(v_);
    const StepWork work =
        integrator.Advance({&f_int_, &f_ext_, &f_contact_}, times, orphan_, &u_, &v_);
    energy_.Add(work);
    if (!work.finite) return Stopped("the velocity is no longer finite" + unstable);
    // Energy balance at t^n (the kinetic energy from the mean of the half
    // steps around it).
    max_scale_ = std::max(max_scale_, energy_.Scale());
    error = energy_.Error();
    max_error_ = std::max(max_error_, error);
    if (step_ > 50 && max_scale_ > 0 && error > kBlowUpError * max_scale_) {
      return Stopped(Format(
          "the energy balance is off by %.3g J, %.0f %% of the energies (kinetic %.3g J, "
          "external work %.3g J): the integration is unstable%s; the step is %.3g us, %g of the "
          "stable step",
          error, 100 * error / max_scale_, energy_.kinetic, energy_.External(),
          factor_ > 1 ? " (the time step factor is above 1)" : "", dt_ * 1e6, factor_));
    }
    sensors_.Sample(t_, *tled_, v_);
    dt_next = times.dt_next;
    PBA_RETURN_IF_ERROR(history.AfterStep({step_, t_, t_ / end_time, false}));
    RecordFrame(curve_.Amplitude(t_), times.dt_next);
    t_ += times.dt_next;
    dt_prev_ = times.dt_next;
    ++step_;
    PBA_RETURN_IF_ERROR(progress.AfterStep({step_, t_, t_ / end_time, last}));
  }
  run_.element_updates_per_s = throughput.UpdatesPerSecond(step_, tled_->num_elements());
  clock_->End();
  return Status::Ok();
}

// What the summary says of the run: the analysis, the steps, the energies,
// each impactor's force.
void ExplicitDynamicRun::Summarise() {
  Summary& summary = solution_->summary;
  summary.error.note =
      "explicit dynamics does not estimate the discretisation error; compare meshes with pba "
      "study convergence (docs/scenes.md)";
  summary.analysis = Format(
      "explicit dynamics (central difference, total Lagrangian, lumped mass) to %.4g ms", t_ * 1e3);
  const double alpha = options_.mass_damping_per_s;
  summary.notes.push_back(Format(
      "explicit: %lld steps of %.3g us (%.2f x the stable %.3g us, set by %s), %d reductions; "
      "bulk viscosity %g (linear) and %g (quadratic)%s",
      static_cast<long long>(step_), run_.first_step_s * 1e6, factor_, stable0_ * 1e6,
      run_.controlling_element.c_str(), run_.step_reductions, setup_.options.bulk_viscosity_linear,
      setup_.options.bulk_viscosity_quadratic,
      alpha > 0 ? Format("; mass damping %g 1/s", alpha).c_str() : ""));
  if (energy_.mass_scaling != 0) {
    summary.notes.push_back(Format(
        "mass scaling during the run: %d element scalings, %.3g kg in all; the nodes kept their "
        "momentum, losing %.3g J of kinetic energy (part of the balance)",
        run_.mass_scaled_elements, run_.added_mass_kg, -energy_.mass_scaling));
  }
  summary.notes.push_back(Format(
      "energy at the end: kinetic %.4g J, internal %.4g J, hourglass %.3g J, contact %.3g J, "
      "damping %.3g J, eroded %.3g J, external work %.4g J; balance error at most %.3g %%",
      run_.kinetic_j, run_.internal_j, run_.hourglass_j, run_.contact_j, run_.damping_j,
      run_.eroded_j, run_.external_work_j, 100 * run_.max_energy_error));
  for (const Impactor& imp : impactors_) {
    ContactSummary c;
    c.name = imp.name();
    for (int k = 0; k < 3; ++k) c.force_n[k] = imp.state().force_on_body(k);
    c.peak_force_n = imp.state().peak_force;
    c.max_penetration_mm = imp.state().penetration / kMm;
    c.penalty_pa_per_mm = 0;
    summary.contacts.push_back(c);
  }
}

Status ExplicitDynamicRun::Finish(StaticResult* result) {
  clock_->Begin("recover", 0.9, 0.95, "end state, sensors, energies");
  // The end state, written as the last frame and row.
  if (problem_.outputs.displacement) {
    solution_->step_time_s.push_back(t_);
    solution_->step_load_factor.push_back(curve_.Amplitude(t_));
    for (int i = 0; i < n_dofs_; ++i) solution_->step_displacement_mm.push_back(u_(i) / kMm);
  }
  const SensorOptions& sensing = problem_.outputs.sensors;
  PBA_RETURN_IF_ERROR(sensors_.Finish(sensing.filter_order, sensing.filter_cutoff_hz,
                                      sensing.interval_s, solution_));
  run_.steps = step_;
  run_.end_time_s = t_;
  run_.last_step_s = dt_;
  run_.kinetic_j = energy_.kinetic;
  run_.internal_j = energy_.Internal();
  run_.hourglass_j = energy_.hourglass;
  run_.contact_j = energy_.Contact();
  run_.damping_j = energy_.damping.total;
  run_.eroded_j = energy_.Eroded();
  run_.external_work_j = energy_.External();
  // The largest balance error over the run relative to the largest energy
  // of the run.
  if (max_scale_ > 0) run_.max_energy_error = max_error_ / max_scale_;
  max_strain_ = tled_->RecoverFields(u_, solution_);
  Summarise();
  result->u = u_;
  result->internal_force = f_int_;
  result->external_force = f_ext_ + f_contact_;
  result->strain_energy_j = energy_.Internal();
  result->max_strain = max_strain_;
  clock_->End();
  return Status::Ok();
}

}  // namespace

Status SolveExplicitDynamic(const Problem& problem, PhaseClock* clock, Solution* solution,
                            StaticResult* result) {
  ExplicitDynamicRun run(problem, clock, solution);
  PBA_RETURN_IF_ERROR(run.Setup());
  PBA_RETURN_IF_ERROR(run.Integrate());
  return run.Finish(result);
}

}  // namespace pba
