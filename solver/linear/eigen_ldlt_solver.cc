// Eigen's simplicial LDL^T with AMD ordering: no external library, slower
// than CHOLMOD on large problems; the fallback.
#include <Eigen/SparseCholesky>

#include "linear/linear_solver.h"

namespace pba {
namespace {

class EigenLdltSolver final : public LinearSolver {
 public:
  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    solver_.compute(a);
    if (solver_.info() != Eigen::Success) {
      return Status::Numerical("Eigen's LDL^T could not factorise the stiffness matrix");
    }
    const auto& d = solver_.vectorD();
    if ((d.array() <= 0).any()) {
      return Status::Numerical(
          "the stiffness matrix is not positive definite (a body not held against rigid motion, or "
          "a degenerate mesh)");
    }
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    *x = solver_.solve(b);
    if (solver_.info() != Eigen::Success || !x->allFinite()) {
      return Status::Numerical("Eigen's LDL^T solve produced no finite answer");
    }
    return Status::Ok();
  }

  std::string Name() const override { return "Eigen simplicial LDL^T"; }
  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<EigenLdltSolver>();
  }

 private:
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver_;
};

}  // namespace

std::unique_ptr<LinearSolver> CreateEigenLdltSolver() {
  return std::make_unique<EigenLdltSolver>();
}

}  // namespace pba
