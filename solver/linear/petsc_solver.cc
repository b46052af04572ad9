// The PETSc backends: conjugate gradients with algebraic multigrid (GAMG or
// hypre's BoomerAMG) for systems too large to factorise, and MUMPS, the
// multifrontal direct solver, for the fallback and for users who want it.
// In a process of its own they work on PETSC_COMM_SELF; as ranks of an MPI
// job (mpirun), every rank hands PETSc its share of the rows and all of
// them solve together (PetscMatrix). Every PETSc call holds PetscLock.
#include <petscksp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_matrix.h"
#include "linear/petsc_runtime.h"

namespace pba {
namespace {

using petsc_detail::CancellableTest;
using petsc_detail::ConfigureMumps;
using petsc_detail::Digest;
using petsc_detail::ExpandedSolve;
using petsc_detail::FactorizeMumps;
using petsc_detail::OnRanks;
using petsc_detail::PetscMatrix;
using petsc_detail::PetscObjects;
using petsc_detail::SetRigidBodyNearNullSpace;
using petsc_detail::SolveCounts;
using petsc_detail::SolverComm;

// Across ranks with a layout: this rank's nodes (PetscMatrix's split), for
// OwnNodes; empty otherwise.
std::vector<char> OwnNodesOf(const UnknownLayout* layout) {
  const ProcessRanks ranks = CurrentRanks();
  if (layout == nullptr || ranks.size <= 1) return {};
  return petsc_detail::NodesOfRank(*layout, ranks.rank, ranks.size);
}

class MumpsSolver final : public LinearSolver {
 public:
  // The layout only matters across ranks: one process factorises the
  // system as given.
  explicit MumpsSolver(const UnknownLayout* layout)
      : layout_(CurrentRanks().size > 1 ? layout : nullptr), own_nodes_(OwnNodesOf(layout_)) {}
  ~MumpsSolver() override {
    const auto lock = PetscLock();
    objects_.Destroy();
  }

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    PBA_RETURN_IF_ERROR(InitializePetsc());
    const auto lock = PetscLock();
    factorized_ = false;
    bool rebuilt = false;
    PBA_RETURN_IF_ERROR(matrix_.Load(a, layout_, &objects_, &rebuilt));
    if (rebuilt || objects_.ksp == nullptr) {
      PBA_RETURN_IF_ERROR(objects_.NewSolver());
      PBA_RETURN_IF_ERROR(ConfigureMumps(objects_.ksp, objects_.matrix));
    }
    PBA_RETURN_IF_ERROR(FactorizeMumps(objects_.ksp, objects_.matrix));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (!factorized_) return Status::Internal("MUMPS solve without a successful Factorize");
    const auto lock = PetscLock();
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, objects_.ksp, &objects_, b, x));
    if (!x->allFinite()) return Status::Numerical("MUMPS's solve produced no finite answer");
    return Status::Ok();
  }

  std::string Name() const override { return "MUMPS multifrontal LDL^T (PETSc)" + OnRanks(); }
  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<MumpsSolver>(layout_);
  }
  const std::vector<char>* OwnNodes() const override {
    return own_nodes_.empty() ? nullptr : &own_nodes_;
  }

 private:
  const UnknownLayout* layout_;  // not owned; null on one process
  std::vector<char> own_nodes_;
  PetscMatrix matrix_;
  PetscObjects objects_;
  bool factorized_ = false;
};

// Conjugate gradients with algebraic multigrid.
class AmgSolver final : public LinearSolver {
 public:
  AmgSolver(const LinearSolverSettings& settings, const UnknownLayout* layout,
            const std::atomic<bool>* cancel)
      : settings_(settings),
        layout_(layout),
        cancel_(cancel),
        own_nodes_(OwnNodesOf(layout)),
        test_(cancel) {}
  ~AmgSolver() override {
    const auto lock = PetscLock();
    DestroyFallback();
    objects_.Destroy();
  }

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    PBA_RETURN_IF_ERROR(InitializePetsc());
    factorized_ = false;
    fallback_factorized_ = false;
    // A positive definite matrix has a positive diagonal; CG on one that is
    // not would wander, so this necessary condition is checked first (as
    // PCG does). Indefinite matrices with a positive diagonal show as a
    // failed solve. Across ranks each checks its own columns, all it may
    // hold (OwnNodes), once the matrix is loaded.
    if (own_nodes_.empty()) PBA_RETURN_IF_ERROR(CheckPositiveDiagonal(a));
    unknowns_ = a.rows();
    const auto lock = PetscLock();
    bool rebuilt = false;
    PBA_RETURN_IF_ERROR(matrix_.Load(a, layout_, &objects_, &rebuilt));
    if (!own_nodes_.empty()) PBA_RETURN_IF_ERROR(matrix_.CheckPositiveDiagonal(a));
    if (rebuilt) DestroyFallback();
    if (rebuilt || objects_.ksp == nullptr) {
      PBA_RETURN_IF_ERROR(Setup());
      hierarchy_iterations_ = -1;
    }
    // Lagged multigrid: the hierarchy built for an earlier matrix of the
    // same pattern (Newton's last tangent) preconditions this one while the
    // solves it serves take at most twice (plus five) the iterations of its
    // first; past that, or when a solve with it fails, it is rebuilt. Its
    // setup (aggregation, Galerkin products, smoother estimates) costs
    // several solves, and Newton's tangents change little between
    // iterations. The answer is unaffected: every solve meets the same
    // tolerance on the true residual of the current matrix.
    const bool reuse = hierarchy_iterations_ >= 0 && !rebuild_next_ &&
                       counts_.last_iterations <= 2 * hierarchy_iterations_ + 5;
    PBA_RETURN_IF_ERROR(SetUpPreconditioner(reuse));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (!factorized_) return Status::Internal("AMG solve without a successful Factorize");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    int iterations = 0;
    double residual = INFINITY;
    PBA_RETURN_IF_ERROR(Iterate(b, x, &reason, &iterations, &residual));
    // A lagged hierarchy that no longer serves: rebuilt for this matrix and
    // the solve redone once.
    if (!Converged(reason, residual) && reused_ && !test_.cancelled() &&
        reason != KSP_DIVERGED_INDEFINITE_MAT) {
      {
        const auto lock = PetscLock();
        PBA_RETURN_IF_ERROR(SetUpPreconditioner(false));
      }
      PBA_RETURN_IF_ERROR(Iterate(b, x, &reason, &iterations, &residual));
    }
    if (test_.cancelled()) {
      return Status::Cancelled(
          Format("cancelled during conjugate gradients (iteration %d)", iterations));
    }
    counts_.Record(iterations, residual);
    if (hierarchy_iterations_ < 0) hierarchy_iterations_ = iterations;
    if (Converged(reason, residual)) return Status::Ok();
    rebuild_next_ = true;
    if (reason == KSP_DIVERGED_INDEFINITE_MAT) {
      // Negative curvature p.Ap < 0: the matrix itself is indefinite (a
      // Newton tangent past a limit point, far from equilibrium), which no
      // other solver would change.
      return Status::Numerical(
          Format("the stiffness matrix is not positive definite: conjugate gradients met a "
                 "direction of negative curvature at iteration %d",
                 iterations));
    }
    const std::string failure = Format(
        "conjugate gradients with %s did not converge: %d iterations reached a relative "
        "residual of %.3g (target %.1e, %s)",
        settings_.PreconditionerName(), iterations, residual, settings_.relative_tolerance,
        KSPConvergedReasons[reason]);
    if (unknowns_ > settings_.fallback_direct_max_unknowns) {
      return Status::Numerical(
          failure + Format("; the system (%lld unknowns) is above "
                           "linear_solver_options.fallback_direct_max_unknowns (%d), so it is "
                           "not redone by MUMPS; a nearly incompressible material or a body "
                           "barely held against rigid motion are the usual causes",
                           static_cast<long long>(unknowns_),
                           settings_.fallback_direct_max_unknowns));
    }
    // Redone by MUMPS, whose inertia also tells an indefinite matrix: a
    // factorisation of the matrix PETSc holds for the multigrid (a
    // modified-Newton step solves with it after the caller's matrix is
    // gone), kept for the next solves with this one.
    const auto lock = PetscLock();
    if (!fallback_factorized_) {
      if (fallback_ == nullptr) {
        PBA_PETSC(KSPCreate(SolverComm(), &fallback_));
        PBA_RETURN_IF_ERROR(ConfigureMumps(fallback_, objects_.matrix));
      }
      const Status factorized = FactorizeMumps(fallback_, objects_.matrix);
      if (!factorized.ok()) {
        return Status::Numerical(failure + "; MUMPS, the fallback: " + factorized.message());
      }
      fallback_factorized_ = true;
    }
    ++fallbacks_;
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, fallback_, &objects_, b, x));
    if (!x->allFinite()) return Status::Numerical("MUMPS's solve produced no finite answer");
    return Status::Ok();
  }

  bool Iterative() const override { return true; }
  std::string Name() const override {
    std::string name =
        Format("conjugate gradients with %s (PETSc%s), relative tolerance %.0e",
               settings_.PreconditionerName(), OnRanks().c_str(), settings_.relative_tolerance);
    if (layout_ == nullptr) name += ", scalar aggregation (no rigid-body modes)";
    if (counts_.solves > 0) {
      name += Format(
          " (%d solves, %d-%d iterations, %d multigrid setups; last: %d iterations, relative "
          "residual %.1e",
          counts_.solves, counts_.min_iterations, counts_.max_iterations, setups_,
          counts_.last_iterations, counts_.last_residual);
      if (fallbacks_ > 0) name += Format("; %d redone by MUMPS", fallbacks_);
      name += ")";
    }
    return name;
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<AmgSolver>(settings_, layout_, cancel_);
  }
  const std::vector<char>* OwnNodes() const override {
    return own_nodes_.empty() ? nullptr : &own_nodes_;
  }

 private:
  // The fallback's factorisation (of an earlier pattern's matrix) goes.
  void DestroyFallback() {
    if (fallback_ != nullptr) KSPDestroy(&fallback_);
    fallback_factorized_ = false;
  }

  Status Setup() {
    if (layout_ != nullptr) {
      PBA_RETURN_IF_ERROR(SetRigidBodyNearNullSpace(matrix_, *layout_, objects_.matrix));
    }
    PBA_RETURN_IF_ERROR(objects_.NewSolver());
    fresh_ksp_ = true;
    PBA_PETSC(KSPSetType(objects_.ksp, KSPCG));
    // The tolerance is on the residual itself, ||b - A x|| / ||b||.
    PBA_PETSC(KSPSetNormType(objects_.ksp, KSP_NORM_UNPRECONDITIONED));
    PBA_PETSC(KSPSetTolerances(objects_.ksp, settings_.relative_tolerance, 0.0, PETSC_DEFAULT,
                               settings_.max_iterations));
    PBA_PETSC(KSPSetErrorIfNotConverged(objects_.ksp, PETSC_FALSE));
    PBA_RETURN_IF_ERROR(test_.Install(objects_.ksp));
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(objects_.ksp, &pc));
    // PRESSURE_SCHUR has a solver of its own (CreateAmgSolver).
    if (settings_.preconditioner != LinearSolverSettings::Preconditioner::kBoomerAmg) {
      PBA_PETSC(PCSetType(pc, PCGAMG));
      PBA_PETSC(PCGAMGSetType(pc, PCGAMGAGG));
      PetscReal threshold[] = {settings_.gamg_threshold};
      PBA_PETSC(PCGAMGSetThreshold(pc, threshold, 1));
      // Completes the multigrid's defaults (Chebyshev-Jacobi smoothing on
      // every level) from an options database holding nothing of the
      // user's (InitializePetsc cleared it): without it the levels keep
      // PCMG's bare defaults, whose V-cycle was several times dearer.
      PBA_PETSC(KSPSetFromOptions(objects_.ksp));
    } else {
      PBA_PETSC(PCSetType(pc, PCHYPRE));
      PBA_PETSC(PCHYPRESetType(pc, "boomeramg"));
      // hypre reads its parameters from the options database: this
      // solver's, under its own prefix, set from the scene only.
      const std::string prefix = Format("pba_amg_%p_", static_cast<void*>(this));
      PBA_PETSC(KSPSetOptionsPrefix(objects_.ksp, prefix.c_str()));
      const std::string strong = Format("%.17g", settings_.boomeramg_strong_threshold);
      const std::pair<const char*, std::string> options[] = {
          {"pc_hypre_boomeramg_strong_threshold", strong},
          {"pc_hypre_boomeramg_coarsen_type", "HMIS"},
          {"pc_hypre_boomeramg_interp_type", "ext+i"},
          {"pc_hypre_boomeramg_nodal_coarsen", layout_ != nullptr ? "6" : "0"},
      };
      for (const auto& [key, value] : options) {
        const std::string name = "-" + prefix + key;
        PBA_PETSC(PetscOptionsSetValue(nullptr, name.c_str(), value.c_str()));
      }
      PBA_PETSC(PCSetFromOptions(pc));
      for (const auto& [key, value] : options) {
        const std::string name = "-" + prefix + key;
        PetscOptionsClearValue(nullptr, name.c_str());
      }
    }
    return Status::Ok();
  }

  // Builds the hierarchy for the current matrix, or keeps the last one.
  Status SetUpPreconditioner(bool reuse) {
    // A new hierarchy is built in a new KSP: set up again in place, GAMG
    // kept parts of the old one, and its smoothers could then make the
    // preconditioner indefinite for a matrix far from the old (seen as
    // DIVERGED_INDEFINITE_PC). The aggregation it would save is a small
    // part of a set-up; the Galerkin products are redone either way.
    if (!reuse && !fresh_ksp_) PBA_RETURN_IF_ERROR(Setup());
    fresh_ksp_ = false;
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(objects_.ksp, &pc));
    PBA_PETSC(PCSetReusePreconditioner(pc, reuse ? PETSC_TRUE : PETSC_FALSE));
    PBA_PETSC(KSPSetOperators(objects_.ksp, objects_.matrix, objects_.matrix));
    PBA_PETSC(KSPSetUp(objects_.ksp));
    PCFailedReason failed = PC_NOERROR;
    PBA_PETSC(PCGetFailedReason(pc, &failed));
    if (failed != PC_NOERROR) {
      return Status::Numerical(
          Format("the multigrid preconditioner could not be built (%s)", PCFailedReasons[failed]));
    }
    reused_ = reuse;
    if (!reuse) {
      ++setups_;
      hierarchy_iterations_ = -1;
      rebuild_next_ = false;
    }
    return Status::Ok();
  }

  // One CG solve: its reason, iterations and true relative residual.
  Status Iterate(const Eigen::VectorXd& b, Eigen::VectorXd* x, KSPConvergedReason* reason,
                 int* iterations, double* residual) {
    const auto lock = PetscLock();
    test_.Reset();
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, objects_.ksp, &objects_, b, x));
    PetscInt its = 0;
    PBA_PETSC(KSPGetIterationNumber(objects_.ksp, &its));
    *iterations = static_cast<int>(its);
    PBA_PETSC(KSPGetConvergedReason(objects_.ksp, reason));
    // The true residual of the system solved (prescribed rows included:
    // theirs is their tiny solution times the scale).
    PBA_RETURN_IF_ERROR(TrueResidual(residual));
    if (!x->allFinite()) *residual = INFINITY;
    return Status::Ok();
  }

  // The recurrence CG tests drifts from the true residual; a digit of
  // drift is accepted, more is not convergence.
  bool Converged(KSPConvergedReason reason, double residual) const {
    return reason > 0 && residual <= 10 * settings_.relative_tolerance;
  }

  // ||b - A x|| / ||b|| over the expanded system just solved.
  Status TrueResidual(double* residual) {
    Vec r = nullptr;
    PBA_PETSC(VecDuplicate(objects_.rhs, &r));
    PetscReal r_norm = 0, b_norm = 0;
    PetscErrorCode code = MatMult(objects_.matrix, objects_.solution, r);
    if (code == 0) code = VecAYPX(r, -1.0, objects_.rhs);
    if (code == 0) code = VecNorm(r, NORM_2, &r_norm);
    if (code == 0) code = VecNorm(objects_.rhs, NORM_2, &b_norm);
    VecDestroy(&r);
    PBA_PETSC(code);
    *residual = r_norm / (b_norm > 0 ? b_norm : 1.0);
    if (!std::isfinite(*residual)) *residual = INFINITY;
    return Status::Ok();
  }

  LinearSolverSettings settings_;
  const UnknownLayout* layout_;      // not owned; may be null
  const std::atomic<bool>* cancel_;  // not owned; may be null
  std::vector<char> own_nodes_;      // across ranks with a layout (OwnNodesOf)
  PetscMatrix matrix_;
  PetscObjects objects_;
  CancellableTest test_;
  KSP fallback_ = nullptr;            // MUMPS on objects_.matrix, once a solve needed it
  bool fallback_factorized_ = false;  // of the matrix's current values
  Eigen::Index unknowns_ = 0;
  bool factorized_ = false;
  SolveCounts counts_;
  int fallbacks_ = 0, setups_ = 0;
  // Iterations of the first solve with the current hierarchy (-1: none yet).
  int hierarchy_iterations_ = -1;
  bool reused_ = false;        // the current solve's hierarchy is an earlier matrix's
  bool fresh_ksp_ = false;     // the KSP has not been set up yet
  bool rebuild_next_ = false;  // the last solve failed: no reuse at the next Factorize
};

}  // namespace

std::unique_ptr<LinearSolver> CreateAmgSolver(const LinearSolverSettings& settings,
                                              const UnknownLayout* layout,
                                              const std::atomic<bool>* cancel) {
  if (settings.preconditioner == LinearSolverSettings::Preconditioner::kPressureSchur) {
    return CreatePressureSchurSolver(settings, layout, cancel);
  }
  return std::make_unique<AmgSolver>(settings, layout, cancel);
}

std::unique_ptr<LinearSolver> CreateMumpsSolver(const UnknownLayout* layout) {
  return std::make_unique<MumpsSolver>(layout);
}

}  // namespace pba
