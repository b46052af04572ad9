// What the PETSc backends share (linear/petsc_solver.cc,
// linear/pressure_schur_solver.cc): the communicator, the objects of one
// solver, a symmetric matrix handed over from Eigen (expanded to whole
// nodes and split between MPI ranks), the solve through it, and MUMPS.
// Internal to linear/; every call holds PetscLock.
#pragma once

#include <petscksp.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_runtime.h"

namespace pba {
namespace petsc_detail {

// The communicator the solvers work on: every rank of an MPI job (each
// holds the whole matrix and takes its share of the rows), else this
// process alone.
inline MPI_Comm SolverComm() {
  return CurrentRanks().size > 1 ? PETSC_COMM_WORLD : PETSC_COMM_SELF;
}

// " on 2 MPI ranks", or nothing in a process of its own.
std::string OnRanks();

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
                 std::vector<int>* order, std::vector<PetscInt>* sizes);

// The nodes of `layout` whose rows the rank `rank` of `ranks` takes (as
// PetscMatrix splits them, by BisectNodes): one flag per node.
std::vector<char> NodesOfRank(const UnknownLayout& layout, int rank, int ranks);

// A symmetric matrix handed over in Eigen's compressed column storage, kept
// as PETSc's row storage of the same matrix (symmetric: columns are rows),
// optionally expanded to every degree of freedom of the mesh's nodes so
// that each node's three unknowns form a block (prescribed ones get a
// diagonal entry of the matrix's scale and a zero right-hand side).
//
// Across the ranks of an MPI job every rank hands PETSc its own rows:
// whole nodes, grouped by recursive coordinate bisection so that a rank's
// rows couple mostly to each other (without a layout, an even split of the
// unknowns in their order). With a layout only those rows (as columns of
// the symmetric matrix) are read, so a rank may be given a matrix that
// holds nothing else (a partitioned assembly); without one every rank
// holds the whole matrix.
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
    PBA_RETURN_IF_ERROR(CheckSameOnEveryRank(a, layout));
    *rebuilt = objects->matrix == nullptr || !SamePattern(a) || layout != layout_;
    if (CurrentRanks().size > 1) {
      // Each rank's own pattern decides; a new PETSc matrix is made by all.
      int any = *rebuilt ? 1 : 0;
      PBA_RETURN_IF_ERROR(Reduce(&any, MPI_INT, MPI_MAX));
      *rebuilt = any != 0;
    }
    if (*rebuilt) {
      if (objects->matrix != nullptr) MatDestroy(&objects->matrix);
      // Recorded once the new matrix exists (below): a failure on the way
      // leaves no pattern that a later call would take for built.
      outer_.clear();
      inner_.clear();
      BuildPattern(a, layout);
    }
    PBA_RETURN_IF_ERROR(FillValues(a));
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
  // Status::Numerical naming the first of this rank's unknowns whose
  // diagonal entry in `a` (as loaded last) is not positive and finite, the
  // least such unknown over the ranks (every rank gets the same answer);
  // for a matrix of which each rank holds its own columns.
  Status CheckPositiveDiagonal(const Eigen::SparseMatrix<double>& a) const {
    int bad = -1;
    double value = 0;
    for (PetscInt r = first_row_; r < last_row_ && bad < 0; ++r) {
      const Eigen::Index j = unknown_at_[r];
      if (j < 0) continue;
      const double d = Diagonal(a, j);
      if (!(d > 0) || !std::isfinite(d)) {
        bad = static_cast<int>(j);
        value = d;
      }
    }
    // The least unknown: the largest of its negation (none: the least int).
    constexpr int kNone = std::numeric_limits<int>::min();
    int worst = bad < 0 ? kNone : -bad - 1;
    PBA_RETURN_IF_ERROR(Reduce(&worst, MPI_INT, MPI_MAX));
    if (worst == kNone) return Status::Ok();
    const int unknown = -worst - 1;
    double shared = unknown == bad ? value : 0;  // from the rank that found it
    PBA_RETURN_IF_ERROR(Reduce(&shared, MPI_DOUBLE, MPI_SUM));
    return Status::Numerical(
        Format("the stiffness matrix is not positive definite (diagonal entry %d is %.3g): "
               "a body not held against rigid motion, an unstable state, or a degenerate mesh",
               unknown, shared));
  }

  // This rank's rows [first_row(), last_row()).
  PetscInt first_row() const { return first_row_; }
  PetscInt last_row() const { return last_row_; }
  // The mesh node at expanded row `row` (a layout's system only).
  int NodeAt(PetscInt row) const { return node_at_[row / 3]; }

 private:
  // Whole matrices must be the same on every rank. Of a layout's system,
  // which a rank may hold only its own columns of, the layout must be (the
  // same mesh and free unknowns): the right-hand side, which every rank
  // holds whole, is compared at each solve (ExpandedSolve).
  static Status CheckSameOnEveryRank(const Eigen::SparseMatrix<double>& a,
                                     const UnknownLayout* layout) {
    if (CurrentRanks().size <= 1) return Status::Ok();
    Digest digest;
    digest.AddValue(static_cast<std::int64_t>(a.rows()));
    if (layout != nullptr) {
      digest.Add(layout->dof_of_unknown.data(), sizeof(int) * layout->dof_of_unknown.size());
      digest.Add(layout->coordinates.data(), sizeof(double) * layout->coordinates.size());
      return digest.CheckSameOnEveryRank("meshes or free unknowns");
    }
    digest.AddValue(static_cast<std::int64_t>(a.nonZeros()));
    digest.Add(a.outerIndexPtr(), sizeof(int) * (a.outerSize() + 1));
    digest.Add(a.innerIndexPtr(), sizeof(int) * a.nonZeros());
    digest.Add(a.valuePtr(), sizeof(double) * a.nonZeros());
    return digest.CheckSameOnEveryRank("stiffness matrices");
  }

  // One value reduced over the ranks in place (PetscLock is held: not
  // SumOverRanks, which takes it).
  static Status Reduce(void* value, MPI_Datatype type, MPI_Op op) {
    if (CurrentRanks().size <= 1) return Status::Ok();
    if (MPI_Allreduce(MPI_IN_PLACE, value, 1, type, op, PETSC_COMM_WORLD) != MPI_SUCCESS) {
      return Status::Internal("the MPI ranks could not combine their matrices' figures");
    }
    return Status::Ok();
  }

  // a(j, j), 0 when the column lacks it.
  static double Diagonal(const Eigen::SparseMatrix<double>& a, Eigen::Index j) {
    const int* begin = a.innerIndexPtr() + a.outerIndexPtr()[j];
    const int* end = a.innerIndexPtr() + a.outerIndexPtr()[j + 1];
    const int* at = std::lower_bound(begin, end, static_cast<int>(j));
    return at != end && *at == j ? a.valuePtr()[at - a.innerIndexPtr()] : 0.0;
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

  Status FillValues(const Eigen::SparseMatrix<double>& a) {
    // A prescribed row's diagonal: the mean free diagonal, so that the
    // expanded matrix is no worse scaled than the free one; across ranks
    // each adds up its own rows' (all a rank may hold).
    double scale = 1;
    if (layout_ != nullptr && CurrentRanks().size > 1) {
      double sum = 0;
      for (PetscInt r = first_row_; r < last_row_; ++r) {
        if (unknown_at_[r] >= 0) sum += std::abs(Diagonal(a, unknown_at_[r]));
      }
      PBA_RETURN_IF_ERROR(Reduce(&sum, MPI_DOUBLE, MPI_SUM));
      if (a.rows() > 0) scale = sum / static_cast<double>(a.rows());
    } else if (a.rows() > 0) {
      scale = a.diagonal().cwiseAbs().mean();
    }
    if (!(scale > 0) || !std::isfinite(scale)) scale = 1;
    values_.resize(source_.size());
    for (std::size_t e = 0; e < source_.size(); ++e) {
      values_[e] = source_[e] < 0 ? scale : a.valuePtr()[source_[e]];
    }
    return Status::Ok();
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
                     const Eigen::VectorXd& b, Eigen::VectorXd* x);

// MUMPS as PETSc's Cholesky-type factorisation (LDL^T with pivoting, sym =
// 2, since the matrix is only flagged symmetric), the inertia telling a
// matrix that is not positive definite. Makes `ksp` such a solver of
// `matrix` (the factor's type is chosen for it).
Status ConfigureMumps(KSP ksp, Mat matrix);

// Factorises `matrix`'s current values with the MUMPS `ksp`; a matrix
// that is not positive definite gives Status::Numerical.
Status FactorizeMumps(KSP ksp, Mat matrix);

// Makes the rigid motions of the nodes (three translations, three
// rotations, from this rank's nodes' coordinates) the near-null space GAMG
// aggregates by, on `matrix`: `loaded`'s expanded system with `layout`.
Status SetRigidBodyNearNullSpace(const PetscMatrix& loaded, const UnknownLayout& layout,
                                 Mat matrix);

// The iteration counts of an iterative solver's solves, for its Name().
struct SolveCounts {
  int solves = 0;
  int min_iterations = 0, max_iterations = 0, last_iterations = 0;
  double last_residual = 0;
  void Record(int iterations, double residual) {
    ++solves;
    min_iterations = solves == 1 ? iterations : std::min(min_iterations, iterations);
    max_iterations = std::max(max_iterations, iterations);
    last_iterations = iterations;
    last_residual = residual;
  }
};

// PETSc's default convergence test, plus a cancel flag looked at every
// iteration: a set flag ends the solve (KSP_DIVERGED_ITS) and cancelled()
// says so. Across ranks, one rank's cancel stops all of them at the same
// iteration (each sees its own signal at its own moment).
class CancellableTest {
 public:
  explicit CancellableTest(const std::atomic<bool>* cancel) : cancel_(cancel) {}
  ~CancellableTest();
  CancellableTest(const CancellableTest&) = delete;
  CancellableTest& operator=(const CancellableTest&) = delete;
  // Makes it `ksp`'s test (a new KSP each time; the last one's context goes).
  Status Install(KSP ksp);
  void Reset() { cancelled_ = false; }
  bool cancelled() const { return cancelled_; }

 private:
  static PetscErrorCode Test(KSP ksp, PetscInt iteration, PetscReal norm,
                             KSPConvergedReason* reason, void* context);
  const std::atomic<bool>* cancel_;  // not owned; may be null
  bool cancelled_ = false;
  void* default_context_ = nullptr;
};

}  // namespace petsc_detail
}  // namespace pba
