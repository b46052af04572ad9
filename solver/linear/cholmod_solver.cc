// Sparse direct solve by CHOLMOD's supernodal Cholesky (SuiteSparse), through
// Eigen's wrapper; fill-reducing ordering chosen by CHOLMOD (AMD/METIS).
#include <Eigen/CholmodSupport>

#include "linear/linear_solver.h"

namespace pba {
namespace {

class CholmodSolver final : public LinearSolver {
 public:
  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    solver_.compute(a);
    if (solver_.info() != Eigen::Success) {
      return Status::Numerical(
          "CHOLMOD could not factorise the stiffness matrix: it is not positive definite "
          "(a body not held against rigid motion, or a degenerate mesh)");
    }
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    *x = solver_.solve(b);
    if (solver_.info() != Eigen::Success || !x->allFinite()) {
      return Status::Numerical("CHOLMOD's solve produced no finite answer");
    }
    return Status::Ok();
  }

  std::string Name() const override { return "CHOLMOD supernodal Cholesky"; }

 private:
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver_;
};

}  // namespace

std::unique_ptr<LinearSolver> CreateCholmodSolver() { return std::make_unique<CholmodSolver>(); }

}  // namespace pba
