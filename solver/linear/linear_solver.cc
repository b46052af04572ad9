#include "linear/linear_solver.h"

namespace pba {

const char* LinearSolverOptions::KindName() const {
  switch (kind) {
    case Kind::kEigenLdlt:
      return "EIGEN_LDLT";
    case Kind::kPcg:
      return "PCG";
    case Kind::kCholmod:
      break;
  }
  return "CHOLMOD";
}

std::unique_ptr<LinearSolver> CreateLinearSolver(const LinearSolverOptions& options) {
  switch (options.kind) {
    case LinearSolverOptions::Kind::kEigenLdlt:
      return CreateEigenLdltSolver();
    case LinearSolverOptions::Kind::kPcg:
      return CreatePcgSolver(options.cancel);
    case LinearSolverOptions::Kind::kCholmod:
      break;
  }
  return CreateCholmodSolver(options.threads);
}

}  // namespace pba
