#include "explicit/explicit_dynamics.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "analysis/time_curve.h"
#include "core/format.h"
#include "explicit/explicit_setup.h"
#include "explicit/impactor.h"
#include "explicit/sensors.h"
#include "explicit/tled_model.h"
#include "signal/butterworth.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;
// Steps between recomputations of the stable step.
constexpr int kStepCheckInterval = 20;
// Largest energy-balance error, relative to the energies, before the run is
// taken as unstable.
constexpr double kBlowUpError = 0.1;

// Running energies [J]; each work is a trapezoidal sum over the steps,
// W^n = W^(n-1) + (f^(n-1) + f^n) . du^(n-1/2) / 2, kept as the part
// through t^n plus the half that waits for the next force.
struct Work {
  double total = 0, carry = 0;
  // At step n: a = f^n . du^(n-1/2) / 2, b = f^n . du^(n+1/2) / 2.
  void Step(double a, double b) {
    total += carry + a;
    carry = b;
  }
};

struct Energies {
  Work internal, external, damping, contact_nodes;
  double kinetic = 0, hourglass = 0, eroded_elements = 0, orphan_kinetic = 0;
  double initial_kinetic = 0;  // of the velocities given at t = 0
  double mass_scaling = 0;     // kinetic energy change by mass added during the run (<= 0)
  double body_work = 0;        // impactors' work on the tissue
  double Internal() const { return internal.total - hourglass - eroded_elements; }
  double Contact() const { return body_work - contact_nodes.total; }
  double External() const { return external.total + body_work; }
  double Eroded() const { return eroded_elements + orphan_kinetic; }
  double Error() const {
    return std::abs(kinetic + Internal() + hourglass + Contact() + damping.total + Eroded() -
                    External() - initial_kinetic - mass_scaling);
  }
  double Scale() const {
    return std::max({std::abs(External()), kinetic, std::abs(internal.total)});
  }
};

std::string ElementName(const Mesh& mesh, int e) {
  if (mesh.region_names.empty()) return Format("element %d", e);
  return Format("element %d (%s)", e, mesh.region_names[mesh.element_region[e]].c_str());
}

}  // namespace

Status SolveExplicitDynamic(const Problem& problem, PhaseClock* clock, Solution* solution,
                            StaticResult* result) {
  const Mesh& mesh = problem.model.mesh;
  Summary& summary = solution->summary;
  const ExplicitOptions& options = problem.explicit_dynamics;
  clock->Begin("setup", 0.05, 0.1, "explicit model: masses, gradients, stable step");
  ExplicitSetup setup;
  PBA_RETURN_IF_ERROR(MakeExplicitSetup(problem, &setup));
  TledModel& tled = *setup.tled;
  const int n_nodes = mesh.num_nodes(), n_dofs = 3 * n_nodes;
  const TimeCurve curve(problem.time);
  const double end_time = curve.end_s();
  const double factor = setup.time_step_factor;
  ExplicitSummary& run = summary.explicit_run;
  if (options.mass_scaling_step_s > 0) {
    const TledModel::MassScaling scaled = tled.ScaleMass(options.mass_scaling_step_s / factor);
    run.mass_scaled_elements = scaled.elements;
    run.added_mass_kg = scaled.added_mass;
    run.model_mass_kg = scaled.model_mass;
    summary.notes.push_back(Format(
        "mass scaling: %d elements whose stable step was below %.3g us took mass, %.3g kg added "
        "to %.4g kg (%.3g %%)",
        scaled.elements, options.mass_scaling_step_s / factor * 1e6, scaled.added_mass,
        scaled.model_mass, 100 * scaled.added_mass / scaled.model_mass));
  }
  int controlling = -1;
  double length = 0;
  const double stable0 = tled.StableTimeStep(nullptr, nullptr, &controlling, &length);
  if (!(stable0 > 0) || !std::isfinite(stable0)) {
    return Status::Numerical(
        "explicit dynamics: no stable time step (is every element's wave "
        "speed finite and positive?)");
  }
  double dt = factor * stable0;
  tled.SetTimeStep(dt);
  run.ran = true;
  run.stable_step_s = stable0;
  run.first_step_s = dt;
  run.controlling_element =
      ElementName(mesh, controlling) + Format(", length %.3g mm", length / kMm);
  const Eigen::VectorXd& node_mass = tled.lumped_mass();

  // Impactors.
  std::vector<Impactor> impactors;
  for (const Contact& c : problem.contacts) {
    std::vector<int> candidates = mesh.face_sets.at(c.set).nodes;
    if (options.erosion_strain > 0) {
      candidates.resize(n_nodes);
      for (int n = 0; n < n_nodes; ++n) candidates[n] = n;
    }
    impactors.emplace_back(c, std::move(candidates), node_mass, dt);
  }
  if (!impactors.empty()) {
    run.contact_stiffness_min_n_per_m = std::numeric_limits<double>::infinity();
    for (const Impactor& imp : impactors) {
      run.contact_stiffness_min_n_per_m =
          std::min(run.contact_stiffness_min_n_per_m, imp.min_stiffness());
      run.contact_stiffness_max_n_per_m =
          std::max(run.contact_stiffness_max_n_per_m, imp.max_stiffness());
    }
  }
  // Sensors.
  SensorArray sensors;
  const SensorOptions& sensing = problem.outputs.sensors;
  PBA_RETURN_IF_ERROR(SensorArray::Locate(sensing.sensors, mesh, tled, &sensors));
  // The sensors record every step; their table is resampled every
  // interval_s and filtered at that rate (the filter was checked with the
  // scene, SensorOptions::Validate).
  const double sample_interval = sensing.interval_s;
  const int filter_order = sensing.filter_order;
  const double cutoff_hz = sensing.filter_cutoff_hz;
  const double output_interval = options.output_interval_s;
  // At most this many frames of the displacement go into result.h5.
  const int max_frames = static_cast<int>(std::clamp<double>(
      2.5e8 / (24.0 * std::max(1, n_nodes)), 2, 1 + std::ceil(end_time / output_interval)));
  const double frame_interval = end_time / std::max(1, max_frames - 1);

  // History columns.
  solution->history_columns = {"time_s",          "step_s",      "kinetic_j", "internal_j",
                               "hourglass_j",     "contact_j",   "damping_j", "eroded_j",
                               "external_work_j", "energy_error"};
  for (const Impactor& imp : impactors) {
    for (const char* axis : {"x", "y", "z"}) {
      solution->history_columns.push_back(imp.name() + " force " + axis + " [N]");
    }
  }
  clock->End();

  clock->Begin("integrate", 0.1, 0.9,
               Format("central difference, step %.3g us (%.2f of the stable %.3g us)", dt * 1e6,
                      factor, stable0 * 1e6));
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n_dofs), v = Eigen::VectorXd::Zero(n_dofs);
  Eigen::VectorXd f_int(n_dofs), f_ext = Eigen::VectorXd::Zero(n_dofs),
                                 f_contact = Eigen::VectorXd::Zero(n_dofs);
  std::vector<char> orphan;
  const std::vector<PrescribedDof>& prescribed = setup.prescribed;
  // Start: prescribed displacements at a(0), velocities at a(0).
  {
    const double a0 = curve.Amplitude(0);
    for (int i = 0; i < n_dofs; ++i) {
      if (prescribed[i].kind == PrescribedDof::kDisplacement) u(i) = prescribed[i].value * a0;
      if (prescribed[i].kind == PrescribedDof::kVelocity) v(i) = prescribed[i].value * a0;
    }
  }
  const double alpha = options.mass_damping_per_s;
  Energies energy;
  for (int i = 0; i < n_dofs; ++i) energy.initial_kinetic += 0.5 * node_mass(i / 3) * v(i) * v(i);
  double t = 0, dt_prev = 0, next_output = 0, next_frame = 0;
  std::vector<Eigen::Vector3d> body_force_prev(impactors.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> centre_prev(impactors.size());
  for (std::size_t k = 0; k < impactors.size(); ++k)
    centre_prev[k] = impactors[k].Centre(curve.Amplitude(0));
  int64_t step = 0;
  double max_scale = 0, max_error = 0;
  const auto loop_start = std::chrono::steady_clock::now();
  bool last = false;
  while (true) {
    // Forces at t^n.
    const bool output = t >= next_output - 1e-3 * dt || last;
    tled.RecordStress(last);
    TledEvaluation eval = tled.InternalForce(u, v, &f_int);
    // Erosion: elements strained past the limit, or inverted, leave.
    if (options.erosion_strain > 0) {
      // Which elements go, in parallel; a cheap bound first: the largest
      // eigenvalue of C is at most its largest absolute row sum
      // (Gershgorin), so most elements need no eigenvalues.
      std::vector<char> erode(tled.num_elements(), 0);
      const double limit = 1 + 2 * options.erosion_strain;  // on the eigenvalue of C
#pragma omp parallel for schedule(static)
      for (int e = 0; e < tled.num_elements(); ++e) {
        if (tled.eroded(e)) continue;
        const Eigen::Matrix3d f = tled.DeformationGradient(e);
        if (!(f.determinant() > 0)) {
          erode[e] = 1;
          continue;
        }
        const Eigen::Matrix3d c = f.transpose() * f;
        if (c.cwiseAbs().rowwise().sum().maxCoeff() <= limit) continue;
        erode[e] = LargestPrincipalStrain(f) > options.erosion_strain;
      }
      bool eroded_now = false;
      // The energy the eroded elements take: the stored total's drop.
      double stored_before = 0;
      if (std::find(erode.begin(), erode.end(), 1) != erode.end()) {
        stored_before = tled.StoredEnergy();
      }
      for (int e = 0; e < tled.num_elements(); ++e) {
        if (!erode[e]) continue;
        tled.Erode(e);
        ++run.eroded_elements;
        run.eroded_mass_kg += tled.material(e).density * tled.reference_volume(e);
        eroded_now = true;
      }
      if (eroded_now) {
        energy.eroded_elements += stored_before - tled.StoredEnergy();
        orphan.assign(n_nodes, 0);
        for (int n : tled.OrphanNodes()) {
          orphan[n] = 1;
          // The node leaves: its kinetic energy with it.
          energy.orphan_kinetic += 0.5 * node_mass(n) * v.segment<3>(3 * n).squaredNorm();
          v.segment<3>(3 * n).setZero();
        }
        eval = tled.InternalForce(u, v, &f_int);  // without the eroded elements
      }
    }
    if (eval.inverted_element >= 0) {
      return Status::Numerical(Format(
          "explicit dynamics stopped at step %lld, t = %.6g s: %s inverted (det F <= 0)%s",
          static_cast<long long>(step), t, ElementName(mesh, eval.inverted_element).c_str(),
          factor > 1
              ? Format("; the time step factor %g is above the stability limit 1", factor).c_str()
              : "; the deformation is too large for this mesh (a finer mesh, erosion "
                "or a slower load)"));
    }
    energy.hourglass = eval.hourglass_energy;
    const double amplitude = curve.Amplitude(t);
    if (setup.has_loads) {
      f_ext = amplitude * (setup.loads->follows_deformation() ? setup.loads->Force(u)
                                                              : setup.loads->dead_force());
    }
    if (!impactors.empty()) {
      f_contact.setZero();
      for (std::size_t k = 0; k < impactors.size(); ++k) {
        Impactor& imp = impactors[k];
        imp.AddForces(mesh, u, amplitude, orphan, &f_contact);
        const Eigen::Vector3d centre = imp.Centre(amplitude);
        const Eigen::Vector3d force = imp.state().force_on_body;
        // The body's work on the tissue: -F_body . dc.
        energy.body_work -= 0.5 * (force + body_force_prev[k]).dot(centre - centre_prev[k]);
        body_force_prev[k] = force;
        centre_prev[k] = centre;
      }
    }
    if (last) break;
    // The next step: shrink if the current elements need it. An impactor
    // crushes the elements at its tip within a few steps, so with one the
    // check is made every step.
    if (step > 0 && (!impactors.empty() || step % kStepCheckInterval == 0)) {
      int e = -1;
      double l = 0;
      double stable;
      if (options.mass_scaling_step_s > 0) {
        // Crushed elements take mass rather than shrink the step.
        const TledModel::MassScaling scaled =
            tled.RescaleMass(u, &v, options.mass_scaling_step_s / factor, &stable, &e, &l);
        run.mass_scaled_elements += scaled.elements;
        run.added_mass_kg += scaled.added_mass;
        energy.mass_scaling += scaled.added_kinetic;
      } else {
        stable = tled.StableTimeStep(&u, &v, &e, &l);
      }
      if (factor * stable < dt * (1 - 1e-12)) {
        dt = factor * stable;
        tled.SetTimeStep(dt);
        ++run.step_reductions;
        run.controlling_element = ElementName(mesh, e) + Format(", length %.3g mm", l / kMm);
      }
    }
    double dt_next = dt;
    if (t + dt_next >= end_time * (1 - 1e-12)) {
      dt_next = end_time - t;
      last = true;
    }
    const double dt_mid = 0.5 * (dt_prev + dt_next);
    const double a_half = curve.Amplitude(t + 0.5 * dt_next);
    const double a_next = curve.Amplitude(t + dt_next);
    sensors.Before(v);
    double w_int_a = 0, w_int_b = 0, w_ext_a = 0, w_ext_b = 0, w_damp_a = 0, w_damp_b = 0,
           w_c_a = 0, w_c_b = 0, kinetic = 0;
    bool finite = true;
#pragma omp parallel for schedule(static) reduction(+ : w_int_a, w_int_b, w_ext_a, w_ext_b, \
                                                        w_damp_a, w_damp_b, w_c_a, w_c_b, kinetic) \
    reduction(&& : finite)
    for (int i = 0; i < n_dofs; ++i) {
      const double m = node_mass(i / 3);
      const double v_old = v(i);
      double v_new;
      double reaction = 0;
      const PrescribedDof& p = prescribed[i];
      if (p.kind == PrescribedDof::kVelocity) {
        v_new = p.value * a_half;
      } else if (p.kind == PrescribedDof::kDisplacement) {
        v_new = (p.value * a_next - u(i)) / dt_next;
      } else if (m > 0 && (orphan.empty() || !orphan[i / 3])) {
        const double acc = (f_ext(i) + f_contact(i) - f_int(i)) / m;
        const double h = 0.5 * alpha * dt_mid;
        v_new = ((1 - h) * v_old + dt_mid * acc) / (1 + h);
      } else {
        v_new = 0;
      }
      if (p.kind != PrescribedDof::kFree && dt_mid > 0) {
        // The force that holds the motion: M a + f_int - f_ext - f_contact.
        reaction = m * (v_new - v_old) / dt_mid + f_int(i) - f_ext(i) - f_contact(i);
      }
      const double du_prev = dt_prev * v_old, du_next = dt_next * v_new;
      const double v_mid = 0.5 * (v_old + v_new);
      w_int_a += 0.5 * f_int(i) * du_prev, w_int_b += 0.5 * f_int(i) * du_next;
      const double applied = f_ext(i) + reaction;
      w_ext_a += 0.5 * applied * du_prev, w_ext_b += 0.5 * applied * du_next;
      w_c_a += 0.5 * f_contact(i) * du_prev, w_c_b += 0.5 * f_contact(i) * du_next;
      if (p.kind == PrescribedDof::kFree && alpha > 0) {
        const double damping = alpha * m * v_mid;
        w_damp_a += 0.5 * damping * du_prev, w_damp_b += 0.5 * damping * du_next;
      }
      kinetic += 0.5 * m * v_mid * v_mid;
      v(i) = v_new;
      u(i) += du_next;
      finite = finite && std::isfinite(v_new);
    }
    energy.internal.Step(w_int_a, w_int_b);
    energy.external.Step(w_ext_a, w_ext_b);
    energy.damping.Step(w_damp_a, w_damp_b);
    energy.contact_nodes.Step(w_c_a, w_c_b);
    energy.kinetic = kinetic;
    if (!finite) {
      return Status::Numerical(Format(
          "explicit dynamics stopped at step %lld, t = %.6g s: the velocity is no longer finite%s",
          static_cast<long long>(step), t,
          factor > 1
              ? Format("; the time step factor %g is above the stability limit 1", factor).c_str()
              : ""));
    }
    // Energy balance at t^n (the kinetic energy from the mean of the half
    // steps around it).
    max_scale = std::max(max_scale, energy.Scale());
    const double error = energy.Error();
    max_error = std::max(max_error, error);
    if (step > 50 && max_scale > 0 && error > kBlowUpError * max_scale) {
      return Status::Numerical(Format(
          "explicit dynamics stopped at step %lld, t = %.6g s: the energy balance is off by %.3g "
          "J, %.0f %% of the energies (kinetic %.3g J, external work %.3g J): the integration "
          "is unstable%s; the step is %.3g us, %g of the stable step",
          static_cast<long long>(step), t, error, 100 * error / max_scale, energy.kinetic,
          energy.External(), factor > 1 ? " (the time step factor is above 1)" : "", dt * 1e6,
          factor));
    }
    sensors.Sample(t, tled, v);
    if (output) {
      std::vector<double> row = {t,
                                 dt_next,
                                 energy.kinetic,
                                 energy.Internal(),
                                 energy.hourglass,
                                 energy.Contact(),
                                 energy.damping.total,
                                 energy.Eroded(),
                                 energy.External(),
                                 max_scale > 0 ? error / max_scale : 0.0};
      for (const Impactor& imp : impactors) {
        for (int c = 0; c < 3; ++c) row.push_back(imp.state().force_on_body(c));
      }
      solution->history.push_back(std::move(row));
      next_output += output_interval;
    }
    if (t >= next_frame - 1e-3 * dt && problem.outputs.displacement) {
      solution->step_time_s.push_back(t);
      solution->step_load_factor.push_back(amplitude);
      for (int i = 0; i < n_dofs; ++i) {
        solution->step_displacement_mm.push_back((u(i) - dt_next * v(i)) / kMm);
      }
      next_frame += frame_interval;
    }
    t += dt_next;
    dt_prev = dt_next;
    ++step;
    if (step % 200 == 0) {
      clock->Update(t / end_time, Format("t = %.4g us of %.4g us, step %lld", t * 1e6,
                                         end_time * 1e6, static_cast<long long>(step)));
      if (clock->cancelled()) return Status::Cancelled("cancelled during explicit dynamics");
    }
  }
  const double loop_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  clock->End();

  clock->Begin("recover", 0.9, 0.95, "end state, sensors, energies");
  // The end state, written as the last frame and row.
  if (problem.outputs.displacement) {
    solution->step_time_s.push_back(t);
    solution->step_load_factor.push_back(curve.Amplitude(t));
    for (int i = 0; i < n_dofs; ++i) solution->step_displacement_mm.push_back(u(i) / kMm);
  }
  PBA_RETURN_IF_ERROR(sensors.Finish(filter_order, cutoff_hz, sample_interval, solution));
  run.steps = step;
  run.end_time_s = t;
  run.last_step_s = dt;
  run.kinetic_j = energy.kinetic;
  run.internal_j = energy.Internal();
  run.hourglass_j = energy.hourglass;
  run.contact_j = energy.Contact();
  run.damping_j = energy.damping.total;
  run.eroded_j = energy.Eroded();
  run.external_work_j = energy.External();
  // The largest balance error over the run relative to the largest energy
  // of the run.
  if (max_scale > 0) run.max_energy_error = max_error / max_scale;
  run.element_updates_per_s =
      loop_s > 0 ? static_cast<double>(step) * tled.num_elements() / loop_s : 0;
  double max_strain = 0;
  FillExplicitFields(tled, solution, &max_strain);
  summary.error.note =
      "explicit dynamics does not estimate the discretisation error; compare meshes with pba "
      "study convergence (docs/scenes.md)";
  summary.analysis = Format(
      "explicit dynamics (central difference, total Lagrangian, lumped mass) to %.4g ms", t * 1e3);
  summary.notes.push_back(Format(
      "explicit: %lld steps of %.3g us (%.2f x the stable %.3g us, set by %s), %d reductions; "
      "bulk viscosity %g (linear) and %g (quadratic)%s",
      static_cast<long long>(step), run.first_step_s * 1e6, factor, stable0 * 1e6,
      run.controlling_element.c_str(), run.step_reductions, setup.options.bulk_viscosity_linear,
      setup.options.bulk_viscosity_quadratic,
      alpha > 0 ? Format("; mass damping %g 1/s", alpha).c_str() : ""));
  if (energy.mass_scaling != 0) {
    summary.notes.push_back(Format(
        "mass scaling during the run: %d element scalings, %.3g kg in all; the nodes kept their "
        "momentum, losing %.3g J of kinetic energy (part of the balance)",
        run.mass_scaled_elements, run.added_mass_kg, -energy.mass_scaling));
  }
  summary.notes.push_back(Format(
      "energy at the end: kinetic %.4g J, internal %.4g J, hourglass %.3g J, contact %.3g J, "
      "damping %.3g J, eroded %.3g J, external work %.4g J; balance error at most %.3g %%",
      run.kinetic_j, run.internal_j, run.hourglass_j, run.contact_j, run.damping_j, run.eroded_j,
      run.external_work_j, 100 * run.max_energy_error));
  for (const Impactor& imp : impactors) {
    ContactSummary c;
    c.name = imp.name();
    for (int k = 0; k < 3; ++k) c.force_n[k] = imp.state().force_on_body(k);
    c.peak_force_n = imp.state().peak_force;
    c.max_penetration_mm = imp.state().penetration / kMm;
    c.penalty_pa_per_mm = 0;
    summary.contacts.push_back(c);
  }
  result->u = u;
  result->internal_force = f_int;
  result->external_force = f_ext + f_contact;
  result->strain_energy_j = energy.Internal();
  result->max_strain = max_strain;
  clock->End();
  return Status::Ok();
}

}  // namespace pba
