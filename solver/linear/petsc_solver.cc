// The PETSc backends: conjugate gradients with algebraic multigrid (GAMG or
// hypre's BoomerAMG) for systems too large to factorise, and MUMPS, the
// multifrontal direct solver, for the fallback and for users who want it.
// In a process of its own they work on PETSC_COMM_SELF; as ranks of an MPI
// job (mpirun), every rank hands PETSc its share of the rows and all of
// them solve together (PetscMatrix). Every PETSc call holds PetscLock.
#include <petscksp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_runtime.h"

namespace pba {
namespace {

// The communicator the solvers work on: every rank of an MPI job (each
// holds the whole matrix and takes its share of the rows), else this
// process alone.
MPI_Comm SolverComm() { return CurrentRanks().size > 1 ? PETSC_COMM_WORLD : PETSC_COMM_SELF; }

// " on 2 MPI ranks", or nothing in a process of its own.
std::string OnRanks() {
  const int size = CurrentRanks().size;
  return size > 1 ? Format(" on %d MPI ranks", size) : std::string();
}

// Every rank of an MPI job runs the same solve and must hand the same
// system to each collective solve; a rank that built a different mesh or
// took another Newton path would otherwise make PETSc mix two problems. A
// digest of what this rank holds is compared across the ranks (a few
// passes over the values: small beside a factorisation or a multigrid
// setup); a difference is an error, never an answer.
class Digest {
 public:
  void Add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) hash_ = (hash_ ^ p[i]) * 1099511628211ULL;
  }
  template <typename T>
  void AddValue(T value) {
    Add(&value, sizeof value);
  }
  // Status::Internal naming `what` when the ranks' digests differ.
  Status CheckSameOnEveryRank(const char* what) const {
    if (CurrentRanks().size <= 1) return Status::Ok();
    std::uint64_t mine[2] = {hash_, ~hash_}, all[2] = {0, 0};
    if (MPI_Allreduce(mine, all, 2, MPI_UINT64_T, MPI_MAX, PETSC_COMM_WORLD) != MPI_SUCCESS) {
      return Status::Internal("the MPI ranks could not compare their systems");
    }
    // The largest hash and the largest complement agree only when every
    // rank's hash is the same.
    if (all[0] != hash_ || all[1] != ~hash_) {
      return Status::Internal(Format(
          "the MPI ranks hold different %s (rank %d differs): they built different meshes or "
          "took different paths, so the solve stops rather than mix them",
          what, CurrentRanks().rank));
    }
    return Status::Ok();
  }

 private:
  std::uint64_t hash_ = 14695981039346656037ULL;
};

// The PETSc objects of one solver, destroyed under the lock.
struct PetscObjects {
  Mat matrix = nullptr;
  KSP ksp = nullptr;
  Vec rhs = nullptr, solution = nullptr;
  // Across ranks: the whole solution on every rank.
  VecScatter gather = nullptr;
  Vec everything = nullptr;

  void Destroy() {
    if (matrix != nullptr) MatDestroy(&matrix);
    DestroySolver();
  }
  // A new KSP and vectors for `matrix` (a new pattern), the old ones gone.
  Status NewSolver() {
    DestroySolver();
    PBA_PETSC(MatCreateVecs(matrix, &solution, &rhs));
    if (CurrentRanks().size > 1) PBA_PETSC(VecScatterCreateToAll(solution, &gather, &everything));
    PBA_PETSC(KSPCreate(SolverComm(), &ksp));
    PBA_PETSC(KSPSetOperators(ksp, matrix, matrix));
    return Status::Ok();
  }

 private:
  void DestroySolver() {
    if (ksp != nullptr) KSPDestroy(&ksp);
    if (rhs != nullptr) VecDestroy(&rhs);
    if (solution != nullptr) VecDestroy(&solution);
    if (gather != nullptr) VecScatterDestroy(&gather);
    if (everything != nullptr) VecDestroy(&everything);
  }
};

// Recursive coordinate bisection: the nodes in `nodes` split into `parts`
// groups of (nearly) equal size, each compact in space, halving along the
// longest side of the group's bounding box. Appends the nodes to *order
// group by group and each group's size to *sizes. Ties in a coordinate are
// broken by the node number, so every rank finds the same order.
void BisectNodes(const std::vector<double>& coordinates, std::vector<int> nodes, int parts,
                 std::vector<int>* order, std::vector<PetscInt>* sizes) {
  if (parts <= 1 || nodes.size() <= 1) {
    order->insert(order->end(), nodes.begin(), nodes.end());
    sizes->push_back(static_cast<PetscInt>(nodes.size()));
    for (int p = 1; p < parts; ++p) sizes->push_back(0);
    return;
  }
  int axis = 0;
  double widest = -1;
  for (int d = 0; d < 3; ++d) {
    double low = INFINITY, high = -INFINITY;
    for (int n : nodes) {
      low = std::min(low, coordinates[3 * n + d]);
      high = std::max(high, coordinates[3 * n + d]);
    }
    if (high - low > widest) {
      widest = high - low;
      axis = d;
    }
  }
  const int first_parts = parts / 2;
  const auto cut = static_cast<std::ptrdiff_t>(nodes.size() * first_parts / parts);
  std::nth_element(nodes.begin(), nodes.begin() + cut, nodes.end(), [&](int a, int b) {
    const double ca = coordinates[3 * a + axis], cb = coordinates[3 * b + axis];
    return ca < cb || (ca == cb && a < b);
  });
  std::vector<int> upper(nodes.begin() + cut, nodes.end());
  nodes.resize(cut);
  BisectNodes(coordinates, std::move(nodes), first_parts, order, sizes);
  BisectNodes(coordinates, std::move(upper), parts - first_parts, order, sizes);
}

// A symmetric matrix handed over in Eigen's compressed column storage, kept
// as PETSc's row storage of the same matrix (symmetric: columns are rows),
// optionally expanded to every degree of freedom of the mesh's nodes so
// that each node's three unknowns form a block (prescribed ones get a
// diagonal entry of the matrix's scale and a zero right-hand side).
//
// Across the ranks of an MPI job every rank holds the whole matrix and
// hands PETSc its own rows: whole nodes, grouped by recursive coordinate
// bisection so that a rank's rows couple mostly to each other (without a
// layout, an even split of the unknowns in their order).
class PetscMatrix {
 public:
  // Builds `objects->matrix` for `a`'s pattern, or refills its values when
  // the pattern is the one it was built for; *rebuilt says which.
  Status Load(const Eigen::SparseMatrix<double>& a, const UnknownLayout* layout,
              PetscObjects* objects, bool* rebuilt) {
    if (!a.isCompressed()) return Status::Internal("PETSc solver given an uncompressed matrix");
    if (layout != nullptr && static_cast<Eigen::Index>(layout->dof_of_unknown.size()) != a.rows()) {
      return Status::Internal("unknown layout does not match the matrix size");
    }
    PBA_RETURN_IF_ERROR(CheckSameOnEveryRank(a));
    *rebuilt = objects->matrix == nullptr || !SamePattern(a) || layout != layout_;
    if (*rebuilt) {
      if (objects->matrix != nullptr) MatDestroy(&objects->matrix);
      // Recorded once the new matrix exists (below): a failure on the way
      // leaves no pattern that a later call would take for built.
      outer_.clear();
      inner_.clear();
      BuildPattern(a, layout);
    }
    FillValues(a);
    if (*rebuilt) {
      PBA_RETURN_IF_ERROR(Create(objects));
      outer_.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
      inner_.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
    } else if (CurrentRanks().size > 1) {
      // Each rank's own rows, in place (their pattern is PETSc's).
      for (PetscInt local = 0; local + 1 < static_cast<PetscInt>(row_start_.size()); ++local) {
        const PetscInt row = first_row_ + local;
        const PetscInt begin = row_start_[local];
        PBA_PETSC(MatSetValues(objects->matrix, 1, &row, row_start_[local + 1] - begin,
                               columns_.data() + begin, values_.data() + begin, INSERT_VALUES));
      }
      PBA_PETSC(MatAssemblyBegin(objects->matrix, MAT_FINAL_ASSEMBLY));
      PBA_PETSC(MatAssemblyEnd(objects->matrix, MAT_FINAL_ASSEMBLY));
    } else {
      // Same pattern, same order: PETSc's value array is overwritten (and
      // its state advanced, so the preconditioner sees a new matrix).
      PetscScalar* target = nullptr;
      PBA_PETSC(MatSeqAIJGetArray(objects->matrix, &target));
      std::copy(values_.begin(), values_.end(), target);
      PBA_PETSC(MatSeqAIJRestoreArray(objects->matrix, &target));
    }
    values_ = std::vector<PetscScalar>();  // PETSc holds its copy
    return Status::Ok();
  }

  // The expanded row of unknown i.
  PetscInt Position(Eigen::Index i) const {
    if (layout_ == nullptr) return static_cast<PetscInt>(i);
    const int dof = layout_->dof_of_unknown[i];
    return 3 * node_position_[dof / 3] + dof % 3;
  }
  // The unknown at expanded row `row`; -1 for a prescribed one.
  Eigen::Index UnknownAt(PetscInt row) const { return unknown_at_[row]; }
  // This rank's rows [first_row(), last_row()).
  PetscInt first_row() const { return first_row_; }
  PetscInt last_row() const { return last_row_; }
  // The mesh node at expanded row `row` (a layout's system only).
  int NodeAt(PetscInt row) const { return node_at_[row / 3]; }

 private:
  Status CheckSameOnEveryRank(const Eigen::SparseMatrix<double>& a) const {
    if (CurrentRanks().size <= 1) return Status::Ok();
    Digest digest;
    digest.AddValue(static_cast<std::int64_t>(a.rows()));
    digest.AddValue(static_cast<std::int64_t>(a.nonZeros()));
    digest.Add(a.outerIndexPtr(), sizeof(int) * (a.outerSize() + 1));
    digest.Add(a.innerIndexPtr(), sizeof(int) * a.nonZeros());
    digest.Add(a.valuePtr(), sizeof(double) * a.nonZeros());
    return digest.CheckSameOnEveryRank("stiffness matrices");
  }

  bool SamePattern(const Eigen::SparseMatrix<double>& a) const {
    return outer_.size() == static_cast<std::size_t>(a.outerSize()) + 1 &&
           inner_.size() == static_cast<std::size_t>(a.nonZeros()) &&
           std::equal(outer_.begin(), outer_.end(), a.outerIndexPtr()) &&
           std::equal(inner_.begin(), inner_.end(), a.innerIndexPtr());
  }

  // The rows' order and their owners: identity on one rank; across ranks,
  // whole nodes by coordinate bisection (or even shares of the unknowns).
  void Partition(Eigen::Index unknowns) {
    const ProcessRanks ranks = CurrentRanks();
    const PetscInt nodes = layout_ != nullptr ? layout_->num_nodes() : 0;
    std::vector<PetscInt> sizes;  // rows per rank
    node_at_.clear();
    if (layout_ != nullptr && ranks.size > 1) {
      std::vector<int> all(nodes);
      for (int n = 0; n < nodes; ++n) all[n] = n;
      BisectNodes(layout_->coordinates, std::move(all), ranks.size, &node_at_, &sizes);
      for (PetscInt& size : sizes) size *= 3;
    } else {
      if (layout_ != nullptr) {
        node_at_.resize(nodes);
        for (int n = 0; n < nodes; ++n) node_at_[n] = n;
      }
      const PetscInt rows = layout_ != nullptr ? 3 * nodes : static_cast<PetscInt>(unknowns);
      const PetscInt unit = layout_ != nullptr ? 3 : 1;
      const PetscInt units = rows / unit;
      for (int r = 0; r < ranks.size; ++r) {
        sizes.push_back(unit * (units / ranks.size + (r < units % ranks.size ? 1 : 0)));
      }
    }
    node_position_.assign(node_at_.size(), 0);
    for (std::size_t p = 0; p < node_at_.size(); ++p) node_position_[node_at_[p]] = p;
    rows_ = 0;
    for (int r = 0; r < ranks.size; ++r) {
      if (r == ranks.rank) first_row_ = rows_;
      rows_ += sizes[r];
      if (r == ranks.rank) last_row_ = rows_;
    }
  }

  // This rank's rows: their starts, sorted global columns, and where each
  // entry's value comes from in `a` (-1: a prescribed row's diagonal).
  void BuildPattern(const Eigen::SparseMatrix<double>& a, const UnknownLayout* layout) {
    layout_ = layout;
    Partition(a.rows());
    unknown_at_.assign(rows_, -1);
    for (Eigen::Index i = 0; i < a.rows(); ++i) unknown_at_[Position(i)] = i;
    row_start_.assign(1, 0);
    columns_.clear();
    source_.clear();
    std::vector<std::pair<PetscInt, int>> row;
    for (PetscInt r = first_row_; r < last_row_; ++r) {
      const Eigen::Index j = unknown_at_[r];
      if (j < 0) {
        columns_.push_back(r);
        source_.push_back(-1);
      } else {
        row.clear();
        for (int k = a.outerIndexPtr()[j]; k < a.outerIndexPtr()[j + 1]; ++k) {
          row.emplace_back(Position(a.innerIndexPtr()[k]), k);
        }
        // Positions follow the unknowns on one rank; a bisection reorders.
        std::sort(row.begin(), row.end());
        for (const auto& [column, k] : row) {
          columns_.push_back(column);
          source_.push_back(k);
        }
      }
      row_start_.push_back(static_cast<PetscInt>(columns_.size()));
    }
  }

  void FillValues(const Eigen::SparseMatrix<double>& a) {
    // A prescribed row's diagonal: the mean free diagonal, so that the
    // expanded matrix is no worse scaled than the free one.
    double scale = 1;
    if (a.rows() > 0) scale = a.diagonal().cwiseAbs().mean();
    if (!(scale > 0) || !std::isfinite(scale)) scale = 1;
    values_.resize(source_.size());
    for (std::size_t e = 0; e < source_.size(); ++e) {
      values_[e] = source_[e] < 0 ? scale : a.valuePtr()[source_[e]];
    }
  }

  Status Create(PetscObjects* objects) {
    const PetscInt local = last_row_ - first_row_;
    PBA_PETSC(MatCreate(SolverComm(), &objects->matrix));
    PBA_PETSC(MatSetSizes(objects->matrix, local, local, rows_, rows_));
    if (layout_ != nullptr) PBA_PETSC(MatSetBlockSize(objects->matrix, 3));
    if (CurrentRanks().size > 1) {
      PBA_PETSC(MatSetType(objects->matrix, MATMPIAIJ));
      PBA_PETSC(MatMPIAIJSetPreallocationCSR(objects->matrix, row_start_.data(), columns_.data(),
                                             values_.data()));
      // Every rank sets only its own rows.
      PBA_PETSC(MatSetOption(objects->matrix, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
    } else {
      PBA_PETSC(MatSetType(objects->matrix, MATSEQAIJ));
      PBA_PETSC(MatSeqAIJSetPreallocationCSR(objects->matrix, row_start_.data(), columns_.data(),
                                             values_.data()));
    }
    PBA_PETSC(MatSetOption(objects->matrix, MAT_SYMMETRIC, PETSC_TRUE));
    PBA_PETSC(MatSetOption(objects->matrix, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
    return Status::Ok();
  }

  const UnknownLayout* layout_ = nullptr;  // of the pattern built
  std::vector<int> outer_, inner_;         // the pattern loaded
  PetscInt rows_ = 0, first_row_ = 0, last_row_ = 0;
  std::vector<int> node_at_;             // node at each expanded node position
  std::vector<PetscInt> node_position_;  // the inverse
  std::vector<Eigen::Index> unknown_at_;
  std::vector<PetscInt> row_start_, columns_;  // this rank's rows
  std::vector<int> source_;
  std::vector<PetscScalar> values_;  // between building and handing over
};

// Copies b into this rank's rows of the expanded right-hand side, runs
// `ksp` (on objects->matrix), and copies the whole answer out (gathered
// from every rank).
Status ExpandedSolve(const PetscMatrix& matrix, KSP ksp, PetscObjects* objects,
                     const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  if (CurrentRanks().size > 1) {
    Digest digest;
    digest.Add(b.data(), sizeof(double) * b.size());
    PBA_RETURN_IF_ERROR(digest.CheckSameOnEveryRank("right-hand sides"));
  }
  PBA_PETSC(VecSet(objects->solution, 0.0));
  PetscScalar* rhs = nullptr;
  PBA_PETSC(VecGetArray(objects->rhs, &rhs));
  for (PetscInt row = matrix.first_row(); row < matrix.last_row(); ++row) {
    const Eigen::Index i = matrix.UnknownAt(row);
    rhs[row - matrix.first_row()] = i >= 0 ? b(i) : 0.0;
  }
  PBA_PETSC(VecRestoreArray(objects->rhs, &rhs));
  PBA_PETSC(KSPSolve(ksp, objects->rhs, objects->solution));
  Vec whole = objects->solution;
  if (objects->gather != nullptr) {
    PBA_PETSC(VecScatterBegin(objects->gather, objects->solution, objects->everything,
                              INSERT_VALUES, SCATTER_FORWARD));
    PBA_PETSC(VecScatterEnd(objects->gather, objects->solution, objects->everything, INSERT_VALUES,
                            SCATTER_FORWARD));
    whole = objects->everything;
  }
  const PetscScalar* solution = nullptr;
  PBA_PETSC(VecGetArrayRead(whole, &solution));
  x->resize(b.size());
  for (Eigen::Index i = 0; i < b.size(); ++i) (*x)(i) = solution[matrix.Position(i)];
  PBA_PETSC(VecRestoreArrayRead(whole, &solution));
  return Status::Ok();
}

// MUMPS as PETSc's Cholesky-type factorisation (LDL^T with pivoting, sym =
// 2, since the matrix is only flagged symmetric), the inertia telling a
// matrix that is not positive definite. Makes `ksp` such a solver of
// `matrix` (the factor's type is chosen for it).
Status ConfigureMumps(KSP ksp, Mat matrix) {
  PBA_PETSC(KSPSetOperators(ksp, matrix, matrix));
  PBA_PETSC(KSPSetType(ksp, KSPPREONLY));
  PC pc = nullptr;
  PBA_PETSC(KSPGetPC(ksp, &pc));
  PBA_PETSC(PCSetType(pc, PCCHOLESKY));
  PBA_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PBA_PETSC(PCFactorSetUpMatSolverType(pc));
  Mat factor = nullptr;
  PBA_PETSC(PCFactorGetMatrix(pc, &factor));
  // Null pivots detected (needed for the inertia); MUMPS prints nothing.
  PBA_PETSC(MatMumpsSetIcntl(factor, 24, 1));
  PBA_PETSC(MatMumpsSetIcntl(factor, 4, 0));
  // Across ranks the inertia is the whole matrix's only when the root
  // front is factorised on one process (MUMPS's ICNTL(13) = 1).
  if (CurrentRanks().size > 1) PBA_PETSC(MatMumpsSetIcntl(factor, 13, 1));
  return Status::Ok();
}

// Factorises `matrix`'s current values with the MUMPS `ksp`; a matrix
// that is not positive definite gives Status::Numerical.
Status FactorizeMumps(KSP ksp, Mat matrix) {
  PBA_PETSC(KSPSetOperators(ksp, matrix, matrix));
  PBA_PETSC(KSPSetUp(ksp));
  PC pc = nullptr;
  PBA_PETSC(KSPGetPC(ksp, &pc));
  PCFailedReason failed = PC_NOERROR;
  PBA_PETSC(PCGetFailedReason(pc, &failed));
  if (failed != PC_NOERROR) {
    return Status::Numerical(
        Format("MUMPS could not factorise the stiffness matrix (%s): it is singular or not "
               "positive definite (a body not held against rigid motion, or a degenerate mesh)",
               PCFailedReasons[failed]));
  }
  Mat factor = nullptr;
  PBA_PETSC(PCFactorGetMatrix(pc, &factor));
  PetscInt negative = 0, zero = 0, positive = 0;
  PBA_PETSC(MatGetInertia(factor, &negative, &zero, &positive));
  if (negative > 0 || zero > 0) {
    return Status::Numerical(
        Format("the stiffness matrix is not positive definite: MUMPS found %d negative and %d "
               "zero pivots (a body not held against rigid motion, an unstable state, or a "
               "degenerate mesh)",
               static_cast<int>(negative), static_cast<int>(zero)));
  }
  return Status::Ok();
}

class MumpsSolver final : public LinearSolver {
 public:
  ~MumpsSolver() override {
    const auto lock = PetscLock();
    objects_.Destroy();
  }

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    PBA_RETURN_IF_ERROR(InitializePetsc());
    const auto lock = PetscLock();
    factorized_ = false;
    bool rebuilt = false;
    PBA_RETURN_IF_ERROR(matrix_.Load(a, nullptr, &objects_, &rebuilt));
    if (rebuilt || objects_.ksp == nullptr) {
      PBA_RETURN_IF_ERROR(objects_.NewSolver());
      PBA_RETURN_IF_ERROR(ConfigureMumps(objects_.ksp, objects_.matrix));
    }
    PBA_RETURN_IF_ERROR(FactorizeMumps(objects_.ksp, objects_.matrix));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (!factorized_) return Status::Internal("MUMPS solve without a successful Factorize");
    const auto lock = PetscLock();
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, objects_.ksp, &objects_, b, x));
    if (!x->allFinite()) return Status::Numerical("MUMPS's solve produced no finite answer");
    return Status::Ok();
  }

  std::string Name() const override { return "MUMPS multifrontal LDL^T (PETSc)" + OnRanks(); }
  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<MumpsSolver>();
  }

 private:
  PetscMatrix matrix_;
  PetscObjects objects_;
  bool factorized_ = false;
};

// Conjugate gradients with algebraic multigrid.
class AmgSolver final : public LinearSolver {
 public:
  AmgSolver(const LinearSolverSettings& settings, const UnknownLayout* layout,
            const std::atomic<bool>* cancel)
      : settings_(settings), layout_(layout), cancel_(cancel) {}
  ~AmgSolver() override {
    const auto lock = PetscLock();
    DestroyFallback();
    objects_.Destroy();
  }

  Status Factorize(const Eigen::SparseMatrix<double>& a) override {
    PBA_RETURN_IF_ERROR(InitializePetsc());
    factorized_ = false;
    fallback_factorized_ = false;
    // A positive definite matrix has a positive diagonal; CG on one that is
    // not would wander, so this necessary condition is checked first (as
    // PCG does). Indefinite matrices with a positive diagonal show as a
    // failed solve.
    PBA_RETURN_IF_ERROR(CheckPositiveDiagonal(a));
    unknowns_ = a.rows();
    const auto lock = PetscLock();
    bool rebuilt = false;
    PBA_RETURN_IF_ERROR(matrix_.Load(a, layout_, &objects_, &rebuilt));
    if (rebuilt) DestroyFallback();
    if (rebuilt || objects_.ksp == nullptr) {
      PBA_RETURN_IF_ERROR(Setup());
      hierarchy_iterations_ = -1;
    }
    // Lagged multigrid: the hierarchy built for an earlier matrix of the
    // same pattern (Newton's last tangent) preconditions this one while the
    // solves it serves take at most twice (plus five) the iterations of its
    // first; past that, or when a solve with it fails, it is rebuilt. Its
    // setup (aggregation, Galerkin products, smoother estimates) costs
    // several solves, and Newton's tangents change little between
    // iterations. The answer is unaffected: every solve meets the same
    // tolerance on the true residual of the current matrix.
    const bool reuse = hierarchy_iterations_ >= 0 && !rebuild_next_ &&
                       last_iterations_ <= 2 * hierarchy_iterations_ + 5;
    PBA_RETURN_IF_ERROR(SetUpPreconditioner(reuse));
    factorized_ = true;
    return Status::Ok();
  }

  Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) override {
    if (!factorized_) return Status::Internal("AMG solve without a successful Factorize");
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    int iterations = 0;
    double residual = INFINITY;
    PBA_RETURN_IF_ERROR(Iterate(b, x, &reason, &iterations, &residual));
    // A lagged hierarchy that no longer serves: rebuilt for this matrix and
    // the solve redone once.
    if (!Converged(reason, residual) && reused_ && !cancelled_ &&
        reason != KSP_DIVERGED_INDEFINITE_MAT) {
      {
        const auto lock = PetscLock();
        PBA_RETURN_IF_ERROR(SetUpPreconditioner(false));
      }
      PBA_RETURN_IF_ERROR(Iterate(b, x, &reason, &iterations, &residual));
    }
    if (cancelled_) {
      return Status::Cancelled(
          Format("cancelled during conjugate gradients (iteration %d)", iterations));
    }
    ++solves_;
    last_iterations_ = iterations;
    last_residual_ = residual;
    if (hierarchy_iterations_ < 0) hierarchy_iterations_ = iterations;
    min_iterations_ = solves_ == 1 ? iterations : std::min(min_iterations_, iterations);
    max_iterations_seen_ = std::max(max_iterations_seen_, iterations);
    if (Converged(reason, residual)) return Status::Ok();
    rebuild_next_ = true;
    if (reason == KSP_DIVERGED_INDEFINITE_MAT) {
      // Negative curvature p.Ap < 0: the matrix itself is indefinite (a
      // Newton tangent past a limit point, far from equilibrium), which no
      // other solver would change.
      return Status::Numerical(
          Format("the stiffness matrix is not positive definite: conjugate gradients met a "
                 "direction of negative curvature at iteration %d",
                 iterations));
    }
    const std::string failure = Format(
        "conjugate gradients with %s did not converge: %d iterations reached a relative "
        "residual of %.3g (target %.1e, %s)",
        settings_.PreconditionerName(), iterations, residual, settings_.relative_tolerance,
        KSPConvergedReasons[reason]);
    if (unknowns_ > settings_.fallback_direct_max_unknowns) {
      return Status::Numerical(
          failure + Format("; the system (%lld unknowns) is above "
                           "linear_solver_options.fallback_direct_max_unknowns (%d), so it is "
                           "not redone by MUMPS; a nearly incompressible material or a body "
                           "barely held against rigid motion are the usual causes",
                           static_cast<long long>(unknowns_),
                           settings_.fallback_direct_max_unknowns));
    }
    // Redone by MUMPS, whose inertia also tells an indefinite matrix: a
    // factorisation of the matrix PETSc holds for the multigrid (a
    // modified-Newton step solves with it after the caller's matrix is
    // gone), kept for the next solves with this one.
    const auto lock = PetscLock();
    if (!fallback_factorized_) {
      if (fallback_ == nullptr) {
        PBA_PETSC(KSPCreate(SolverComm(), &fallback_));
        PBA_RETURN_IF_ERROR(ConfigureMumps(fallback_, objects_.matrix));
      }
      const Status factorized = FactorizeMumps(fallback_, objects_.matrix);
      if (!factorized.ok()) {
        return Status::Numerical(failure + "; MUMPS, the fallback: " + factorized.message());
      }
      fallback_factorized_ = true;
    }
    ++fallbacks_;
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, fallback_, &objects_, b, x));
    if (!x->allFinite()) return Status::Numerical("MUMPS's solve produced no finite answer");
    return Status::Ok();
  }

  bool Iterative() const override { return true; }
  std::string Name() const override {
    std::string name =
        Format("conjugate gradients with %s (PETSc%s), relative tolerance %.0e",
               settings_.PreconditionerName(), OnRanks().c_str(), settings_.relative_tolerance);
    if (layout_ == nullptr) name += ", scalar aggregation (no rigid-body modes)";
    if (solves_ > 0) {
      name += Format(
          " (%d solves, %d-%d iterations, %d multigrid setups; last: %d iterations, relative "
          "residual %.1e",
          solves_, min_iterations_, max_iterations_seen_, setups_, last_iterations_,
          last_residual_);
      if (fallbacks_ > 0) name += Format("; %d redone by MUMPS", fallbacks_);
      name += ")";
    }
    return name;
  }

  std::unique_ptr<LinearSolver> NewOfSameKind() const override {
    return std::make_unique<AmgSolver>(settings_, layout_, cancel_);
  }

 private:
  // The fallback's factorisation (of an earlier pattern's matrix) goes.
  void DestroyFallback() {
    if (fallback_ != nullptr) KSPDestroy(&fallback_);
    fallback_factorized_ = false;
  }

  Status Setup() {
    if (layout_ != nullptr) PBA_RETURN_IF_ERROR(SetNearNullSpace());
    PBA_RETURN_IF_ERROR(objects_.NewSolver());
    fresh_ksp_ = true;
    PBA_PETSC(KSPSetType(objects_.ksp, KSPCG));
    // The tolerance is on the residual itself, ||b - A x|| / ||b||.
    PBA_PETSC(KSPSetNormType(objects_.ksp, KSP_NORM_UNPRECONDITIONED));
    PBA_PETSC(KSPSetTolerances(objects_.ksp, settings_.relative_tolerance, 0.0, PETSC_DEFAULT,
                               settings_.max_iterations));
    PBA_PETSC(KSPSetErrorIfNotConverged(objects_.ksp, PETSC_FALSE));
    void* default_test = nullptr;
    PBA_PETSC(KSPConvergedDefaultCreate(&default_test));
    PBA_PETSC(KSPSetConvergenceTest(objects_.ksp, &AmgSolver::Test, this, nullptr));
    default_test_.reset(default_test);
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(objects_.ksp, &pc));
    if (settings_.preconditioner == LinearSolverSettings::Preconditioner::kGamg) {
      PBA_PETSC(PCSetType(pc, PCGAMG));
      PBA_PETSC(PCGAMGSetType(pc, PCGAMGAGG));
      PetscReal threshold[] = {settings_.gamg_threshold};
      PBA_PETSC(PCGAMGSetThreshold(pc, threshold, 1));
      // Completes the multigrid's defaults (Chebyshev-Jacobi smoothing on
      // every level) from an options database holding nothing of the
      // user's (InitializePetsc cleared it): without it the levels keep
      // PCMG's bare defaults, whose V-cycle was several times dearer.
      PBA_PETSC(KSPSetFromOptions(objects_.ksp));
    } else {
      PBA_PETSC(PCSetType(pc, PCHYPRE));
      PBA_PETSC(PCHYPRESetType(pc, "boomeramg"));
      // hypre reads its parameters from the options database: this
      // solver's, under its own prefix, set from the scene only.
      const std::string prefix = Format("pba_amg_%p_", static_cast<void*>(this));
      PBA_PETSC(KSPSetOptionsPrefix(objects_.ksp, prefix.c_str()));
      const std::string strong = Format("%.17g", settings_.boomeramg_strong_threshold);
      const std::pair<const char*, std::string> options[] = {
          {"pc_hypre_boomeramg_strong_threshold", strong},
          {"pc_hypre_boomeramg_coarsen_type", "HMIS"},
          {"pc_hypre_boomeramg_interp_type", "ext+i"},
          {"pc_hypre_boomeramg_nodal_coarsen", layout_ != nullptr ? "6" : "0"},
      };
      for (const auto& [key, value] : options) {
        const std::string name = "-" + prefix + key;
        PBA_PETSC(PetscOptionsSetValue(nullptr, name.c_str(), value.c_str()));
      }
      PBA_PETSC(PCSetFromOptions(pc));
      for (const auto& [key, value] : options) {
        const std::string name = "-" + prefix + key;
        PetscOptionsClearValue(nullptr, name.c_str());
      }
    }
    return Status::Ok();
  }

  // Builds the hierarchy for the current matrix, or keeps the last one.
  Status SetUpPreconditioner(bool reuse) {
    // A new hierarchy is built in a new KSP: set up again in place, GAMG
    // kept parts of the old one, and its smoothers could then make the
    // preconditioner indefinite for a matrix far from the old (seen as
    // DIVERGED_INDEFINITE_PC). The aggregation it would save is a small
    // part of a set-up; the Galerkin products are redone either way.
    if (!reuse && !fresh_ksp_) PBA_RETURN_IF_ERROR(Setup());
    fresh_ksp_ = false;
    PC pc = nullptr;
    PBA_PETSC(KSPGetPC(objects_.ksp, &pc));
    PBA_PETSC(PCSetReusePreconditioner(pc, reuse ? PETSC_TRUE : PETSC_FALSE));
    PBA_PETSC(KSPSetOperators(objects_.ksp, objects_.matrix, objects_.matrix));
    PBA_PETSC(KSPSetUp(objects_.ksp));
    PCFailedReason failed = PC_NOERROR;
    PBA_PETSC(PCGetFailedReason(pc, &failed));
    if (failed != PC_NOERROR) {
      return Status::Numerical(
          Format("the multigrid preconditioner could not be built (%s)", PCFailedReasons[failed]));
    }
    reused_ = reuse;
    if (!reuse) {
      ++setups_;
      hierarchy_iterations_ = -1;
      rebuild_next_ = false;
    }
    return Status::Ok();
  }

  // One CG solve: its reason, iterations and true relative residual.
  Status Iterate(const Eigen::VectorXd& b, Eigen::VectorXd* x, KSPConvergedReason* reason,
                 int* iterations, double* residual) {
    const auto lock = PetscLock();
    cancelled_ = false;
    PBA_RETURN_IF_ERROR(ExpandedSolve(matrix_, objects_.ksp, &objects_, b, x));
    PetscInt its = 0;
    PBA_PETSC(KSPGetIterationNumber(objects_.ksp, &its));
    *iterations = static_cast<int>(its);
    PBA_PETSC(KSPGetConvergedReason(objects_.ksp, reason));
    // The true residual of the system solved (prescribed rows included:
    // theirs is their tiny solution times the scale).
    PBA_RETURN_IF_ERROR(TrueResidual(residual));
    if (!x->allFinite()) *residual = INFINITY;
    return Status::Ok();
  }

  // The recurrence CG tests drifts from the true residual; a digit of
  // drift is accepted, more is not convergence.
  bool Converged(KSPConvergedReason reason, double residual) const {
    return reason > 0 && residual <= 10 * settings_.relative_tolerance;
  }

  // ||b - A x|| / ||b|| over the expanded system just solved.
  Status TrueResidual(double* residual) {
    Vec r = nullptr;
    PBA_PETSC(VecDuplicate(objects_.rhs, &r));
    PetscReal r_norm = 0, b_norm = 0;
    PetscErrorCode code = MatMult(objects_.matrix, objects_.solution, r);
    if (code == 0) code = VecAYPX(r, -1.0, objects_.rhs);
    if (code == 0) code = VecNorm(r, NORM_2, &r_norm);
    if (code == 0) code = VecNorm(objects_.rhs, NORM_2, &b_norm);
    VecDestroy(&r);
    PBA_PETSC(code);
    *residual = r_norm / (b_norm > 0 ? b_norm : 1.0);
    if (!std::isfinite(*residual)) *residual = INFINITY;
    return Status::Ok();
  }

  // The rigid motions of the nodes: three translations, three rotations,
  // from the coordinates of this rank's nodes.
  Status SetNearNullSpace() {
    Vec coordinates = nullptr;
    PBA_PETSC(MatCreateVecs(objects_.matrix, &coordinates, nullptr));
    PetscScalar* c = nullptr;
    PetscErrorCode code = VecGetArray(coordinates, &c);
    if (code == 0) {
      for (PetscInt row = matrix_.first_row(); row < matrix_.last_row(); ++row) {
        c[row - matrix_.first_row()] = layout_->coordinates[3 * matrix_.NodeAt(row) + row % 3];
      }
      code = VecRestoreArray(coordinates, &c);
    }
    MatNullSpace rigid = nullptr;
    if (code == 0) code = MatNullSpaceCreateRigidBody(coordinates, &rigid);
    VecDestroy(&coordinates);
    PBA_PETSC(code);
    const PetscErrorCode set = MatSetNearNullSpace(objects_.matrix, rigid);
    MatNullSpaceDestroy(&rigid);
    PBA_PETSC(set);
    return Status::Ok();
  }

  // PETSc's default test, plus the cancel flag.
  static PetscErrorCode Test(KSP ksp, PetscInt iteration, PetscReal norm,
                             KSPConvergedReason* reason, void* context) {
    auto* self = static_cast<AmgSolver*>(context);
    int cancel = self->cancel_ != nullptr && self->cancel_->load(std::memory_order_relaxed);
    // Across ranks, one rank's cancel stops all of them at the same
    // iteration (each sees its own signal at its own moment).
    if (CurrentRanks().size > 1) {
      MPI_Allreduce(MPI_IN_PLACE, &cancel, 1, MPI_INT, MPI_LOR, PETSC_COMM_WORLD);
    }
    if (cancel != 0) {
      self->cancelled_ = true;
      *reason = KSP_DIVERGED_ITS;
      return 0;
    }
    return KSPConvergedDefault(ksp, iteration, norm, reason, self->default_test_.get());
  }

  struct DefaultTestDeleter {
    void operator()(void* context) const { KSPConvergedDefaultDestroy(context); }
  };

  LinearSolverSettings settings_;
  const UnknownLayout* layout_;      // not owned; may be null
  const std::atomic<bool>* cancel_;  // not owned; may be null
  PetscMatrix matrix_;
  PetscObjects objects_;
  std::unique_ptr<void, DefaultTestDeleter> default_test_;
  KSP fallback_ = nullptr;            // MUMPS on objects_.matrix, once a solve needed it
  bool fallback_factorized_ = false;  // of the matrix's current values
  Eigen::Index unknowns_ = 0;
  bool factorized_ = false;
  bool cancelled_ = false;
  int solves_ = 0, fallbacks_ = 0, setups_ = 0;
  // Iterations of the first solve with the current hierarchy (-1: none yet).
  int hierarchy_iterations_ = -1;
  bool reused_ = false;        // the current solve's hierarchy is an earlier matrix's
  bool fresh_ksp_ = false;     // the KSP has not been set up yet
  bool rebuild_next_ = false;  // the last solve failed: no reuse at the next Factorize
  int last_iterations_ = 0, min_iterations_ = 0, max_iterations_seen_ = 0;
  double last_residual_ = 0;
};

}  // namespace

std::unique_ptr<LinearSolver> CreateAmgSolver(const LinearSolverSettings& settings,
                                              const UnknownLayout* layout,
                                              const std::atomic<bool>* cancel) {
  return std::make_unique<AmgSolver>(settings, layout, cancel);
}

std::unique_ptr<LinearSolver> CreateMumpsSolver() { return std::make_unique<MumpsSolver>(); }

}  // namespace pba
