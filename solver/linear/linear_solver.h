// LinearSolver: factorise a symmetric positive definite matrix once, solve
// for right-hand sides. One backend per file; CreateLinearSolver picks one.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <atomic>
#include <memory>
#include <string>

#include "core/thread_context.h"
#include "pba/status.h"

namespace pba {

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // Analyses and factorises `a` (both triangles stored; only the lower one is read).
  // A matrix that is not positive definite gives Status::Numerical.
  virtual Status Factorize(const Eigen::SparseMatrix<double>& a) = 0;
  virtual Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) = 0;
  // For people, e.g. "CHOLMOD supernodal Cholesky".
  virtual std::string Name() const = 0;
  // A fresh solver of the same kind (to hold a second factorisation).
  virtual std::unique_ptr<LinearSolver> NewOfSameKind() const = 0;
};

// Which backend an implicit analysis factorises with (analysis.linear_solver).
struct LinearSolverOptions {
  enum class Kind {
    kCholmod,    // supernodal sparse Cholesky (SuiteSparse), the default
    kEigenLdlt,  // Eigen's simplicial LDL^T, the fallback
    kPcg,        // conjugate gradients with incomplete Cholesky (CreatePcgSolver)
  };
  Kind kind = Kind::kCholmod;
  // Set by the caller to stop an iterative solve early (the analysis passes
  // SolveOptions::cancel): PCG looks at it every iteration and its Solve
  // returns Status::Cancelled. Direct factorisations cannot be interrupted:
  // CHOLMOD's and Eigen's run to the end once started (seconds to minutes on
  // a large mesh) and the flag is seen after them. Not owned; may be null.
  const std::atomic<bool>* cancel = nullptr;
  // The threads a factorisation may use (CHOLMOD's and its BLAS's):
  // SolveScene sets the solve's.
  ThreadContext threads;

  // "CHOLMOD", "EIGEN_LDLT" or "PCG": the scene's name for the kind.
  const char* KindName() const;
};

std::unique_ptr<LinearSolver> CreateLinearSolver(const LinearSolverOptions& options);

// The backends (linear/cholmod_solver.cc, linear/eigen_ldlt_solver.cc,
// linear/pcg_solver.cc).
// CHOLMOD's OpenMP teams and its BLAS's threads are bounded by `threads`
// during each factorisation and solve (LibraryThreadScope).
std::unique_ptr<LinearSolver> CreateCholmodSolver(const ThreadContext& threads);
std::unique_ptr<LinearSolver> CreateEigenLdltSolver();
// Iterative: conjugate gradients with an incomplete Cholesky preconditioner,
// aiming at ||b - A x|| / ||b|| <= 1e-12 in at most max(1000, 10 n)
// iterations. Factorize computes the preconditioner (and keeps a copy of
// `a`); Solve fails with Status::Numerical, naming the iterations and the
// residual reached, when the true residual ends above 1e-8. After a solve,
// Name() carries its iteration count and residual. A set `*cancel` (may be
// null) ends a solve within an iteration with Status::Cancelled.
std::unique_ptr<LinearSolver> CreatePcgSolver(const std::atomic<bool>* cancel = nullptr);

}  // namespace pba
