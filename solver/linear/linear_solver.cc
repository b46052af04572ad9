#include "linear/linear_solver.h"

#include "core/format.h"

namespace pba {
namespace {

// Picks its backend by the size of the first system it is given.
class AutoSolver final : public LinearSolver {
 public:
  explicit AutoSolver(const LinearSolverOptions& options) : options_(options) {}

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    if (chosen_ == nullptr) {
      const LinearSolverSettings& s = options_.settings;
      direct_ = a.rows() <= s.auto_direct_max_unknowns;
      unknowns_ = a.rows();
      chosen_ = direct_ ? CreateCholmodSolver(options_.threads)
                        : CreateAmgSolver(s, options_.layout, options_.cancel);
    }
    return chosen_->Factorize(a);
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (chosen_ == nullptr) return Status::Internal("solve before any factorisation");
    return chosen_->Solve(b, x);
  }

  std::string Name() const override {
    if (chosen_ == nullptr) return "AUTO (no system solved)";
    return chosen_->Name() +
           Format(" [AUTO: %lld unknowns, %s linear_solver_options.auto_direct_max_unknowns = %d]",
                  static_cast<long long>(unknowns_), direct_ ? "at most" : "more than",
                  options_.settings.auto_direct_max_unknowns);
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<AutoSolver>(options_);
  }

 private:
  LinearSolverOptions options_;
  std::unique_ptr<LinearSolver> chosen_;
  Eigen::Index unknowns_ = 0;
  bool direct_ = true;
};

}  // namespace

const char* LinearSolverSettings::PreconditionerName() const {
  return preconditioner == Preconditioner::kBoomerAmg ? "hypre BoomerAMG"
                                                      : "GAMG smoothed aggregation";
}

const char* LinearSolverOptions::KindName() const {
  switch (kind) {
    case Kind::kCholmod:
      return "CHOLMOD";
    case Kind::kEigenLdlt:
      return "EIGEN_LDLT";
    case Kind::kPcg:
      return "PCG";
    case Kind::kAmg:
      return "AMG";
    case Kind::kMumps:
      return "MUMPS";
    case Kind::kAuto:
      break;
  }
  return "AUTO";
}

std::unique_ptr<LinearSolver> CreateAutoSolver(const LinearSolverOptions& options) {
  return std::make_unique<AutoSolver>(options);
}

std::unique_ptr<LinearSolver> CreateLinearSolver(const LinearSolverOptions& options) {
  switch (options.kind) {
    case LinearSolverOptions::Kind::kCholmod:
      return CreateCholmodSolver(options.threads);
    case LinearSolverOptions::Kind::kEigenLdlt:
      return CreateEigenLdltSolver();
    case LinearSolverOptions::Kind::kPcg:
      return CreatePcgSolver(options.cancel);
    case LinearSolverOptions::Kind::kAmg:
      return CreateAmgSolver(options.settings, options.layout, options.cancel);
    case LinearSolverOptions::Kind::kMumps:
      return CreateMumpsSolver();
    case LinearSolverOptions::Kind::kAuto:
      break;
  }
  return CreateAutoSolver(options);
}

}  // namespace pba
