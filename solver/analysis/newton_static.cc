#include "analysis/newton_static.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/format.h"
#include "linear/petsc_runtime.h"

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

// An attempt whose last NewtonOptions::stagnation_iterations iterations
// left more than this share of the residual has stagnated: at that pace
// (under 1 % per iteration) its whole budget could not converge.
constexpr double kStagnantShare = 0.95;

// Behind an iterative linear solver the indefinite consistent tangent is
// factorised (SolveIndefinite) only up to this many unknowns; larger
// systems take the definite substitutes, converging linearly past a
// bifurcation, and the increment records no eigenvalue count.
constexpr Eigen::Index kIterativeLdltMaxUnknowns = 60000;

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
// With `own` (may be null), partitioned between MPI ranks: each evaluates
// its nodes' share, all agree on whether every element was admissible, and
// the shares are added up.
Residual Evaluate(const FiniteStrainModel& model, const Loading& loading, const DofMap& dofs,
                  const Eigen::VectorXd& u, const std::vector<char>* own) {
  Residual r;
  Eigen::VectorXd force;
  if (own == nullptr) {
    if (!model.InternalForce(u, &force, nullptr)) return r;
  } else {
    int failed = model.InternalForceShare(u, *own, &force) ? 0 : 1;
    if (!MaxOverRanks(&failed, 1).ok() || failed != 0) return r;
    if (!SumOverRanks(force.data(), static_cast<int>(force.size())).ok()) return r;
  }
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
    // A partitioned tangent holds its rank's columns only.
    std::vector<char> column(stiffness.outerSize(), 1);
    if (options.own_nodes != nullptr) {
      for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
        const int f = dofs.free_index(dof);
        if (f >= 0) column[f] = (*options.own_nodes)[dof / 3];
      }
    }
    for (int col = 0; col < stiffness.outerSize(); ++col) {
      if (!column[col]) continue;
      for (SparseMatrix::InnerIterator it(stiffness, col); it; ++it) {
        system->k.coeffRef(it.row(), col) += it.value();
      }
    }
    system->k.makeCompressed();
  }
  return Status::Ok();
}

// One Newton solve: the state, the two linear solvers that take turns, the
// counters, and the steps of the increment loop.
class NewtonRun {
 public:
  NewtonRun(const FiniteStrainModel& model, const ExternalLoads* loads, const DofMap& dofs,
            const NewtonOptions& options, LinearSolver* solver,
            const std::function<bool(const NewtonProgress&)>& keep_going, Eigen::VectorXd* u,
            NewtonReport* report)
      : model_(model),
        loads_(loads),
        dofs_(dofs),
        options_(options),
        solver_(solver),
        keep_going_(keep_going),
        u_(*u),
        report_(*report),
        spare_(solver->NewOfSameKind()) {}

  Status Run();

 private:
  // What one attempt at an increment ended with.
  struct Attempt {
    Status status;
    bool converged = false;
    int iteration = 0;
    double residual = INFINITY;
  };

  double Amplitude(double lambda) const {
    return options_.amplitude ? options_.amplitude(lambda) : lambda;
  }
  Status Cancelled() const {
    return Status::Cancelled(Format("cancelled at load factor %.4g", load_));
  }
  // What every assembly asks for: the volume constraints apart too when
  // the solver solves with them; across MPI ranks, only this rank's share
  // of the tangent once both solvers read no more (AUTO reads the first
  // tangents whole to choose).
  AssemblyOptions BaseOptions() const {
    AssemblyOptions options;
    options.volumetric_split = solver_->WantsVolumetricSplit();
    if (!options.volumetric_split) options.own_nodes = OwnNodes();
    return options;
  }
  // This rank's nodes once both solvers read only theirs; null otherwise.
  const std::vector<char>* OwnNodes() const {
    return spare_->OwnNodes() != nullptr ? solver_->OwnNodes() : nullptr;
  }
  // The residual at `state`, partitioned as the tangents are.
  Residual EvaluateAt(const Loading& loading, const Eigen::VectorXd& state) {
    ScopedTimer timer(&report_.residual_s);
    return Evaluate(model_, loading, dofs_, state, OwnNodes());
  }
  // The tangent and rhs at a state with `options` (Assemble below, bound
  // to the state), for the substitutes SolveLinear may need.
  using Reassemble = std::function<Status(const AssemblyOptions&, LinearSystem*)>;
  // AssembleLoaded, counting the tangents and those assembled partitioned.
  Status Assemble(const Loading& loading, const Eigen::VectorXd& u, const DofMap& dofs,
                  const AssemblyOptions& options, LinearSystem* system) {
    ++report_.tangents;
    if (options.own_nodes != nullptr) ++report_.partitioned_tangents;
    return AssembleLoaded(model_, loading, u, dofs, options, system);
  }
  // Solves with `system`, assembled with `options`.
  Status SolveLinear(const LinearSystem& system, const AssemblyOptions& options, int iteration,
                     double residual, bool near_equilibrium, const Reassemble& reassemble,
                     Eigen::VectorXd* du);
  Status SolveApproximate(const LinearSystem& system, const AssemblyOptions& options,
                          LinearSolver* target, int iteration, double residual,
                          const Reassemble& reassemble, Eigen::VectorXd* du);
  Status Predict(double target, const Loading& loading, Eigen::VectorXd* trial,
                 double* first_energy);
  Attempt Increment(double target, const Loading& loading, bool* cancelled);
  Status Correct(const Loading& loading, double first_energy, Eigen::VectorXd* trial,
                 Attempt* attempt, bool* cancelled);
  Status Accept(double target, const Attempt& attempt, Eigen::VectorXd* trial);
  Status Cut(double target, const Attempt& attempt);

  const FiniteStrainModel& model_;
  const ExternalLoads* loads_;
  const DofMap& dofs_;
  const NewtonOptions& options_;
  LinearSolver* solver_;
  const std::function<bool(const NewtonProgress&)>& keep_going_;
  Eigen::VectorXd& u_;
  NewtonReport& report_;

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
  std::unique_ptr<LinearSolver> spare_;
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> ldlt_;
  // Negative eigenvalues of the tangent of the last step, when it was
  // factorised by LDL^T (0 after a Cholesky of the consistent tangent, -1
  // when the step used another tangent).
  int step_negative_ = 0;
  LinearSolver* good_ = nullptr;  // holds the last positive definite factorisation
  SparseMatrix shifted_;
  LinearSystem approximate_;
  LinearSystem whole_;  // a partitioned tangent assembled whole, for LDL^T
  // Consecutive iterations whose consistent tangent was not positive
  // definite: when an increment fails with the tangent still indefinite
  // close to equilibrium, the equilibrium itself may be unstable.
  int indefinite_streak_ = 0;
  // One tangent for the whole solve: the predictor's DofMap (`increment` in
  // Predict) frees the same unknowns as `dofs`, so every assembly fills the
  // same pattern in place (see AssembleSystem) instead of building a new
  // matrix beside the old one.
  LinearSystem system_;
  double load_ = 0;
  // The last converged state's tangent had negative eigenvalues (the path
  // passed a bifurcation and follows the now unstable fundamental branch):
  // its indefinite tangent is then the right predictor.
  bool unstable_branch_ = false;
  double step_ = 0;
};

// Factorises `k` and solves. A matrix that is not positive definite shows
// as Status::Numerical from the factorisation (Cholesky's failed pivot) or,
// for an iterative solver, from the solve (conjugate gradients meeting
// negative curvature); either sends Newton to its substitutes. Other
// failures (a cancel) pass through.
Status FactorizeAndSolve(LinearSolver* solver, const SparseMatrix& k, const Eigen::VectorXd& rhs,
                         Eigen::VectorXd* du) {
  PBA_RETURN_IF_ERROR(solver->Factorize(k));
  return solver->Solve(rhs, du);
}

// The same for an assembled tangent, with its volume constraints apart when
// the model gave them (LinearSystem::split).
Status FactorizeAndSolve(LinearSolver* solver, const LinearSystem& tangent,
                         const Eigen::VectorXd& rhs, Eigen::VectorXd* du) {
  PBA_RETURN_IF_ERROR(solver->FactorizeSplit(tangent.k, tangent.split));
  return solver->Solve(rhs, du);
}

Status NewtonRun::SolveLinear(const LinearSystem& system, const AssemblyOptions& options,
                              int iteration, double residual, bool near_equilibrium,
                              const Reassemble& reassemble, Eigen::VectorXd* du) {
  ScopedTimer timer(&report_.linear_solve_s);
  LinearSolver* target = good_ == solver_ ? spare_.get() : solver_;
  const Status status = FactorizeAndSolve(target, system, system.rhs, du);
  if (status.ok()) {
    good_ = target;
    indefinite_streak_ = 0;
    step_negative_ = 0;
    return Status::Ok();
  }
  if (status.code() != Status::Code::kNumerical) return status;
  ++indefinite_streak_;
  // The sparse LDL^T costs a direct factorisation: behind an iterative
  // solver, chosen where a factor may not fit, only small systems take it.
  const bool ldlt_affordable = !target->Iterative() || system.k.rows() <= kIterativeLdltMaxUnknowns;
  if (near_equilibrium && ldlt_affordable) {
    // A partitioned tangent is whole on no rank: every rank assembles the
    // whole of it for the LDL^T (all are here together, as the failed
    // factorisation or solve was collective).
    const LinearSystem* whole = &system;
    bool assembled = true;
    if (system.own_nodes != nullptr) {
      AssemblyOptions all = options;
      all.own_nodes = nullptr;
      double assembly = 0;
      {
        ScopedTimer assembling(&assembly);
        assembled = reassemble(all, &whole_).ok();
      }
      report_.assembly_s += assembly;
      report_.linear_solve_s -= assembly;
      whole = &whole_;
    }
    if (assembled && SolveIndefinite(*whole, &ldlt_, du, &step_negative_)) {
      ++report_.indefinite_iterations;
      return Status::Ok();
    }
  }
  step_negative_ = -1;
  return SolveApproximate(system, options, target, iteration, residual, reassemble, du);
}

// The substitutes for a tangent that is not positive definite, in turn: the
// tangent without initial-stress terms, the last positive definite one, a
// shifted one.
Status NewtonRun::SolveApproximate(const LinearSystem& system, const AssemblyOptions& options,
                                   LinearSolver* target, int iteration, double residual,
                                   const Reassemble& reassemble, Eigen::VectorXd* du) {
  bool approximated = false;
  {
    // The approximate tangent's assembly counts as assembly, not solving.
    double assembly = 0;
    {
      ScopedTimer assembling(&assembly);
      AssemblyOptions definite = options;
      definite.drop_pressure_stiffness = true;
      approximated = reassemble(definite, &approximate_).ok();
    }
    report_.assembly_s += assembly;
    report_.linear_solve_s -= assembly;
  }
  if (approximated && FactorizeAndSolve(target, approximate_, system.rhs, du).ok()) {
    ++report_.approximate_iterations;
    good_ = target;
    return Status::Ok();
  }
  ++report_.modified_iterations;
  if (good_ != nullptr) return good_->Solve(system.rhs, du);
  const Eigen::VectorXd diagonal = system.k.diagonal().cwiseAbs();
  for (double tau = 1e-4; tau <= 1e2; tau *= 10) {
    shifted_ = system.k;
    for (int i = 0; i < shifted_.outerSize(); ++i) shifted_.coeffRef(i, i) += tau * diagonal(i);
    if (FactorizeAndSolve(target, shifted_, system.rhs, du).ok()) return Status::Ok();
  }
  return Status::Numerical(
      Format("the tangent stiffness could not be made positive definite at iteration %d "
             "(relative residual %.3g)",
             iteration, residual));
}

// Predictor: the tangent at the converged state carries the prescribed
// increment into the free unknowns; *trial gets the predicted state and
// *first_energy du_pred . K du_pred, the scale of the energy test.
Status NewtonRun::Predict(double target, const Loading& loading, Eigen::VectorXd* trial,
                          double* first_energy) {
  const double amplitude_change = Amplitude(target) - Amplitude(load_);
  DofMap increment = dofs_;
  for (int dof = 0; dof < dofs_.num_dofs(); ++dof) {
    if (dofs_.prescribed(dof)) {
      increment.Prescribe(dof / 3, dof % 3, amplitude_change * dofs_.prescribed_value(dof));
    }
  }
  increment.Finalize();
  AssemblyOptions lift = BaseOptions();
  lift.lift_prescribed = true;
  *trial = u_;
  Eigen::VectorXd du;
  // At the converged state f_int = lambda_old f_ext, so the rhs
  // lambda_new f_ext - f_int is the load increment.
  Status status;
  {
    ScopedTimer timer(&report_.assembly_s);
    status = Assemble(loading, u_, increment, lift, &system_);
  }
  if (status.ok() && dofs_.num_free() > 0) {
    status = SolveLinear(
        system_, lift, 0, 0.0, unstable_branch_,
        [&](const AssemblyOptions& options, LinearSystem* out) {
          return Assemble(loading, u_, increment, options, out);
        },
        &du);
  }
  *first_energy = status.ok() && dofs_.num_free() > 0 ? std::abs(du.dot(system_.rhs)) : 0.0;
  if (!status.ok()) return status;
  if (dofs_.num_free() > 0) AddFree(dofs_, du, 1.0, trial);
  for (int dof = 0; dof < dofs_.num_dofs(); ++dof) {
    if (dofs_.prescribed(dof)) (*trial)(dof) = loading.factor * dofs_.prescribed_value(dof);
  }
  return Status::Ok();
}

// The Newton iterations of one increment from the predicted *trial, with a
// backtracking line search, until the convergence tests hold.
Status NewtonRun::Correct(const Loading& loading, double first_energy, Eigen::VectorXd* trial,
                          Attempt* attempt, bool* cancelled) {
  Residual current = EvaluateAt(loading, *trial);
  attempt->residual = current.relative;
  if (!std::isfinite(attempt->residual)) {
    return Status::Numerical("the predictor inverted an element");
  }
  if (dofs_.num_free() == 0) {
    attempt->iteration = 1;  // as the loop below would count it
    attempt->converged = true;
    return Status::Ok();
  }
  Eigen::VectorXd du;
  int augmentations = 0;
  int budget = options_.max_iterations;
  int& iteration = attempt->iteration;
  double& residual = attempt->residual;
  // The residual's norm [N] after each iteration of this attempt (first:
  // the predictor's), for the stagnation test: absolute, since the relative
  // residual of a body whose internal force vanishes as it converges (free
  // growth) stays near 1.
  std::vector<double> history = {current.free.norm()};
  for (iteration = 1; iteration <= budget; ++iteration) {
    if (!keep_going_({load_, iteration, residual})) {
      *cancelled = true;
      return Cancelled();
    }
    const AssemblyOptions options = BaseOptions();
    {
      ScopedTimer timer(&report_.assembly_s);
      PBA_RETURN_IF_ERROR(Assemble(loading, *trial, dofs_, options, &system_));
    }
    PBA_RETURN_IF_ERROR(SolveLinear(
        system_, options, iteration, residual, residual <= kIndefiniteNewtonResidual,
        [&](const AssemblyOptions& again, LinearSystem* out) {
          return Assemble(loading, *trial, dofs_, again, out);
        },
        &du));
    const double energy = std::abs(du.dot(current.free));
    // Backtracking line search: halve the step while it inverts an element
    // or raises the residual.
    double alpha = 1.0;
    Eigen::VectorXd next = *trial;
    AddFree(dofs_, du, alpha, &next);
    Residual candidate = EvaluateAt(loading, next);
    while (options_.line_search && alpha > 1.0 / 64 &&
           !(candidate.relative < std::max(current.relative, 1e-300))) {
      alpha *= 0.5;
      next = *trial;
      AddFree(dofs_, du, alpha, &next);
      candidate = EvaluateAt(loading, next);
    }
    if (!std::isfinite(candidate.relative)) return Status::Numerical("an element inverted");
    *trial = std::move(next);
    current = std::move(candidate);
    residual = current.relative;
    ++report_.total_iterations;
    const double change = alpha * du.norm() / std::max(FreeNorm(dofs_, *trial), 1e-300);
    // The residual and the correction of a nearly incompressible body have a
    // rounding floor (K / mu up to 1e6 amplifies the error of J - 1 and the
    // condition number); once the correction's energy is down at rounding
    // level, no further iteration can improve the state. Measured against
    // the increment's own energy, or the state's when the increment is tiny
    // (after cuts).
    const double energy_scale = std::max(first_energy, current.work);
    const bool rounding_floor = energy <= kRoundingEnergy * energy_scale;
    if ((residual <= options_.residual_tolerance || rounding_floor) &&
        (change <= options_.displacement_tolerance || rounding_floor) &&
        energy <= options_.energy_tolerance * std::max(energy_scale, 1e-300)) {
      if (options_.augment && augmentations < options_.max_augmentations &&
          options_.augment(*trial)) {
        // The equations changed (e.g. contact multipliers): iterate again
        // from this state, with a fresh iteration budget.
        ++augmentations;
        ++report_.augmentations;
        budget = iteration + options_.max_iterations;
        current = EvaluateAt(loading, *trial);
        residual = current.relative;
        history = {current.free.norm()};  // new equations: the stagnation test starts again
        continue;
      }
      attempt->converged = true;
      return Status::Ok();
    }
    if (residual > 1e6) {
      return Status::Numerical(Format("diverging (relative residual %.3g)", residual));
    }
    history.push_back(current.free.norm());
    const int window = options_.stagnation_iterations;
    if (window > 0 && static_cast<int>(history.size()) > window &&
        history.back() > kStagnantShare * history[history.size() - 1 - window]) {
      ++report_.stagnations;
      return Status::Numerical(Format(
          "the residual stagnated at %.3g (relative): the last %d Newton iterations lowered it "
          "by %.2g %% in all (a load the body cannot carry, a part held by nothing, a degenerate "
          "element or material)",
          residual, window, 100 * (1 - history.back() / history[history.size() - 1 - window])));
    }
  }
  return Status::Ok();
}

NewtonRun::Attempt NewtonRun::Increment(double target, const Loading& loading, bool* cancelled) {
  Attempt attempt;
  Eigen::VectorXd trial;
  double first_energy = 0;
  attempt.status = Predict(target, loading, &trial, &first_energy);
  if (attempt.status.ok()) {
    attempt.status = Correct(loading, first_energy, &trial, &attempt, cancelled);
  }
  if (attempt.converged) attempt.status = Accept(target, attempt, &trial);
  return attempt;
}

Status NewtonRun::Accept(double target, const Attempt& attempt, Eigen::VectorXd* trial) {
  u_ = std::move(*trial);
  report_.increments.push_back(
      {target, target - load_, attempt.iteration, attempt.residual, step_negative_});
  load_ = target;
  unstable_branch_ = step_negative_ > 0;
  if (options_.on_increment) options_.on_increment(load_, u_);
  if (attempt.iteration <= options_.quick_iterations) {
    step_ = std::min(step_ * 1.5, options_.max_increment);
  }
  if (options_.observers == nullptr) return Status::Ok();
  return options_.observers->AfterStep({.step = static_cast<int64_t>(report_.increments.size()),
                                        .time_s = load_,
                                        .fraction = load_,
                                        .last = load_ >= 1,
                                        .next_step = step_,
                                        .u = &u_});
}

// A failed increment is halved and retried, down to min_increment.
Status NewtonRun::Cut(double target, const Attempt& attempt) {
  std::string last_failure =
      attempt.status.ok() ? Format("no convergence in %d iterations (relative residual %.3g)",
                                   attempt.iteration - 1, attempt.residual)
                          : attempt.status.message();
  if (attempt.status.ok() && indefinite_streak_ >= 3 && attempt.residual < 1e-4) {
    last_failure += Format(
        "; the tangent stiffness stayed indefinite for the last %d iterations although the "
        "residual was small, so the equilibrium there may be unstable (buckling, or a "
        "spurious mode of the element under strong compression)",
        indefinite_streak_);
  }
  report_.cut_reasons.push_back(Format("increment %.4g -> %.4g: ", load_, target) + last_failure);
  step_ *= 0.5;
  ++report_.cuts;
  if (step_ < options_.min_increment) {
    return Status::Numerical(
        Format("the load could not be applied beyond %.4g of its full value: increments were cut "
               "below %g; last failure: ",
               load_, options_.min_increment) +
        last_failure);
  }
  return Status::Ok();
}

Status NewtonRun::Run() {
  report_ = NewtonReport();
  if (options_.start_u.size() > 0 && options_.start_u.size() != dofs_.num_dofs()) {
    return Status::Internal(Format("the start state has %d unknowns, the model %d",
                                   static_cast<int>(options_.start_u.size()), dofs_.num_dofs()));
  }
  u_ = options_.start_u.size() > 0 ? options_.start_u : Eigen::VectorXd::Zero(dofs_.num_dofs());
  load_ = options_.start_load;
  step_ = options_.start_step > 0 ? options_.start_step
                                  : 1.0 / std::max(1, options_.initial_increments);
  while (load_ < 1.0) {
    if (!keep_going_({load_, 0, INFINITY})) return Cancelled();
    const double largest = options_.max_increment_at
                               ? std::max(options_.min_increment, options_.max_increment_at(load_))
                               : INFINITY;
    step_ = std::min(step_, largest);
    // A last sliver below the smallest increment joins this one.
    const double target = load_ + step_ >= 1.0 - 0.5 * options_.min_increment ? 1.0 : load_ + step_;
    const Loading loading{loads_, Amplitude(target)};
    if (options_.begin_increment) PBA_RETURN_IF_ERROR(options_.begin_increment(load_, target));
    bool cancelled = false;
    const Attempt attempt = Increment(target, loading, &cancelled);
    if (cancelled) return attempt.status;
    if (attempt.converged) {
      PBA_RETURN_IF_ERROR(attempt.status);
      continue;
    }
    if (attempt.status.code() == Status::Code::kCancelled) return attempt.status;
    PBA_RETURN_IF_ERROR(Cut(target, attempt));
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
  NewtonRun run(model, loads, dofs, options, solver, keep_going, u, report);
  return run.Run();
}

}  // namespace pba
