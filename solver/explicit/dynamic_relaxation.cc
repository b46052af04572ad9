#include "explicit/dynamic_relaxation.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/format.h"
#include "explicit/explicit_setup.h"

namespace pba {
namespace {

// Steps over which the loads rise to their full value.
constexpr int kRampSteps = 200;
// Steps over which the convergence rate is measured.
constexpr int kRateWindow = 20;
constexpr int64_t kMaxSteps = 200000;

}  // namespace

Status SolveDynamicRelaxation(const Problem& problem, PhaseClock* clock, Solution* solution,
                              StaticResult* result) {
  const Mesh& mesh = problem.model.mesh;
  Summary& summary = solution->summary;
  clock->Begin("setup", 0.05, 0.1, "explicit model, fictitious masses");
  ExplicitSetup setup;
  PBA_RETURN_IF_ERROR(MakeExplicitSetup(problem, &setup));
  TledModel& tled = *setup.tled;
  const int n_dofs = 3 * mesh.num_nodes();
  // Fictitious masses: every element's stable step 1 / factor (the scene's
  // time_step_factor, else ExplicitOptions::kRelaxationTimeStepFactor).
  constexpr double dt = 1;
  const double factor = problem.explicit_dynamics.time_step_factor;
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(mesh.num_nodes());
  for (int e = 0; e < tled.num_elements(); ++e) {
    const TledMaterial& m = tled.material(e);
    const double l = tled.characteristic_length(e);
    const double rho = (m.bulk + 4 * m.mu / 3) * (dt / (factor * l)) * (dt / (factor * l));
    const int npe = tled.nodes_per_element();
    for (int a = 0; a < npe; ++a) {
      mass(tled.element_nodes(e)[a]) += rho * tled.reference_volume(e) / npe;
    }
  }
  tled.SetLumpedMass(mass);
  tled.SetTimeStep(dt);
  const double tolerance = problem.explicit_dynamics.relaxation_tolerance;
  solution->history_columns = {"step",    "amplitude",       "relative_residual", "estimated_error",
                               "kinetic", "damping_per_step"};
  clock->End();

  clock->Begin("relax", 0.1, 0.9, "dynamic relaxation");
  const std::vector<PrescribedDof>& prescribed = setup.prescribed;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n_dofs), v = Eigen::VectorXd::Zero(n_dofs);
  Eigen::VectorXd f_int(n_dofs), f_int_prev = Eigen::VectorXd::Zero(n_dofs),
                                 du_prev = Eigen::VectorXd::Zero(n_dofs),
                                 f_ext = Eigen::VectorXd::Zero(n_dofs);
  std::vector<double> increments;  // largest |du| per step
  double damping = 0, residual = 1, estimate = 0;
  int64_t step = 0;
  bool converged = false;
  const auto start = std::chrono::steady_clock::now();
  for (; step < kMaxSteps; ++step) {
    const double amplitude = std::min(1.0, static_cast<double>(step) / kRampSteps);
    for (int i = 0; i < n_dofs; ++i) {
      if (prescribed[i].kind == PrescribedDof::kDisplacement) {
        u(i) = prescribed[i].value * amplitude;
      }
    }
    const TledEvaluation eval = tled.InternalForce(u, v, &f_int);
    if (eval.inverted_element >= 0) {
      return Status::Numerical(
          Format("dynamic relaxation stopped at step %lld (load %.0f %%): element %d inverted; the "
                 "deformation is too large for this mesh",
                 static_cast<long long>(step), 100 * amplitude, eval.inverted_element));
    }
    if (setup.has_loads) {
      f_ext = amplitude * (setup.loads->follows_deformation() ? setup.loads->Force(u)
                                                              : setup.loads->dead_force());
    }
    // Underwood's damping: omega_min^2 from the Rayleigh quotient with the
    // diagonal stiffness of the last step's change.
    double num = 0, den = 0, largest_r = 0, largest_load = 0, largest_u = 0;
    for (int i = 0; i < n_dofs; ++i) {
      const double m = mass(i / 3);
      if (prescribed[i].kind != PrescribedDof::kFree) {
        largest_load = std::max(largest_load, std::abs(f_int(i) - f_ext(i)));
        continue;
      }
      largest_load = std::max(largest_load, std::abs(f_ext(i)));
      largest_r = std::max(largest_r, std::abs(f_ext(i) - f_int(i)));
      largest_u = std::max(largest_u, std::abs(u(i)));
      if (step > 0 && du_prev(i) != 0) {
        const double k = (f_int(i) - f_int_prev(i)) / du_prev(i);
        num += u(i) * u(i) * k;
        den += u(i) * u(i) * m;
      }
    }
    if (den > 0 && num > 0) damping = std::min(2 * std::sqrt(num / den), 1.9 / dt);
    residual = largest_load > 0 ? largest_r / largest_load : largest_r;
    // The distance to the answer from the rate the increments shrink.
    const std::size_t k = increments.size();
    estimate = INFINITY;
    if (k > kRateWindow && increments[k - 1 - kRateWindow] > 0) {
      const double rate =
          std::pow(increments[k - 1] / increments[k - 1 - kRateWindow], 1.0 / kRateWindow);
      if (rate < 1) estimate = rate / (1 - rate) * increments[k - 1];
    }
    const double relative_estimate = largest_u > 0 ? estimate / largest_u : estimate;
    if (step % 50 == 0) {
      double kinetic = 0;
      for (int i = 0; i < n_dofs; ++i) kinetic += 0.5 * mass(i / 3) * v(i) * v(i);
      solution->history.push_back({static_cast<double>(step), amplitude, residual,
                                   relative_estimate, kinetic, damping * dt});
    }
    if (step > kRampSteps && residual <= tolerance && relative_estimate <= tolerance) {
      converged = true;
      break;
    }
    // v^(n+1/2) = ((2 - c dt) v^(n-1/2) + 2 dt r / m) / (2 + c dt).
    double largest_du = 0;
    for (int i = 0; i < n_dofs; ++i) {
      double du;
      if (prescribed[i].kind == PrescribedDof::kFree && mass(i / 3) > 0) {
        v(i) = ((2 - damping * dt) * v(i) + 2 * dt * (f_ext(i) - f_int(i)) / mass(i / 3)) /
               (2 + damping * dt);
        du = dt * v(i);
      } else {
        const double next =
            prescribed[i].kind == PrescribedDof::kDisplacement
                ? prescribed[i].value * std::min(1.0, static_cast<double>(step + 1) / kRampSteps)
                : u(i);
        du = next - u(i);
        v(i) = du / dt;
      }
      du_prev(i) = du;
      if (prescribed[i].kind == PrescribedDof::kFree)
        largest_du = std::max(largest_du, std::abs(du));
      u(i) += du;
    }
    if (!std::isfinite(largest_du)) {
      return Status::Numerical(
          Format("dynamic relaxation stopped at step %lld: the motion is "
                 "no longer finite",
                 static_cast<long long>(step)));
    }
    increments.push_back(largest_du);
    f_int_prev = f_int;
    if (step % 200 == 0) {
      clock->Update(
          std::min(0.99, std::log10(std::max(residual, tolerance)) / std::log10(tolerance)),
          Format("step %lld, out of balance %.3g", static_cast<long long>(step), residual));
      if (clock->cancelled()) return Status::Cancelled("cancelled during dynamic relaxation");
    }
  }
  const double loop_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!converged) {
    return Status::Numerical(Format(
        "dynamic relaxation did not converge in %lld steps: out-of-balance force %.3g of the "
        "largest load or reaction, estimated distance to the answer %.3g of the largest "
        "displacement (tolerance %g); try NONLINEAR_STATIC, or a looser "
        "analysis.explicit_dynamics.relaxation_tolerance",
        static_cast<long long>(kMaxSteps), residual, estimate, tolerance));
  }
  clock->End();
  clock->Begin("recover", 0.9, 0.95, "finite-strain fields");
  tled.RecordStress(true);
  tled.InternalForce(u, v, &f_int);
  double max_strain = 0;
  FillExplicitFields(tled, solution, &max_strain);
  ExplicitSummary& run = summary.explicit_run;
  run.ran = true;
  run.steps = step;
  run.converged = true;
  run.relative_residual = residual;
  run.element_updates_per_s =
      loop_s > 0 ? static_cast<double>(step) * tled.num_elements() / loop_s : 0;
  summary.relative_residual = residual;
  summary.error.note =
      "dynamic relaxation does not estimate the discretisation error; compare meshes with pba "
      "study convergence";
  summary.analysis = "dynamic relaxation (explicit, total Lagrangian, adaptive damping)";
  summary.notes.push_back(
      Format("dynamic relaxation: converged in %lld steps (loads ramped over the first %d), "
             "out-of-balance force %.3g of the largest load or reaction, estimated distance to the "
             "answer %.3g of the largest displacement (tolerance %g); %.3g element updates/s",
             static_cast<long long>(step), kRampSteps, residual,
             std::isfinite(estimate) ? estimate : 0.0, tolerance, run.element_updates_per_s));
  result->u = u;
  result->internal_force = f_int;
  result->external_force = f_ext;
  double energy = 0;
  for (int e = 0; e < tled.num_elements(); ++e) {
    energy +=
        tled.reference_volume(e) * tled.material(e).model->Energy(tled.DeformationGradient(e));
  }
  result->strain_energy_j = energy;
  result->max_strain = max_strain;
  clock->End();
  return Status::Ok();
}

}  // namespace pba
