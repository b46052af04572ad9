#include "linear/linear_solver.h"

namespace pba {

std::unique_ptr<LinearSolver> CreateLinearSolver(AnalysisSpec::LinearSolver kind) {
  switch (kind) {
    case AnalysisSpec::LinearSolver::kEigenLdlt:
      return CreateEigenLdltSolver();
    case AnalysisSpec::LinearSolver::kPcg:
      return CreatePcgSolver();
    case AnalysisSpec::LinearSolver::kCholmod:
      break;
  }
  return CreateCholmodSolver();
}

}  // namespace pba
