// The PRESSURE_SCHUR solver (linear/linear_solver.h): a tangent given with
// its volume constraints apart (VolumetricSplit) is solved in its
// displacement-pressure form by flexible GMRES with PETSc's Schur field
// split; one given without them goes to GAMG.
//
// The mixed system is scaled so that its residual bounds the condensed
// one. With S = diag(s), s = beta weight and beta >= ||b||_2, the unknowns
// (u, q = S^-1 p) solve
//
//   [ A      b^T S        ] [u]   [r]
//   [ S b   -S diag(1/w) S ] [q] = [0],
//
// still symmetric, and for any (u, q) the condensed residual
// r - K u = r_u - b^T w r_p is at most ||r_u|| + ||S r_p|| <= sqrt(2) times
// the mixed one (r_p = b u - p / w, the second row's residual before S).
// The Schur complement of the scaled system is S (-1/w - b A^-1 b^T) S,
// preconditioned by its diagonal -s^2 (1/w + V / ((1 + gamma) mu)): the
// pressure mass matrix over the shear modulus stands for b A^-1 b^T,
// spectrally equivalent to it for an inf-sup stable pair once A holds a
// share gamma mu / V of each constraint's stiffness (Elman, Silvester &
// Wathen, Finite Elements and Fast Iterative Solvers, 2nd ed., 2014,
// chapter 9; the augmentation: Benzi & Olshanskii, SIAM J. Sci. Comput.
// 28:2095, 2006). The preconditioner is the upper block-triangular factor
// [A (S b)^T; 0 S_hat]: one V-cycle per iteration, where the full
// factorisation takes two (it took as many iterations on the pressed cube
// when both were tried; no script reruns that comparison).
#include <petscksp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_matrix.h"
#include "linear/petsc_runtime.h"

namespace pba {
namespace {

using petsc_detail::CancellableTest;
using petsc_detail::ConfigureMumps;
using petsc_detail::Digest;
using petsc_detail::ExpandedSolve;
using petsc_detail::FactorizeMumps;
using petsc_detail::OnRanks;
using petsc_detail::PetscMatrix;
using petsc_detail::PetscObjects;
using petsc_detail::SetRigidBodyNearNullSpace;
using petsc_detail::SolveCounts;
using petsc_detail::SolverComm;

// A in the preconditioner is one GAMG V-cycle. The alternatives were tried
// on the pressed cube while this was built (the switches were not kept, so
// no script reruns them): inner conjugate gradients to 1e-2 took fewer
// outer iterations but more time, and broke down (not a number) where a
// state far from equilibrium makes A indefinite; inner GMRES ran to its
// limit there.
//
// A solve stops as not converged at settings.max_iterations, or sooner at
// kStallFactor times the iterations of the last converged solve (at least
// kStallFloor): far from equilibrium the pressures' initial stress can make
// A indefinite, FGMRES then stalls, and Newton's substitute tangent (or
// MUMPS, for a small system) serves sooner than the full limit would.
constexpr int kStallFactor = 3;
constexpr int kStallFloor = 100;

// FGMRES keeps two vectors per iteration of a cycle; 50 bounds that memory
// at about 100 copies of the unknowns.
constexpr PetscInt kRestart = 50;

// A = K - b^T diag(weight) b, on K's pattern (the constraints' terms are
// element blocks, so inside it). False when an entry is missing from it.
bool DisplacementBlock(const Eigen::SparseMatrix<double>& k, const VolumetricSplit& split,
                       const Eigen::VectorXd& weight, Eigen::SparseMatrix<double>* a) {
  *a = k;
  const int* outer = a->outerIndexPtr();
  const int* inner = a->innerIndexPtr();
  double* values = a->valuePtr();
  for (Eigen::Index e = 0; e < split.b.rows(); ++e) {
    const double w = weight(e);
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator col(split.b, e); col; ++col) {
      const int* begin = inner + outer[col.index()];
      const int* end = inner + outer[col.index() + 1];
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator row(split.b, e); row;
           ++row) {
        const int* at = std::lower_bound(begin, end, static_cast<int>(row.index()));
        if (at == end || *at != row.index()) return false;
        values[at - inner] -= w * row.value() * col.value();
      }
    }
  }
  return true;
}

// What the mixed form needs of `split`, checked against K: sizes, and
// finite positive weights, volumes and moduli (U'' > 0: a material whose
// volumetric energy is convex there).
Status CheckSplit(const Eigen::SparseMatrix<double>& k, const VolumetricSplit& split) {
  const Eigen::Index n = split.b.rows();
  if (split.b.cols() != k.rows() || split.weight.size() != n || split.volume.size() != n ||
      split.shear_modulus.size() != n) {
    return Status::Internal("PRESSURE_SCHUR: the volume constraints do not match the tangent");
  }
  for (Eigen::Index e = 0; e < n; ++e) {
    if (!(split.weight(e) > 0) || !std::isfinite(split.weight(e)) || !(split.volume(e) > 0) ||
        !std::isfinite(split.volume(e)) || !(split.shear_modulus(e) > 0) ||
        !std::isfinite(split.shear_modulus(e))) {
      return Status::Numerical(Format(
          "PRESSURE_SCHUR: volume constraint %lld has weight U''/V = %.3g, volume %.3g and "
          "shear modulus %.3g; the mixed form needs all three positive and finite",
          static_cast<long long>(e), split.weight(e), split.volume(e), split.shear_modulus(e)));
    }
  }
  if (!std::isfinite(split.b.norm())) {
    return Status::Numerical("PRESSURE_SCHUR: a volume gradient is not finite");
  }
  return Status::Ok();
}

// The share of each constraint's stiffness kept in A: gamma mu / V, with
// gamma = min(kGradDiv, half of U'' / mu). The isochoric stiffness alone
// does not control the divergence (a nearly dilational field strains it
// little), so b A^-1 b^T would have eigenvalues far above V / mu and the
// Schur complement's diagonal would not stand for it; with gamma mu / V in
// A ("grad-div" augmentation) it does, while A stays a moderately
// compressible elasticity (K / mu about gamma) that GAMG solves well.
// 0, 1, 10 and 100 were tried on the pressed cube while this was built (no
// script reruns them): the iterations fell up to 10, and 100 slowed the
// multigrid on A.
constexpr double kGradDiv = 10;

// The weights left to the pressures (w - gamma mu / V) and gamma.
void SplitWeights(const VolumetricSplit& split, Eigen::VectorXd* weight, Eigen::VectorXd* gamma) {
  weight->resize(split.weight.size());
  gamma->resize(split.weight.size());
  for (Eigen::Index e = 0; e < weight->size(); ++e) {
    const double shear = split.shear_modulus(e) / split.volume(e);  // mu / V
    (*gamma)(e) = std::min(kGradDiv, 0.5 * split.weight(e) / shear);
    (*weight)(e) = split.weight(e) - (*gamma)(e)*shear;
  }
}

// An upper bound of ||b||_2: sqrt(||b||_1 ||b||_inf).
double SpectralBound(const Eigen::SparseMatrix<double, Eigen::RowMajor>& b) {
  Eigen::VectorXd column_sums = Eigen::VectorXd::Zero(b.cols());
  double row_max = 0;
  for (Eigen::Index e = 0; e < b.rows(); ++e) {
    double row = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(b, e); it; ++it) {
      row += std::abs(it.value());
      column_sums(it.index()) += std::abs(it.value());
    }
    row_max = std::max(row_max, row);
  }
  const double bound = std::sqrt(row_max * (b.cols() > 0 ? column_sums.maxCoeff() : 0.0));
  return bound > 0 ? bound : 1.0;
}

// The PETSc objects of the mixed form (besides A, which PetscMatrix holds).
struct MixedObjects {
  Mat b = nullptr, bt = nullptr, c = nullptr, schur = nullptr, nest = nullptr;
  Vec x = nullptr, rhs = nullptr;
  Vec pressure = nullptr;  // scratch, the pressures' layout
  KSP ksp = nullptr;
  // The fallback: K itself, factorised by MUMPS.
  Mat k = nullptr;
  KSP direct = nullptr;

  void Destroy() {
    DestroySolver();
    for (Mat* m : {&b, &bt, &c, &schur}) {
      if (*m != nullptr) MatDestroy(m);
    }
  }
  void DestroySolver() {
    DestroyFallback();
    if (ksp != nullptr) KSPDestroy(&ksp);
    for (Vec* v : {&x, &rhs, &pressure}) {
      if (*v != nullptr) VecDestroy(v);
    }
    if (nest != nullptr) MatDestroy(&nest);
  }
  void DestroyFallback() {
    if (direct != nullptr) KSPDestroy(&direct);
    if (k != nullptr) MatDestroy(&k);
  }
};

class PressureSchurSolver final : public LinearSolver {
 public:
  PressureSchurSolver(const LinearSolverSettings& settings, const UnknownLayout* layout,
                      const std::atomic<bool>* cancel)
      : settings_(settings), layout_(layout), cancel_(cancel), test_(cancel) {}
  ~PressureSchurSolver() override {
    const auto lock = PetscLock();
    mixed_.Destroy();
    objects_.Destroy();
  }

  bool WantsVolumetricSplit() const override { return true; }
  bool Iterative() const override { return true; }

  // Without constraints: GAMG.
  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    mixed_active_ = false;
    factorized_ = false;
    if (plain_ == nullptr) {
      LinearSolverSettings gamg = settings_;
      gamg.preconditioner = LinearSolverSettings::Preconditioner::kGamg;
      plain_ = CreateAmgSolver(gamg, layout_, cancel_);
    }
    PBA_RETURN_IF_ERROR(plain_->Factorize(a));
    factorized_ = true;
    return Status::Ok();
  }

  Status FactorizeSplit(const Eigen::SparseMatrix<double>& k,
                        const VolumetricSplit& split) override {
    if (split.empty()) return Factorize(k);
    PBA_RETURN_IF_ERROR(InitializePetsc());
    mixed_active_ = false;
    factorized_ = false;
    PBA_RETURN_IF_ERROR(CheckPositiveDiagonal(k));
    PBA_RETURN_IF_ERROR(CheckSplit(k, split));
    unknowns_ = k.rows();
    Eigen::SparseMatrix<double> a;
    Eigen::VectorXd weight, gamma;
    SplitWeights(split, &weight, &gamma);
    if (!DisplacementBlock(k, split, weight, &a)) {
      return Status::Internal("PRESSURE_SCHUR: a volume constraint couples unknowns K does not");
    }
    const auto lock = PetscLock();
    bool rebuilt = false;
    PBA_RETURN_IF_ERROR(matrix_.Load(a, layout_, &objects_, &rebuilt));
    a = Eigen::SparseMatrix<double>();
    if (rebuilt) {
      PBA_RETURN_IF_ERROR(objects_.NewSolver());  // A's vectors, for the fallback's solve
      if (layout_ != nullptr) {
        PBA_RETURN_IF_ERROR(SetRigidBodyNearNullSpace(matrix_, *layout_, objects_.matrix));
      }
    }
    PBA_RETURN_IF_ERROR(LoadConstraints(split, weight, gamma, rebuilt || !SameConstraints(split)));
    // A new KSP for every tangent: set up again in place, GAMG would keep
    // parts of the hierarchy of a matrix far from this one (as AMG's
    // rebuild notes).
    PBA_RETURN_IF_ERROR(BuildKsp());
    PBA_RETURN_IF_ERROR(SetUp());
    mixed_active_ = true;
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& r, Eigen::VectorXd* x) override {
    if (!factorized_)
      return Status::Internal("PRESSURE_SCHUR solve without a successful Factorize");
    if (!mixed_active_) return plain_->Solve(r, x);
    int iterations = 0;
    double residual = INFINITY;
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    {
      const auto lock = PetscLock();
      PBA_RETURN_IF_ERROR(Iterate(r, x, &reason, &iterations, &residual));
    }
    if (test_.cancelled()) {
      return Status::Cancelled(Format("cancelled during FGMRES (iteration %d)", iterations));
    }
    counts_.Record(iterations, residual);
    if (reason > 0 && residual <= 10 * settings_.relative_tolerance) {
      converged_iterations_ = iterations;
      return Status::Ok();
    }
    return Fallback(r, x,
                    Format("FGMRES with %s did not converge: %d iterations reached a "
                           "relative residual of %.3g (target %.1e, %s)",
                           settings_.PreconditionerName(), iterations, residual,
                           settings_.relative_tolerance, KSPConvergedReasons[reason]));
  }

  std::string Name() const override {
    std::string name =
        Format("FGMRES with %s (PETSc%s), relative tolerance %.0e", settings_.PreconditionerName(),
               OnRanks().c_str(), settings_.relative_tolerance);
    if (counts_.solves > 0) {
      name += Format(
          " (%d solves, %d-%d iterations; last: %d iterations, relative residual %.1e, %lld "
          "pressures",
          counts_.solves, counts_.min_iterations, counts_.max_iterations, counts_.last_iterations,
          counts_.last_residual, static_cast<long long>(pressures_));
      if (fallbacks_ > 0) name += Format("; %d redone by MUMPS", fallbacks_);
      name += ")";
    }
    if (plain_ != nullptr) {
      name += "; tangents without volume constraints: " + plain_->Name();
    }
    return name;
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<PressureSchurSolver>(settings_, layout_, cancel_);
  }

 private:
  bool SameConstraints(const VolumetricSplit& split) const {
    return mixed_.b != nullptr && split.b.rows() == pressures_ &&
           static_cast<std::size_t>(split.b.nonZeros()) == pattern_.size() &&
           std::equal(pattern_.begin(), pattern_.end(), split.b.innerIndexPtr()) &&
           std::equal(row_start_.begin(), row_start_.end(), split.b.outerIndexPtr());
  }

  // The scaled S b, -S diag(1/w) S and the Schur complement's diagonal:
  // this rank's share of the pressures (an even split in constraint order),
  // columns at A's expanded positions.
  Status LoadConstraints(const VolumetricSplit& split, const Eigen::VectorXd& weight,
                         const Eigen::VectorXd& gamma, bool new_pattern) {
    if (CurrentRanks().size > 1) {
      Digest digest;
      digest.Add(split.b.valuePtr(), sizeof(double) * split.b.nonZeros());
      digest.Add(weight.data(), sizeof(double) * weight.size());
      PBA_RETURN_IF_ERROR(digest.CheckSameOnEveryRank("volume constraints"));
    }
    const double beta = SpectralBound(split.b);
    if (new_pattern) {
      mixed_.Destroy();
      pressures_ = split.b.rows();
      pattern_.assign(split.b.innerIndexPtr(), split.b.innerIndexPtr() + split.b.nonZeros());
      row_start_.assign(split.b.outerIndexPtr(), split.b.outerIndexPtr() + pressures_ + 1);
      const ProcessRanks ranks = CurrentRanks();
      first_pressure_ = pressures_ * ranks.rank / ranks.size;
      last_pressure_ = pressures_ * (ranks.rank + 1) / ranks.size;
      const PetscInt local = last_pressure_ - first_pressure_;
      const PetscInt local_u = matrix_.last_row() - matrix_.first_row();
      PetscInt width = 0;
      for (Eigen::Index e = 0; e < pressures_; ++e) {
        width = std::max<PetscInt>(width, row_start_[e + 1] - row_start_[e]);
      }
      PBA_PETSC(MatCreateAIJ(SolverComm(), local, local_u, PETSC_DETERMINE, PETSC_DETERMINE, width,
                             nullptr, width, nullptr, &mixed_.b));
      for (Mat* m : {&mixed_.c, &mixed_.schur}) {
        PBA_PETSC(MatCreateAIJ(SolverComm(), local, local, PETSC_DETERMINE, PETSC_DETERMINE, 1,
                               nullptr, 0, nullptr, m));
      }
    }
    std::vector<PetscInt> columns;
    std::vector<PetscScalar> values;
    for (PetscInt e = first_pressure_; e < last_pressure_; ++e) {
      const double w = weight(e), s = beta * w;
      columns.clear();
      values.clear();
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(split.b, e); it; ++it) {
        columns.push_back(matrix_.Position(it.index()));
        values.push_back(s * it.value());
      }
      PBA_PETSC(MatSetValues(mixed_.b, 1, &e, static_cast<PetscInt>(columns.size()), columns.data(),
                             values.data(), INSERT_VALUES));
      const PetscScalar c = -s * s / w;
      const PetscScalar schur = -s * s * (1 / w + split.volume(e) / split.shear_modulus(e));
      PBA_PETSC(MatSetValues(mixed_.c, 1, &e, 1, &e, &c, INSERT_VALUES));
      PBA_PETSC(MatSetValues(mixed_.schur, 1, &e, 1, &e, &schur, INSERT_VALUES));
    }
    for (Mat m : {mixed_.b, mixed_.c, mixed_.schur}) {
      PBA_PETSC(MatAssemblyBegin(m, MAT_FINAL_ASSEMBLY));
      PBA_PETSC(MatAssemblyEnd(m, MAT_FINAL_ASSEMBLY));
    }
    PBA_PETSC(
        MatTranspose(mixed_.b, new_pattern ? MAT_INITIAL_MATRIX : MAT_REUSE_MATRIX, &mixed_.bt));
    // The weights, for the condensed residual: w / s^2 per pressure.
    weight_over_s2_.resize(last_pressure_ - first_pressure_);
    for (PetscInt e = first_pressure_; e < last_pressure_; ++e) {
      weight_over_s2_[e - first_pressure_] = 1 / (beta * beta * weight(e));
    }
    return Status::Ok();
  }

  // The nest [A, (S b)^T; S b, C], its vectors, and FGMRES with the split.
  Status BuildKsp() {
    mixed_.DestroySolver();
    Mat blocks[4] = {objects_.matrix, mixed_.bt, mixed_.b, mixed_.c};
    PBA_PETSC(MatCreateNest(SolverComm(), 2, nullptr, 2, nullptr, blocks, &mixed_.nest));
    PBA_PETSC(MatCreateVecs(mixed_.nest, &mixed_.x, &mixed_.rhs));
    PBA_PETSC(MatCreateVecs(mixed_.c, &mixed_.pressure, nullptr));
    PBA_PETSC(KSPCreate(SolverComm(), &mixed_.ksp));
    PBA_PETSC(KSPSetOperators(mixed_.ksp, mixed_.nest, mixed_.nest));
    PBA_PETSC(KSPSetType(mixed_.ksp, KSPFGMRES));
    PBA_PETSC(KSPGMRESSetRestart(mixed_.ksp, kRestart));
    // The mixed residual bounds the condensed one within sqrt(2).
    int limit = settings_.max_iterations;
    if (converged_iterations_ > 0) {
      limit = std::min(limit, std::max(kStallFloor, kStallFactor * converged_iterations_));
    }
    PBA_PETSC(KSPSetTolerances(mixed_.ksp, settings_.relative_tolerance / std::sqrt(2.0), 0.0,
                               PETSC_DEFAULT, limit));
    PBA_PETSC(KSPSetErrorIfNotConverged(mixed_.ksp, PETSC_FALSE));
    PBA_RETURN_IF_ERROR(test_.Install(mixed_.ksp));
    // The blocks' solvers read their settings from the options database:
    // this solver's, under its own prefix (given before the fields, whose
    // solvers take it when made), set from the scene only and cleared
    // after the set-up.
    prefix_ = Format("pba_schur_%p_", static_cast<void*>(this));
    PBA_PETSC(KSPSetOptionsPrefix(mixed_.ksp, prefix_.c_str()));
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(mixed_.ksp, &pc));
    PBA_PETSC(PCSetType(pc, PCFIELDSPLIT));
    IS fields[2] = {nullptr, nullptr};
    PBA_PETSC(MatNestGetISs(mixed_.nest, fields, nullptr));
    PBA_PETSC(PCFieldSplitSetIS(pc, "u", fields[0]));
    PBA_PETSC(PCFieldSplitSetIS(pc, "p", fields[1]));
    PBA_PETSC(PCFieldSplitSetType(pc, PC_COMPOSITE_SCHUR));
    PBA_PETSC(PCFieldSplitSetSchurFactType(pc, PC_FIELDSPLIT_SCHUR_FACT_UPPER));
    PBA_PETSC(PCFieldSplitSetSchurPre(pc, PC_FIELDSPLIT_SCHUR_PRE_USER, mixed_.schur));
    return Status::Ok();
  }

  // Builds the split's solvers for the current values: one GAMG V-cycle
  // for A, the diagonal for the Schur complement.
  Status SetUp() {
    const std::string threshold = Format("%.17g", settings_.gamg_threshold);
    const std::pair<const char*, std::string> options[] = {
        {"fieldsplit_u_ksp_type", "preonly"}, {"fieldsplit_u_pc_type", "gamg"},
        {"fieldsplit_u_pc_gamg_type", "agg"}, {"fieldsplit_u_pc_gamg_threshold", threshold},
        {"fieldsplit_p_ksp_type", "preonly"}, {"fieldsplit_p_pc_type", "jacobi"},
    };
    for (const auto& [key, value] : options) {
      PBA_PETSC(PetscOptionsSetValue(nullptr, ("-" + prefix_ + key).c_str(), value.c_str()));
    }
    PetscErrorCode code = KSPSetFromOptions(mixed_.ksp);
    if (code == 0) code = KSPSetOperators(mixed_.ksp, mixed_.nest, mixed_.nest);
    if (code == 0) code = KSPSetUp(mixed_.ksp);
    for (const auto& [key, value] : options) {
      PetscOptionsClearValue(nullptr, ("-" + prefix_ + key).c_str());
    }
    PBA_PETSC(code);
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(mixed_.ksp, &pc));
    PCFailedReason failed = PC_NOERROR;
    PBA_PETSC(PCGetFailedReason(pc, &failed));
    if (failed != PC_NOERROR) {
      return Status::Numerical(Format("the field-split preconditioner could not be built (%s)",
                                      PCFailedReasons[failed]));
    }
    return Status::Ok();
  }

  // One FGMRES solve of the mixed system for right-hand side r: u into *x,
  // the reason, the iterations and the condensed relative residual
  // ||r - K u|| / ||r||.
  Status Iterate(const Eigen::VectorXd& r, Eigen::VectorXd* x, KSPConvergedReason* reason,
                 int* iterations, double* residual) {
    test_.Reset();
    if (CurrentRanks().size > 1) {
      Digest digest;
      digest.Add(r.data(), sizeof(double) * r.size());
      PBA_RETURN_IF_ERROR(digest.CheckSameOnEveryRank("right-hand sides"));
    }
    IS fields[2] = {nullptr, nullptr};
    PBA_PETSC(MatNestGetISs(mixed_.nest, fields, nullptr));
    PBA_PETSC(VecSet(mixed_.rhs, 0.0));
    Vec ru = nullptr;
    PBA_PETSC(VecGetSubVector(mixed_.rhs, fields[0], &ru));
    PetscScalar* values = nullptr;
    PetscErrorCode code = VecGetArray(ru, &values);
    if (code == 0) {
      for (PetscInt row = matrix_.first_row(); row < matrix_.last_row(); ++row) {
        const Eigen::Index i = matrix_.UnknownAt(row);
        values[row - matrix_.first_row()] = i >= 0 ? r(i) : 0.0;
      }
      code = VecRestoreArray(ru, &values);
    }
    const PetscErrorCode restored = VecRestoreSubVector(mixed_.rhs, fields[0], &ru);
    PBA_PETSC(code);
    PBA_PETSC(restored);
    PBA_PETSC(VecSet(mixed_.x, 0.0));
    PBA_PETSC(KSPSolve(mixed_.ksp, mixed_.rhs, mixed_.x));
    PetscInt its = 0;
    PBA_PETSC(KSPGetIterationNumber(mixed_.ksp, &its));
    *iterations = static_cast<int>(its);
    PBA_PETSC(KSPGetConvergedReason(mixed_.ksp, reason));
    Vec xu = nullptr;
    PBA_PETSC(VecGetSubVector(mixed_.rhs, fields[0], &ru));
    code = VecGetSubVector(mixed_.x, fields[0], &xu);
    Status status = code == 0 ? CondensedResidual(ru, xu, residual) : Status::Ok();
    if (code == 0 && status.ok()) status = Gather(xu, r.size(), x);
    if (xu != nullptr) VecRestoreSubVector(mixed_.x, fields[0], &xu);
    VecRestoreSubVector(mixed_.rhs, fields[0], &ru);
    PBA_PETSC(code);
    PBA_RETURN_IF_ERROR(status);
    if (!x->allFinite()) *residual = INFINITY;
    return Status::Ok();
  }

  // ||r - A u - b^T w b u|| / ||r|| on the expanded displacements:
  // b^T w b u = (S b)^T (w / s^2) (S b u).
  Status CondensedResidual(Vec r, Vec u, double* residual) {
    Vec t = nullptr;
    PBA_PETSC(VecDuplicate(r, &t));
    PetscErrorCode code = MatMult(mixed_.b, u, mixed_.pressure);
    PetscScalar* p = nullptr;
    if (code == 0) code = VecGetArray(mixed_.pressure, &p);
    if (code == 0) {
      for (std::size_t e = 0; e < weight_over_s2_.size(); ++e) p[e] *= weight_over_s2_[e];
      code = VecRestoreArray(mixed_.pressure, &p);
    }
    if (code == 0) code = MatMult(mixed_.bt, mixed_.pressure, t);
    if (code == 0) code = MatMultAdd(objects_.matrix, u, t, t);
    if (code == 0) code = VecAYPX(t, -1.0, r);
    PetscReal t_norm = 0, r_norm = 0;
    if (code == 0) code = VecNorm(t, NORM_2, &t_norm);
    if (code == 0) code = VecNorm(r, NORM_2, &r_norm);
    VecDestroy(&t);
    PBA_PETSC(code);
    *residual = t_norm / (r_norm > 0 ? r_norm : 1.0);
    if (!std::isfinite(*residual)) *residual = INFINITY;
    return Status::Ok();
  }

  // The whole displacement vector on every rank, in the caller's order.
  Status Gather(Vec u, Eigen::Index size, Eigen::VectorXd* x) {
    Vec whole = u;
    VecScatter gather = nullptr;
    if (CurrentRanks().size > 1) {
      PBA_PETSC(VecScatterCreateToAll(u, &gather, &whole));
      PetscErrorCode code = VecScatterBegin(gather, u, whole, INSERT_VALUES, SCATTER_FORWARD);
      if (code == 0) code = VecScatterEnd(gather, u, whole, INSERT_VALUES, SCATTER_FORWARD);
      if (code != 0) {
        VecScatterDestroy(&gather);
        VecDestroy(&whole);
        PBA_PETSC(code);
      }
    }
    const PetscScalar* values = nullptr;
    PetscErrorCode code = VecGetArrayRead(whole, &values);
    if (code == 0) {
      x->resize(size);
      for (Eigen::Index i = 0; i < size; ++i) (*x)(i) = values[matrix_.Position(i)];
      code = VecRestoreArrayRead(whole, &values);
    }
    if (gather != nullptr) {
      VecScatterDestroy(&gather);
      VecDestroy(&whole);
    }
    PBA_PETSC(code);
    return Status::Ok();
  }

  // The solve that did not converge, redone by MUMPS on K = A + b^T w b
  // when the system is small enough; else `failure` with the reason.
  Status Fallback(const Eigen::VectorXd& r, Eigen::VectorXd* x, const std::string& failure) {
    if (unknowns_ > settings_.fallback_direct_max_unknowns) {
      return Status::Numerical(
          failure + Format("; the system (%lld unknowns) is above "
                           "linear_solver_options.fallback_direct_max_unknowns (%d), so it is "
                           "not redone by MUMPS",
                           static_cast<long long>(unknowns_),
                           settings_.fallback_direct_max_unknowns));
    }
    const auto lock = PetscLock();
    if (mixed_.direct == nullptr) {
      // K = A + (S b)^T diag(w / s^2) (S b).
      Mat scaled = nullptr;
      PBA_PETSC(MatDuplicate(mixed_.b, MAT_COPY_VALUES, &scaled));
      Vec d = nullptr;
      PetscErrorCode code = VecDuplicate(mixed_.pressure, &d);
      PetscScalar* dv = nullptr;
      if (code == 0) code = VecGetArray(d, &dv);
      if (code == 0) {
        std::copy(weight_over_s2_.begin(), weight_over_s2_.end(), dv);
        code = VecRestoreArray(d, &dv);
      }
      if (code == 0) code = MatDiagonalScale(scaled, d, nullptr);
      Mat product = nullptr;
      if (code == 0) {
        code = MatTransposeMatMult(mixed_.b, scaled, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &product);
      }
      if (code == 0) code = MatDuplicate(objects_.matrix, MAT_COPY_VALUES, &mixed_.k);
      if (code == 0) code = MatAXPY(mixed_.k, 1.0, product, SUBSET_NONZERO_PATTERN);
      if (code == 0) code = MatSetOption(mixed_.k, MAT_SYMMETRIC, PETSC_TRUE);
      if (product != nullptr) MatDestroy(&product);
      if (d != nullptr) VecDestroy(&d);
      MatDestroy(&scaled);
      PBA_PETSC(code);
      PBA_PETSC(KSPCreate(SolverComm(), &mixed_.direct));
      PBA_RETURN_IF_ERROR(ConfigureMumps(mixed_.direct, mixed_.k));
      const Status factorized = FactorizeMumps(mixed_.direct, mixed_.k);
      if (!factorized.ok()) {
        mixed_.DestroyFallback();
        return Status::Numerical(failure + "; MUMPS, the fallback: " + factorized.message());
      }
    }
    ++fallbacks_;
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, mixed_.direct, &objects_, r, x));
    if (!x->allFinite()) return Status::Numerical("MUMPS's solve produced no finite answer");
    return Status::Ok();
  }

  LinearSolverSettings settings_;
  const UnknownLayout* layout_;      // not owned; may be null
  const std::atomic<bool>* cancel_;  // not owned; may be null
  CancellableTest test_;
  PetscMatrix matrix_;    // A, expanded to whole nodes
  PetscObjects objects_;  // A, and its vectors for the fallback's solve
  MixedObjects mixed_;
  std::unique_ptr<LinearSolver> plain_;  // GAMG, for tangents without constraints
  std::string prefix_;
  Eigen::Index unknowns_ = 0, pressures_ = 0;
  PetscInt first_pressure_ = 0, last_pressure_ = 0;
  std::vector<int> pattern_, row_start_;  // of the constraints loaded
  std::vector<double> weight_over_s2_;    // this rank's pressures
  bool factorized_ = false, mixed_active_ = false;
  SolveCounts counts_;
  int fallbacks_ = 0;
  int converged_iterations_ = 0;  // of the last converged solve (0: none yet)
};

}  // namespace

std::unique_ptr<LinearSolver> CreatePressureSchurSolver(const LinearSolverSettings& settings,
                                                        const UnknownLayout* layout,
                                                        const std::atomic<bool>* cancel) {
  return std::make_unique<PressureSchurSolver>(settings, layout, cancel);
}

}  // namespace pba
