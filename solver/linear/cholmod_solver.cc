// Sparse direct solve by CHOLMOD's supernodal Cholesky (SuiteSparse), through
// Eigen's wrapper; fill-reducing ordering chosen by CHOLMOD (AMD/METIS).
#include <Eigen/CholmodSupport>
#include <algorithm>
#include <vector>

#include "linear/linear_solver.h"

namespace pba {
namespace {

class CholmodSolver final : public LinearSolver {
 public:
  // A matrix that is not positive definite is reported through Status (a
  // Newton iterate far from equilibrium may have one, and the load step is
  // then cut), so CHOLMOD's own warning print is turned off.
  explicit CholmodSolver(const ThreadContext& threads) : threads_(threads) {
    solver_.cholmod().print = 0;
  }

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    const LibraryThreadScope bounded(threads_);
    // Newton iterations refactorise the same pattern: the fill-reducing
    // ordering and symbolic analysis are done once per pattern.
    if (!SamePattern(a)) {
      solver_.analyzePattern(a);
      outer_.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
      inner_.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
    }
    solver_.factorize(a);
    if (solver_.info() != Eigen::Success) {
      return Status::Numerical(
          "CHOLMOD could not factorise the stiffness matrix: it is not positive definite "
          "(a body not held against rigid motion, or a degenerate mesh)");
    }
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    const LibraryThreadScope bounded(threads_);
    *x = solver_.solve(b);
    if (solver_.info() != Eigen::Success || !x->allFinite()) {
      return Status::Numerical("CHOLMOD's solve produced no finite answer");
    }
    return Status::Ok();
  }

  std::string Name() const override { return "CHOLMOD supernodal Cholesky"; }
  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<CholmodSolver>(threads_);
  }

 private:
  bool SamePattern(const Eigen::SparseMatrix<double>& a) const {
    return a.isCompressed() && outer_.size() == static_cast<std::size_t>(a.outerSize()) + 1 &&
           inner_.size() == static_cast<std::size_t>(a.nonZeros()) &&
           std::equal(outer_.begin(), outer_.end(), a.outerIndexPtr()) &&
           std::equal(inner_.begin(), inner_.end(), a.innerIndexPtr());
  }

  ThreadContext threads_;
  std::vector<int> outer_, inner_;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver_;
};

}  // namespace

Status PredictCholmodFactor(const Eigen::SparseMatrix<double>& a, const ThreadContext& threads,
                            FactorPrediction* prediction) {
  const LibraryThreadScope bounded(threads);
  cholmod_common common;
  cholmod_start(&common);
  common.print = 0;
  common.supernodal = CHOLMOD_SUPERNODAL;
  // A view of the lower triangle (no copy), as the solver factorises it.
  cholmod_sparse view = Eigen::viewAsCholmod(a.selfadjointView<Eigen::Lower>());
  cholmod_factor* factor = cholmod_analyze(&view, &common);
  Status status = Status::Ok();
  if (factor == nullptr || common.status < CHOLMOD_OK) {
    status = Status::Internal("CHOLMOD's symbolic analysis failed");
  } else {
    // The supernodal factor's values, its row indices and the column
    // structure per supernode.
    prediction->bytes = static_cast<double>(factor->xsize) * sizeof(double) +
                        static_cast<double>(factor->ssize) * sizeof(int);
    prediction->flops = common.fl;
  }
  if (factor != nullptr) cholmod_free_factor(&factor, &common);
  cholmod_finish(&common);
  return status;
}

std::unique_ptr<LinearSolver> CreateCholmodSolver(const ThreadContext& threads) {
  return std::make_unique<CholmodSolver>(threads);
}

}  // namespace pba
