#include "linear/petsc_matrix.h"

#include <algorithm>
#include <cmath>

#include "core/format.h"

namespace pba {
namespace petsc_detail {

std::string OnRanks() {
  const int size = CurrentRanks().size;
  return size > 1 ? Format(" on %d MPI ranks", size) : std::string();
}

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

std::vector<char> NodesOfRank(const UnknownLayout& layout, int rank, int ranks) {
  std::vector<int> all(layout.num_nodes()), order;
  for (int n = 0; n < layout.num_nodes(); ++n) all[n] = n;
  std::vector<PetscInt> sizes;
  BisectNodes(layout.coordinates, std::move(all), ranks, &order, &sizes);
  std::vector<char> own(layout.num_nodes(), 0);
  PetscInt first = 0;
  for (int r = 0; r < rank; ++r) first += sizes[r];
  for (PetscInt p = first; p < first + sizes[rank]; ++p) own[order[p]] = 1;
  return own;
}

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

Status SetRigidBodyNearNullSpace(const PetscMatrix& loaded, const UnknownLayout& layout,
                                 Mat matrix) {
  Vec coordinates = nullptr;
  PBA_PETSC(MatCreateVecs(matrix, &coordinates, nullptr));
  PetscScalar* c = nullptr;
  PetscErrorCode code = VecGetArray(coordinates, &c);
  if (code == 0) {
    for (PetscInt row = loaded.first_row(); row < loaded.last_row(); ++row) {
      c[row - loaded.first_row()] = layout.coordinates[3 * loaded.NodeAt(row) + row % 3];
    }
    code = VecRestoreArray(coordinates, &c);
  }
  MatNullSpace rigid = nullptr;
  if (code == 0) code = MatNullSpaceCreateRigidBody(coordinates, &rigid);
  VecDestroy(&coordinates);
  PBA_PETSC(code);
  const PetscErrorCode set = MatSetNearNullSpace(matrix, rigid);
  MatNullSpaceDestroy(&rigid);
  PBA_PETSC(set);
  return Status::Ok();
}

CancellableTest::~CancellableTest() {
  if (default_context_ != nullptr) KSPConvergedDefaultDestroy(default_context_);
}

Status CancellableTest::Install(KSP ksp) {
  if (default_context_ != nullptr) KSPConvergedDefaultDestroy(default_context_);
  default_context_ = nullptr;
  PBA_PETSC(KSPConvergedDefaultCreate(&default_context_));
  PBA_PETSC(KSPSetConvergenceTest(ksp, &CancellableTest::Test, this, nullptr));
  return Status::Ok();
}

PetscErrorCode CancellableTest::Test(KSP ksp, PetscInt iteration, PetscReal norm,
                                     KSPConvergedReason* reason, void* context) {
  auto* self = static_cast<CancellableTest*>(context);
  int cancel = self->cancel_ != nullptr && self->cancel_->load(std::memory_order_relaxed);
  if (CurrentRanks().size > 1) {
    MPI_Allreduce(MPI_IN_PLACE, &cancel, 1, MPI_INT, MPI_LOR, PETSC_COMM_WORLD);
  }
  if (cancel != 0) {
    self->cancelled_ = true;
    *reason = KSP_DIVERGED_ITS;
    return 0;
  }
  return KSPConvergedDefault(ksp, iteration, norm, reason, self->default_context_);
}

}  // namespace petsc_detail
}  // namespace pba
