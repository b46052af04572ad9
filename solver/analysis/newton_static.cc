#include "analysis/newton_static.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/format.h"

namespace pba {
namespace {

// Energy ratio |du . R| / |du_p . K du_p| at which a Newton correction is
// rounding noise.
constexpr double kRoundingEnergy = 1e-20;

double FreeNorm(const DofMap& dofs, const Eigen::VectorXd& full) {
  double sum = 0;
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if (!dofs.prescribed(dof)) sum += full(dof) * full(dof);
  }
  return std::sqrt(sum);
}

void AddFree(const DofMap& dofs, const Eigen::VectorXd& free, double scale, Eigen::VectorXd* u) {
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    const int f = dofs.free_index(dof);
    if (f >= 0) (*u)(dof) += scale * free(f);
  }
}

// Residual of state `u`: ||R_f|| / ||f_int|| (infinite when an element is
// inverted) and R on the free unknowns.
struct Residual {
  double relative = INFINITY;
  Eigen::VectorXd free;
  double work = 0;  // |u . f_int|, the scale of the state's energy
};
Residual Evaluate(const FiniteStrainModel& model, const DofMap& dofs, const Eigen::VectorXd& u) {
  Residual r;
  Eigen::VectorXd force;
  if (!model.InternalForce(u, &force, nullptr)) return r;
  r.free.resize(dofs.num_free());
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    const int f = dofs.free_index(dof);
    if (f >= 0) r.free(f) = -force(dof);
  }
  const double scale = force.norm();
  r.relative = r.free.norm() / (scale > 0 ? scale : 1.0);
  r.work = std::abs(u.dot(force));
  return r;
}

}  // namespace

Status SolveNewtonStatic(const FiniteStrainModel& model, const DofMap& dofs,
                         const NewtonOptions& options, LinearSolver* solver,
                         const std::function<bool(const NewtonProgress&)>& keep_going,
                         Eigen::VectorXd* u, NewtonReport* report) {
  *u = Eigen::VectorXd::Zero(dofs.num_dofs());
  *report = NewtonReport();
  // Far from equilibrium the tangent may be indefinite: a nearly
  // incompressible body's predictor leaves J - 1 = O(step^2), and the
  // pressure K (J - 1) >> mu that follows destroys positive definiteness,
  // so Cholesky fails. The iteration then takes a modified-Newton step with
  // the last positive definite tangent, which is kept factorised in a second
  // solver (usually the predictor's, at the last converged state): it
  // removes the volumetric error to first order, and full Newton resumes as
  // soon as the tangent is positive definite again. Without such a tangent
  // the current one is shifted by tau diag(K), tau growing tenfold from 1e-4
  // until Cholesky succeeds (Nocedal & Wright, Numerical Optimization, 3.4).
  std::unique_ptr<LinearSolver> spare = solver->NewOfSameKind();
  LinearSolver* good = nullptr;  // holds the last positive definite factorisation
  SparseMatrix shifted;
  const auto solve = [&](const LinearSystem& system, int iteration, double residual,
                         Eigen::VectorXd* du) {
    LinearSolver* target = good == solver ? spare.get() : solver;
    Status status = target->Factorize(system.k);
    if (status.ok()) {
      good = target;
      return good->Solve(system.rhs, du);
    }
    ++report->modified_iterations;
    if (good != nullptr) return good->Solve(system.rhs, du);
    const Eigen::VectorXd diagonal = system.k.diagonal().cwiseAbs();
    for (double tau = 1e-4; tau <= 1e2; tau *= 10) {
      shifted = system.k;
      for (int i = 0; i < shifted.outerSize(); ++i) shifted.coeffRef(i, i) += tau * diagonal(i);
      if (target->Factorize(shifted).ok()) return target->Solve(system.rhs, du);
    }
    return Status::Numerical(
        Format("the tangent stiffness could not be made positive definite at iteration %d "
               "(relative residual %.3g)",
               iteration, residual));
  };
  double load = 0;
  double step = 1.0 / std::max(1, options.initial_increments);
  std::string last_failure;
  auto cancelled = [&] { return Status::Cancelled(Format("cancelled at load factor %.4g", load)); };

  while (load < 1.0) {
    if (!keep_going({load, 0, INFINITY})) return cancelled();
    const double target = std::min(1.0, load + step);

    // Predictor: the tangent at the converged state carries the prescribed
    // increment into the free unknowns.
    DofMap increment = dofs;
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      if (dofs.prescribed(dof)) {
        increment.Prescribe(dof / 3, dof % 3, (target - load) * dofs.prescribed_value(dof));
      }
    }
    increment.Finalize();
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    LinearSystem system;
    Eigen::VectorXd trial = *u;
    Eigen::VectorXd du;
    Status status = model.Assemble(*u, increment, lift, &system);
    if (status.ok() && dofs.num_free() > 0) status = solve(system, 0, 0.0, &du);
    bool converged = false;
    int iteration = 0;
    double residual = INFINITY;
    // Energy of the increment, du_pred . K du_pred: the scale of the energy test.
    const double first_energy =
        status.ok() && dofs.num_free() > 0 ? std::abs(du.dot(system.rhs)) : 0.0;
    if (status.ok()) {
      if (dofs.num_free() > 0) AddFree(dofs, du, 1.0, &trial);
      for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
        if (dofs.prescribed(dof)) trial(dof) = target * dofs.prescribed_value(dof);
      }
      Residual current = Evaluate(model, dofs, trial);
      residual = current.relative;
      if (!std::isfinite(residual)) {
        status = Status::Numerical("the predictor inverted an element");
      } else if (dofs.num_free() == 0) {
        converged = true;
      }
      for (iteration = 1; status.ok() && !converged && iteration <= options.max_iterations;
           ++iteration) {
        if (!keep_going({load, iteration, residual})) return cancelled();
        status = model.Assemble(trial, dofs, AssemblyOptions(), &system);
        if (!status.ok()) break;
        status = solve(system, iteration, residual, &du);
        if (!status.ok()) break;
        const double energy = std::abs(du.dot(current.free));
        // Backtracking line search: halve the step while it inverts an
        // element or raises the residual.
        double alpha = 1.0;
        Eigen::VectorXd next = trial;
        AddFree(dofs, du, alpha, &next);
        Residual candidate = Evaluate(model, dofs, next);
        while (options.line_search && alpha > 1.0 / 64 &&
               !(candidate.relative < std::max(current.relative, 1e-300))) {
          alpha *= 0.5;
          next = trial;
          AddFree(dofs, du, alpha, &next);
          candidate = Evaluate(model, dofs, next);
        }
        if (!std::isfinite(candidate.relative)) {
          status = Status::Numerical("an element inverted");
          break;
        }
        trial = std::move(next);
        current = std::move(candidate);
        residual = current.relative;
        ++report->total_iterations;
        const double change = alpha * du.norm() / std::max(FreeNorm(dofs, trial), 1e-300);
        // The residual and the correction of a nearly incompressible body
        // have a rounding floor (K / mu up to 1e6 amplifies the error of
        // J - 1 and the condition number); once the correction's energy is
        // down at rounding level, no further iteration can improve the state.
        // Measured against the increment's own energy, or the state's when
        // the increment is tiny (after cuts).
        const double energy_scale = std::max(first_energy, current.work);
        const bool rounding_floor = energy <= kRoundingEnergy * energy_scale;
        if ((residual <= options.residual_tolerance || rounding_floor) &&
            (change <= options.displacement_tolerance || rounding_floor) &&
            energy <= options.energy_tolerance * std::max(energy_scale, 1e-300)) {
          converged = true;
          break;
        }
        if (residual > 1e6) {
          status = Status::Numerical(Format("diverging (relative residual %.3g)", residual));
          break;
        }
      }
    }
    if (converged) {
      *u = std::move(trial);
      load = target;
      report->increments.push_back({load, iteration, residual});
      if (options.on_increment) options.on_increment(load, *u);
      if (iteration <= options.quick_iterations) {
        step = std::min(step * 1.5, options.max_increment);
      }
      continue;
    }
    if (status.code() == Status::Code::kCancelled) return status;
    last_failure = status.ok() ? Format("no convergence in %d iterations (relative residual %.3g)",
                                        options.max_iterations, residual)
                               : status.message();
    report->cut_reasons.push_back(Format("increment %.4g -> %.4g: ", load, target) + last_failure);
    step *= 0.5;
    ++report->cuts;
    if (step < options.min_increment) {
      return Status::Numerical(
          Format("the load could not be applied beyond %.4g of its full value: increments were cut "
                 "below %g; last failure: ",
                 load, options.min_increment) +
          last_failure);
    }
  }
  return Status::Ok();
}

}  // namespace pba
