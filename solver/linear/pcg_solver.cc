// Preconditioned conjugate gradients (Eigen) with an incomplete Cholesky
// preconditioner (Lin & More 1999, as in Eigen's IncompleteCholesky: the
// factor keeps the original matrix's entry count per column, diagonal
// scaling and a growing diagonal shift when a pivot fails). For systems
// whose direct factor would not fit in memory: the solver keeps the lower
// triangle of the matrix and a factor of the same size, where the Cholesky
// factor of a 3D mesh grows like n^(4/3).
#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

#include "core/format.h"
#include "linear/linear_solver.h"

namespace pba {
namespace {

// Relative residual ||b - A x|| / ||b|| at which CG stops. The solution
// feeds Newton's tests (relative force residual 1e-8 by default, energy
// 1e-12): an inexact linear solve would leave its error in every Newton
// correction and stall the iteration above those tolerances, so CG is run to
// near the accuracy a direct solve gives rather than to the usual 1e-6..1e-8.
constexpr double kRelativeTolerance = 1e-12;

// CG on an n x n positive definite matrix ends in n steps in exact
// arithmetic; rounding and clustered eigenvalues cost more. Ten times n (and
// at least 1000, for small systems) is past any useful convergence and
// bounds the time of a solve that will not converge.
constexpr int kMinIterations = 1000;
constexpr int kIterationsPerUnknown = 10;

// What is accepted at the end, the true residual ||b - A x|| / ||b||. CG
// tests the residual it updates by recurrence, which drifts from the true one
// in floating point, the more so the worse the conditioning; and on an ill
// conditioned matrix it can stagnate just above the target until the
// iteration limit. Either answer is still far more accurate than Newton
// needs (its correction's residual is measured against the whole internal
// force, this one against the current out-of-balance force), so it is
// accepted; a worse one is refused rather than passed on.
constexpr double kAcceptedResidual = 1e-8;

class PcgSolver final : public LinearSolver {
 public:
  explicit PcgSolver(const std::atomic<bool>* cancel) : cancel_(cancel) {}

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    // Eigen's solver keeps a reference to the matrix it was given; Newton
    // reuses an older factorisation (a modified-Newton step) after its own
    // matrix is gone, so the solver owns a copy - of the lower triangle
    // only, half the memory: the matrix is symmetric, CG multiplies through
    // its selfadjoint view and the incomplete factorisation reads only that
    // triangle. That product runs on one thread where the full matrix's
    // would use OpenMP, but it reads half the data and is bound by memory
    // bandwidth: on the 2-core machine CG was not slower for it (TET10,
    // 101,277 unknowns in scaling_bench: 11.6 s against 16 s per Newton
    // iteration, one run each).
    //
    // The last matrix and factor are released first, so that the new ones
    // never coexist with them (Newton never refactorises the solver that
    // holds its last good factorisation).
    factorized_ = false;
    preconditioner_.reset();
    lower_ = Eigen::SparseMatrix<double>();
    lower_ = a.triangularView<Eigen::Lower>();
    if (!Eigen::Map<const Eigen::VectorXd>(lower_.valuePtr(), lower_.nonZeros()).allFinite()) {
      return Status::Numerical("the stiffness matrix has entries that are not finite numbers");
    }
    // A positive definite matrix has a positive diagonal. The incomplete
    // factorisation would shift such a matrix into one it can factorise, and
    // CG would then wander, so this necessary condition is checked first.
    PBA_RETURN_IF_ERROR(CheckPositiveDiagonal(lower_));
    // The natural ordering needs no analysis (see Preconditioner below).
    preconditioner_ = std::make_unique<Preconditioner>();
    preconditioner_->compute(lower_);
    if (preconditioner_->info() != Eigen::Success) {
      return Status::Numerical(
          "the incomplete Cholesky preconditioner could not be computed even with a diagonal "
          "shift: the stiffness matrix is far from positive definite; try analysis.linear_solver "
          "CHOLMOD");
    }
    max_iterations_ = std::max<Eigen::Index>(
        kMinIterations, kIterationsPerUnknown * static_cast<Eigen::Index>(lower_.rows()));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (!factorized_) return Status::Internal("PCG solve without a successful Factorize");
    PBA_RETURN_IF_ERROR(Iterate(b, x));
    const double scale = b.norm();
    residual_ = x->allFinite() ? (b - lower_.selfadjointView<Eigen::Lower>() * *x).norm() /
                                     (scale > 0 ? scale : 1.0)
                               : INFINITY;
    if (!(residual_ <= kAcceptedResidual)) {
      return Status::Numerical(
          Format("conjugate gradients did not converge: %d iterations reached a relative "
                 "residual of %.3g (target %.0e); the matrix may be ill conditioned (a nearly "
                 "incompressible material), singular or indefinite (a body not held against "
                 "rigid motion) - the direct solver, analysis.linear_solver CHOLMOD, copes "
                 "better",
                 iterations_, residual_, kRelativeTolerance));
    }
    return Status::Ok();
  }

  // After a solve the name carries its iteration count and residual, so the
  // summary shows how hard the last system was.
  bool Iterative() const override { return true; }
  std::string Name() const override {
    std::string name = "conjugate gradient with incomplete Cholesky (IC) preconditioner";
    if (iterations_ >= 0) {
      name +=
          Format(" (last solve: %d iterations, relative residual %.1e)", iterations_, residual_);
    }
    return name;
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<PcgSolver>(cancel_);
  }

 private:
  // Preconditioned CG from x = 0 until ||r|| <= kRelativeTolerance ||b|| or
  // max_iterations_, as Eigen's internal::conjugate_gradient (Saad,
  // Iterative Methods for Sparse Linear Systems, algorithm 9.1) but written
  // out so that a cancel is seen every iteration: a solve runs hundreds of
  // iterations, minutes on a large mesh. Sets iterations_.
  Status Iterate(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
    const auto a = lower_.selfadjointView<Eigen::Lower>();
    x->setZero(b.size());
    iterations_ = 0;
    const double b_norm2 = b.squaredNorm();
    if (b_norm2 == 0) return Status::Ok();
    const double threshold = std::max(kRelativeTolerance * kRelativeTolerance * b_norm2,
                                      std::numeric_limits<double>::min());
    Eigen::VectorXd r = b;
    Eigen::VectorXd p = preconditioner_->solve(r);
    Eigen::VectorXd z(b.size()), ap(b.size());
    double rz = r.dot(p);
    for (Eigen::Index i = 0; i < max_iterations_; ++i) {
      if (cancel_ != nullptr && cancel_->load(std::memory_order_relaxed)) {
        return Status::Cancelled(Format("cancelled during conjugate gradients (iteration %lld)",
                                        static_cast<long long>(i)));
      }
      ap.noalias() = a * p;
      const double alpha = rz / p.dot(ap);
      *x += alpha * p;
      r -= alpha * ap;
      iterations_ = static_cast<int>(i + 1);
      if (r.squaredNorm() < threshold) break;
      z = preconditioner_->solve(r);
      const double rz_old = rz;
      rz = r.dot(z);
      p = z + (rz / rz_old) * p;
    }
    return Status::Ok();
  }

  Eigen::SparseMatrix<double> lower_;  // lower triangle of the last matrix factorised
  // The incomplete factor in the natural ordering, the mesh's node
  // numbering. An AMD ordering, made to limit the fill of complete factors,
  // costs more CG iterations here (scaling_bench, K/mu = 10, 101,277
  // unknowns: 714 against 503 per solve with TET10, 162 against 97 with
  // TET4_ANP), and with it Eigen forms a permuted copy of the whole matrix,
  // both triangles, at every factorisation.
  using Preconditioner =
      Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::NaturalOrdering<int>>;
  std::unique_ptr<Preconditioner> preconditioner_;
  const std::atomic<bool>* cancel_;  // not owned; may be null
  Eigen::Index max_iterations_ = 0;
  bool factorized_ = false;
  int iterations_ = -1;  // of the last solve; -1 before the first
  double residual_ = 0;  // true relative residual of the last solve
};

}  // namespace

std::unique_ptr<LinearSolver> CreatePcgSolver(const std::atomic<bool>* cancel) {
  return std::make_unique<PcgSolver>(cancel);
}

}  // namespace pba
