// Preconditioned conjugate gradients (Eigen) with an incomplete Cholesky
// preconditioner (Lin & More 1999, as in Eigen's IncompleteCholesky: the
// factor keeps the original matrix's entry count per column, AMD ordering,
// diagonal scaling and a growing diagonal shift when a pivot fails). For
// systems whose direct factor would not fit in memory: the preconditioner
// costs about the matrix's own storage, where the Cholesky factor of a 3D
// mesh grows like n^(4/3).
#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <vector>

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
  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    // Eigen's solver keeps a reference to the matrix it was given; Newton
    // reuses an older factorisation (a modified-Newton step) after its own
    // matrix is gone, so the solver owns a copy.
    factorized_ = false;
    a_ = a;
    a_.makeCompressed();
    if (!a_.coeffs().allFinite()) {
      return Status::Numerical("the stiffness matrix has entries that are not finite numbers");
    }
    // A positive definite matrix has a positive diagonal. The incomplete
    // factorisation would shift such a matrix into one it can factorise, and
    // CG would then wander, so this necessary condition is checked first.
    const Eigen::VectorXd diagonal = a_.diagonal();
    for (Eigen::Index i = 0; i < diagonal.size(); ++i) {
      if (!(diagonal(i) > 0)) {
        return Status::Numerical(
            Format("the stiffness matrix is not positive definite (diagonal entry %lld is %.3g): "
                   "a body not held against rigid motion, or a degenerate mesh",
                   static_cast<long long>(i), diagonal(i)));
      }
    }
    // Newton iterations refactorise the same pattern: the AMD ordering is
    // computed once per pattern.
    if (!SamePattern(a_)) {
      solver_.analyzePattern(a_);
      outer_.assign(a_.outerIndexPtr(), a_.outerIndexPtr() + a_.outerSize() + 1);
      inner_.assign(a_.innerIndexPtr(), a_.innerIndexPtr() + a_.nonZeros());
    }
    solver_.factorize(a_);
    if (solver_.info() != Eigen::Success) {
      return Status::Numerical(
          "the incomplete Cholesky preconditioner could not be computed even with a diagonal "
          "shift: the stiffness matrix is far from positive definite; try analysis.linear_solver "
          "CHOLMOD");
    }
    solver_.setTolerance(kRelativeTolerance);
    solver_.setMaxIterations(std::max<Eigen::Index>(
        kMinIterations, kIterationsPerUnknown * static_cast<Eigen::Index>(a_.rows())));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    // After a failed Factorize, Eigen's solver still refers to the matrix
    // that a_ held before.
    if (!factorized_) return Status::Internal("PCG solve without a successful Factorize");
    *x = solver_.solve(b);
    iterations_ = static_cast<int>(solver_.iterations());
    const double scale = b.norm();
    residual_ = x->allFinite() ? (b - a_ * *x).norm() / (scale > 0 ? scale : 1.0) : INFINITY;
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
  std::string Name() const override {
    std::string name = "conjugate gradient with incomplete Cholesky (IC) preconditioner";
    if (iterations_ >= 0) {
      name +=
          Format(" (last solve: %d iterations, relative residual %.1e)", iterations_, residual_);
    }
    return name;
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<PcgSolver>();
  }

 private:
  bool SamePattern(const Eigen::SparseMatrix<double>& a) const {
    return outer_.size() == static_cast<std::size_t>(a.outerSize()) + 1 &&
           inner_.size() == static_cast<std::size_t>(a.nonZeros()) &&
           std::equal(outer_.begin(), outer_.end(), a.outerIndexPtr()) &&
           std::equal(inner_.begin(), inner_.end(), a.innerIndexPtr());
  }

  Eigen::SparseMatrix<double> a_;
  std::vector<int> outer_, inner_;
  // Lower | Upper: both triangles are stored, so the matrix-vector product
  // runs on the full matrix, which Eigen parallelises with OpenMP (it cannot
  // for a product through a selfadjoint view of one triangle).
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>
      solver_;
  bool factorized_ = false;
  int iterations_ = -1;  // of the last solve; -1 before the first
  double residual_ = 0;  // true relative residual of the last solve
};

}  // namespace

std::unique_ptr<LinearSolver> CreatePcgSolver() { return std::make_unique<PcgSolver>(); }

}  // namespace pba
