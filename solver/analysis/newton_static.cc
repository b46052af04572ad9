#include "analysis/newton_static.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/format.h"

namespace pba {
namespace {

// Adds the wall time of its scope to `*seconds`.
class ScopedTimer {
 public:
  explicit ScopedTimer(double* seconds)
      : seconds_(seconds), start_(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    *seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  double* seconds_;
  std::chrono::steady_clock::time_point start_;
};

// Energy ratio |du . R| / |du_p . K du_p| at which a Newton correction is
// rounding noise.
constexpr double kRoundingEnergy = 1e-20;

// Relative residual below which an iteration whose consistent tangent is not
// positive definite steps with that tangent anyway (LDL^T): close to
// equilibrium the indefiniteness is the equilibrium's own, not the transient
// of a poor predictor.
constexpr double kIndefiniteNewtonResidual = 1e-4;

// Solves K du = rhs with the symmetric indefinite K by a sparse LDL^T
// (fill-reducing ordering, no pivoting) and counts the negative pivots, which
// by Sylvester's law of inertia are K's negative eigenvalues. False when a
// pivot vanishes or the solve is inaccurate (no pivoting).
bool SolveIndefinite(const LinearSystem& system,
                     Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>* ldlt, Eigen::VectorXd* du,
                     int* negative) {
  ldlt->compute(system.k);
  if (ldlt->info() != Eigen::Success || !ldlt->vectorD().allFinite()) return false;
  *negative = static_cast<int>((ldlt->vectorD().array() < 0).count());
  *du = ldlt->solve(system.rhs);
  return du->allFinite() && (system.k * *du - system.rhs).norm() <= 1e-6 * system.rhs.norm();
}

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

// The loads at one load factor.
struct Loading {
  const ExternalLoads* loads;  // may be null
  double factor;
  bool active() const { return loads != nullptr && !loads->empty() && factor != 0; }
};

// Residual of state `u`: ||R_f|| / max(||f_int||, ||lambda f_ext||)
// (infinite when an element is inverted) and R = lambda f_ext - f_int on the
// free unknowns.
struct Residual {
  double relative = INFINITY;
  Eigen::VectorXd free;
  double work = 0;  // |u . f_int|, the scale of the state's energy
};
Residual Evaluate(const FiniteStrainModel& model, const Loading& loading, const DofMap& dofs,
                  const Eigen::VectorXd& u) {
  Residual r;
  Eigen::VectorXd force;
  if (!model.InternalForce(u, &force, nullptr)) return r;
  r.work = std::abs(u.dot(force));
  double scale = force.norm();
  if (loading.active()) {
    const Eigen::VectorXd external = loading.factor * loading.loads->Force(u);
    scale = std::max(scale, external.norm());
    force -= external;
  }
  r.free.resize(dofs.num_free());
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    const int f = dofs.free_index(dof);
    if (f >= 0) r.free(f) = -force(dof);
  }
  r.relative = r.free.norm() / (scale > 0 ? scale : 1.0);
  return r;
}

// The model's tangent and rhs with the loads at `loading` added: rhs gains
// lambda f_ext on the free unknowns, K the load stiffness of follower loads.
Status AssembleLoaded(const FiniteStrainModel& model, const Loading& loading,
                      const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                      LinearSystem* system) {
  PBA_RETURN_IF_ERROR(model.Assemble(u, dofs, options, system));
  if (!loading.active()) return Status::Ok();
  const Eigen::VectorXd external = loading.loads->Force(u);
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    const int f = dofs.free_index(dof);
    if (f >= 0) system->rhs(f) += loading.factor * external(dof);
  }
  if (loading.loads->follows_deformation() && !options.drop_pressure_stiffness) {
    // The loaded triangles' nodes share a tetrahedron, so the sum keeps
    // K's pattern (and the solver's symbolic analysis); it is added in
    // place, not by `k += s`, which builds the sum as a second matrix.
    // Should an entry be missing after all, coeffRef inserts it and k is
    // compressed again (the next assembly then builds a new pattern).
    const SparseMatrix stiffness = loading.loads->Stiffness(u, dofs, loading.factor);
    for (int col = 0; col < stiffness.outerSize(); ++col) {
      for (SparseMatrix::InnerIterator it(stiffness, col); it; ++it) {
        system->k.coeffRef(it.row(), col) += it.value();
      }
    }
    system->k.makeCompressed();
  }
  return Status::Ok();
}

}  // namespace

Status SolveNewtonStatic(const FiniteStrainModel& model, const DofMap& dofs,
                         const NewtonOptions& options, LinearSolver* solver,
                         const std::function<bool(const NewtonProgress&)>& keep_going,
                         Eigen::VectorXd* u, NewtonReport* report) {
  return SolveNewtonStatic(model, nullptr, dofs, options, solver, keep_going, u, report);
}

Status SolveNewtonStatic(const FiniteStrainModel& model, const ExternalLoads* loads,
                         const DofMap& dofs, const NewtonOptions& options, LinearSolver* solver,
                         const std::function<bool(const NewtonProgress&)>& keep_going,
                         Eigen::VectorXd* u, NewtonReport* report) {
  *report = NewtonReport();
  const auto amplitude = [&](double lambda) {
    return options.amplitude ? options.amplitude(lambda) : lambda;
  };
  if (options.start_u.size() > 0 && options.start_u.size() != dofs.num_dofs()) {
    return Status::Internal(Format("the start state has %d unknowns, the model %d",
                                   static_cast<int>(options.start_u.size()), dofs.num_dofs()));
  }
  *u = options.start_u.size() > 0 ? options.start_u : Eigen::VectorXd::Zero(dofs.num_dofs());
  // Far from equilibrium the tangent may be indefinite: a nearly
  // incompressible body's predictor leaves J - 1 = O(step^2), and the
  // pressure K (J - 1) >> mu that follows destroys positive definiteness
  // through its initial-stress stiffness, so Cholesky fails. The iteration
  // then first tries the current tangent without the pressure's (and a
  // follower load's) initial-stress terms, which keeps the volumetric
  // stiffness of the current state; failing that, a modified-Newton step
  // with the last positive definite tangent, kept factorised in a second
  // solver (usually the predictor's, at the last converged state). Full
  // Newton resumes as soon as the tangent is positive definite again.
  // Without any such tangent the current one is shifted by tau diag(K), tau
  // growing tenfold from 1e-4 until Cholesky succeeds (Nocedal & Wright,
  // Numerical Optimization, 3.4).
  // Close to equilibrium (relative residual <= kIndefiniteNewtonResidual),
  // and for the predictor when the last converged state's tangent was
  // already indefinite, the consistent tangent is used although it is not
  // positive definite (LDL^T): the path has then passed a critical point
  // (e.g. TET4_ANP under 50 % bonded compression: the smallest eigenvalue
  // crosses zero between 41 and 43 %, as increment_cutting_test prints),
  // and the definite substitutes converge only linearly to the equilibrium
  // beyond it.
  // The two solvers take turns, so both hold a factorisation between
  // iterations. Releasing the older one once the newer succeeds would not
  // lower the peak (a factorisation is attempted while the last good one
  // must survive its failure, so two coexist then anyway), and a released
  // CHOLMOD solver would redo its symbolic analysis, which each solver
  // otherwise keeps for the unchanged pattern.
  std::unique_ptr<LinearSolver> spare = solver->NewOfSameKind();
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> ldlt;
  // Negative eigenvalues of the tangent of the last step, when it was
  // factorised by LDL^T (0 after a Cholesky of the consistent tangent, -1
  // when the step used another tangent).
  int step_negative = 0;
  LinearSolver* good = nullptr;  // holds the last positive definite factorisation
  SparseMatrix shifted;
  LinearSystem approximate;
  // Consecutive iterations whose consistent tangent was not positive
  // definite: when an increment fails with the tangent still indefinite
  // close to equilibrium, the equilibrium itself may be unstable.
  int indefinite_streak = 0;
  const auto solve =
      [&](const LinearSystem& system, int iteration, double residual, bool near_equilibrium,
          const std::function<Status(LinearSystem*)>& assemble_approximate, Eigen::VectorXd* du) {
        ScopedTimer timer(&report->linear_solve_s);
        LinearSolver* target = good == solver ? spare.get() : solver;
        Status status = target->Factorize(system.k);
        if (status.ok()) {
          good = target;
          indefinite_streak = 0;
          step_negative = 0;
          return good->Solve(system.rhs, du);
        }
        ++indefinite_streak;
        if (near_equilibrium && SolveIndefinite(system, &ldlt, du, &step_negative)) {
          ++report->indefinite_iterations;
          return Status::Ok();
        }
        step_negative = -1;
        bool approximated = false;
        {
          // The approximate tangent's assembly counts as assembly, not solving.
          double assembly = 0;
          {
            ScopedTimer assembling(&assembly);
            approximated = assemble_approximate(&approximate).ok();
          }
          report->assembly_s += assembly;
          report->linear_solve_s -= assembly;
        }
        if (approximated && target->Factorize(approximate.k).ok()) {
          ++report->approximate_iterations;
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
  // One tangent for the whole solve: the predictor's DofMap (`increment`
  // below) frees the same unknowns as `dofs`, so every assembly fills the
  // same pattern in place (see AssembleSystem) instead of building a new
  // matrix beside the old one.
  LinearSystem system;
  double load = options.start_load;
  // The last converged state's tangent had negative eigenvalues (the path
  // passed a bifurcation and follows the now unstable fundamental branch):
  // its indefinite tangent is then the right predictor.
  bool unstable_branch = false;
  double step =
      options.start_step > 0 ? options.start_step : 1.0 / std::max(1, options.initial_increments);
  std::string last_failure;
  auto cancelled = [&] { return Status::Cancelled(Format("cancelled at load factor %.4g", load)); };

  while (load < 1.0) {
    if (!keep_going({load, 0, INFINITY})) return cancelled();
    const double largest = options.max_increment_at
                               ? std::max(options.min_increment, options.max_increment_at(load))
                               : INFINITY;
    step = std::min(step, largest);
    // A last sliver below the smallest increment joins this one.
    const double target = load + step >= 1.0 - 0.5 * options.min_increment ? 1.0 : load + step;
    const Loading loading{loads, amplitude(target)};
    if (options.begin_increment) PBA_RETURN_IF_ERROR(options.begin_increment(load, target));

    // Predictor: the tangent at the converged state carries the prescribed
    // increment into the free unknowns.
    const double amplitude_change = amplitude(target) - amplitude(load);
    DofMap increment = dofs;
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      if (dofs.prescribed(dof)) {
        increment.Prescribe(dof / 3, dof % 3, amplitude_change * dofs.prescribed_value(dof));
      }
    }
    increment.Finalize();
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    Eigen::VectorXd trial = *u;
    Eigen::VectorXd du;
    // At the converged state f_int = lambda_old f_ext, so the rhs
    // lambda_new f_ext - f_int is the load increment.
    Status status;
    {
      ScopedTimer timer(&report->assembly_s);
      status = AssembleLoaded(model, loading, *u, increment, lift, &system);
    }
    if (status.ok() && dofs.num_free() > 0) {
      status = solve(
          system, 0, 0.0, unstable_branch,
          [&](LinearSystem* out) {
            AssemblyOptions definite = lift;
            definite.drop_pressure_stiffness = true;
            return AssembleLoaded(model, loading, *u, increment, definite, out);
          },
          &du);
    }
    bool converged = false;
    int iteration = 0;
    double residual = INFINITY;
    // Energy of the increment, du_pred . K du_pred: the scale of the energy test.
    const double first_energy =
        status.ok() && dofs.num_free() > 0 ? std::abs(du.dot(system.rhs)) : 0.0;
    if (status.ok()) {
      if (dofs.num_free() > 0) AddFree(dofs, du, 1.0, &trial);
      for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
        if (dofs.prescribed(dof)) trial(dof) = loading.factor * dofs.prescribed_value(dof);
      }
      const auto evaluate = [&](const Eigen::VectorXd& state) {
        ScopedTimer timer(&report->residual_s);
        return Evaluate(model, loading, dofs, state);
      };
      Residual current = evaluate(trial);
      residual = current.relative;
      if (!std::isfinite(residual)) {
        status = Status::Numerical("the predictor inverted an element");
      } else if (dofs.num_free() == 0) {
        converged = true;
      }
      int augmentations = 0;
      int budget = options.max_iterations;
      for (iteration = 1; status.ok() && !converged && iteration <= budget; ++iteration) {
        if (!keep_going({load, iteration, residual})) return cancelled();
        {
          ScopedTimer timer(&report->assembly_s);
          status = AssembleLoaded(model, loading, trial, dofs, AssemblyOptions(), &system);
        }
        if (!status.ok()) break;
        status = solve(
            system, iteration, residual, residual <= kIndefiniteNewtonResidual,
            [&](LinearSystem* out) {
              AssemblyOptions definite;
              definite.drop_pressure_stiffness = true;
              return AssembleLoaded(model, loading, trial, dofs, definite, out);
            },
            &du);
        if (!status.ok()) break;
        const double energy = std::abs(du.dot(current.free));
        // Backtracking line search: halve the step while it inverts an
        // element or raises the residual.
        double alpha = 1.0;
        Eigen::VectorXd next = trial;
        AddFree(dofs, du, alpha, &next);
        Residual candidate = evaluate(next);
        while (options.line_search && alpha > 1.0 / 64 &&
               !(candidate.relative < std::max(current.relative, 1e-300))) {
          alpha *= 0.5;
          next = trial;
          AddFree(dofs, du, alpha, &next);
          candidate = evaluate(next);
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
          if (options.augment && augmentations < options.max_augmentations &&
              options.augment(trial)) {
            // The equations changed (e.g. contact multipliers): iterate again
            // from this state, with a fresh iteration budget.
            ++augmentations;
            ++report->augmentations;
            budget = iteration + options.max_iterations;
            current = evaluate(trial);
            residual = current.relative;
            continue;
          }
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
      report->increments.push_back({target, target - load, iteration, residual, step_negative});
      load = target;
      unstable_branch = step_negative > 0;
      if (options.on_increment) options.on_increment(load, *u);
      if (iteration <= options.quick_iterations) {
        step = std::min(step * 1.5, options.max_increment);
      }
      if (options.after_increment) PBA_RETURN_IF_ERROR(options.after_increment(load, step, *u));
      continue;
    }
    if (status.code() == Status::Code::kCancelled) return status;
    last_failure = status.ok() ? Format("no convergence in %d iterations (relative residual %.3g)",
                                        iteration - 1, residual)
                               : status.message();
    if (status.ok() && indefinite_streak >= 3 && residual < 1e-4) {
      last_failure += Format(
          "; the tangent stiffness stayed indefinite for the last %d iterations although the "
          "residual was small, so the equilibrium there may be unstable (buckling, or a "
          "spurious mode of the element under strong compression)",
          indefinite_streak);
    }
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
