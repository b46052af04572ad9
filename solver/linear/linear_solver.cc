#include "linear/linear_solver.h"

#include <cmath>

#include "core/format.h"
#include "linear/petsc_runtime.h"

namespace pba {
namespace {

// Picks its backend by the size of the first system it is given.
class AutoSolver final : public LinearSolver {
 public:
  explicit AutoSolver(const LinearSolverOptions& options) : options_(options) {}

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    if (chosen_ == nullptr) PBA_RETURN_IF_ERROR(Choose(a));
    return chosen_->Factorize(a);
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (chosen_ == nullptr) return Status::Internal("solve before any factorisation");
    return chosen_->Solve(b, x);
  }

  bool Iterative() const override { return chosen_ != nullptr && chosen_->Iterative(); }
  // Whole matrices until it has chosen (CHOLMOD's analysis reads them).
  const std::vector<char>* OwnNodes() const override {
    return chosen_ != nullptr ? chosen_->OwnNodes() : nullptr;
  }
  // Before the choice: whether the AMG it may choose would use the split.
  bool WantsVolumetricSplit() const override {
    if (chosen_ != nullptr) return chosen_->WantsVolumetricSplit();
    return options_.settings.preconditioner == LinearSolverSettings::Preconditioner::kPressureSchur;
  }
  Status FactorizeSplit(const Eigen::SparseMatrix<double>& a,
                        const VolumetricSplit& split) override {
    if (chosen_ == nullptr) PBA_RETURN_IF_ERROR(Choose(a));
    return chosen_->FactorizeSplit(a, split);
  }
  std::string Name() const override {
    if (chosen_ == nullptr) return "AUTO (chosen at the first factorisation)";
    return chosen_->Name() + " [AUTO: " + reason_ + "]";
  }

  // A second solver for the same systems (Newton's) takes the same choice
  // without a second analysis.
  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    auto other = std::make_unique<AutoSolver>(options_);
    if (chosen_ != nullptr) {
      other->chosen_ = chosen_->NewOfSameKind();
      other->reason_ = reason_;
    }
    return other;
  }

 private:
  // CHOLMOD while its predicted factor fits the budget, else AMG. As the
  // ranks of an MPI job, MUMPS in CHOLMOD's place: CHOLMOD is one process's,
  // MUMPS factorises across the ranks (its factor is of the same order).
  Status Choose(const Eigen::SparseMatrix<double>& a) {
    std::string budget_source;
    const double budget_mb = Budget(&budget_source);
    FactorPrediction prediction;
    PBA_RETURN_IF_ERROR(PredictCholmodFactor(a, options_.threads, &prediction));
    const double factor_mb = prediction.bytes / (1024.0 * 1024.0);
    const bool direct = factor_mb <= budget_mb;
    reason_ = Format("%lld unknowns, predicted Cholesky factor %.0f MB %s %.0f MB (%s)",
                     static_cast<long long>(a.rows()), factor_mb, direct ? "<=" : ">", budget_mb,
                     budget_source.c_str());
    const bool ranks = CurrentRanks().size > 1;
    if (direct) {
      chosen_ = ranks ? CreateMumpsSolver(options_.layout) : CreateCholmodSolver(options_.threads);
    } else {
      chosen_ = CreateAmgSolver(options_.settings, options_.layout, options_.cancel);
    }
    return Status::Ok();
  }

  // The largest factor CHOLMOD is given [MB]: the scene's, else a quarter
  // of the memory the solve may take (Newton holds two factorisations, and
  // the mesh, the tangent and the solver's work need the rest).
  double Budget(std::string* source) const {
    const int set = options_.settings.auto_direct_max_factor_mb;
    if (set > 0) {
      *source = "linear_solver_options.auto_direct_max_factor_mb";
      return set;
    }
    const double memory = SolveMemoryBytes();
    if (!(memory > 0)) {
      *source = "the machine's memory could not be read";
      return LinearSolverSettings::kFallbackDirectFactorMb;
    }
    *source = Format("a quarter of the %.1f GiB the solve may take", memory / (1 << 30));
    return memory / 4 / (1024.0 * 1024.0);
  }

  LinearSolverOptions options_;
  std::unique_ptr<LinearSolver> chosen_;
  std::string reason_;
};

}  // namespace

Status CheckPositiveDiagonal(const Eigen::SparseMatrix<double>& a) {
  const Eigen::VectorXd diagonal = a.diagonal();
  for (Eigen::Index i = 0; i < diagonal.size(); ++i) {
    if (!(diagonal(i) > 0) || !std::isfinite(diagonal(i))) {
      return Status::Numerical(
          Format("the stiffness matrix is not positive definite (diagonal entry %lld is %.3g): "
                 "a body not held against rigid motion, or a degenerate mesh",
                 static_cast<long long>(i), diagonal(i)));
    }
  }
  return Status::Ok();
}

const char* LinearSolverSettings::PreconditionerName() const {
  switch (preconditioner) {
    case Preconditioner::kBoomerAmg:
      return "hypre BoomerAMG";
    case Preconditioner::kPressureSchur:
      return "a displacement-pressure Schur field split (GAMG on the displacements)";
    case Preconditioner::kGamg:
      break;
  }
  return "GAMG smoothed aggregation";
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
      return CreateMumpsSolver(options.layout);
    case LinearSolverOptions::Kind::kAuto:
      break;
  }
  return CreateAutoSolver(options);
}

}  // namespace pba
