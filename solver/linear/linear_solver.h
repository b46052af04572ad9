// LinearSolver: factorise a symmetric positive definite matrix once, solve
// for right-hand sides. One backend per file; CreateLinearSolver picks one.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/thread_context.h"
#include "pba/status.h"

namespace pba {

// A tangent written with its elements' volume constraints apart (the
// mean-dilatation elements, TET10_MD and HEX8: one constraint per element):
//
//   K = A + b^T diag(weight) b
//
// with one row of `b` per constraint, its volume gradient dv/dx on the
// free unknowns, and weight = U''(theta) / V. Nearly incompressible, the
// second term dwarfs A (K / mu of 1e3 and more), and multigrid on K
// converges ever more slowly; the same system with the constraints'
// pressures p = diag(weight) b u as unknowns,
//
//   [ A   b^T          ] [u]   [r]
//   [ b  -diag(1/weight)] [p] = [0],
//
// is solved at a cost that does not grow with K / mu when the pair is
// inf-sup stable (P2/P0, TET10_MD), by a Schur-complement field split
// (CreateAmgSolver with the PRESSURE_SCHUR preconditioner). A is K less the
// constraints' term, so whatever else K holds (contact, follower loads) is
// A's.
struct VolumetricSplit {
  Eigen::SparseMatrix<double, Eigen::RowMajor> b;  // constraints x free unknowns [m^2]
  Eigen::VectorXd weight;                          // U''(theta) / V [Pa/m^3]
  // Per constraint: the element's reference volume V [m^3] and its
  // material's initial shear modulus [Pa], the scale of the pressures'
  // preconditioner.
  Eigen::VectorXd volume;
  Eigen::VectorXd shear_modulus;
  bool empty() const { return b.rows() == 0; }
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // Analyses and factorises `a` (both triangles stored; only the lower one is read).
  // A matrix that is not positive definite gives Status::Numerical.
  virtual Status Factorize(const Eigen::SparseMatrix<double>& a) = 0;
  virtual Status Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) = 0;
  // For people, e.g. "CHOLMOD supernodal Cholesky".
  virtual std::string Name() const = 0;
  // An iterative solver (PCG, AMG): chosen where a factorisation may not
  // fit, so callers do not fall back on one of their own for any size.
  virtual bool Iterative() const { return false; }
  // A fresh solver of the same kind (to hold a second factorisation).
  virtual std::unique_ptr<LinearSolver> NewOfSameKind() const = 0;
  // Whether FactorizeSplit uses a VolumetricSplit (the caller then
  // assembles one where the model has it).
  virtual bool WantsVolumetricSplit() const { return false; }
  // Factorises `a`, given also with its volume constraints apart (`split`,
  // of the same a). A solver that WantsVolumetricSplit solves the mixed
  // form, to a's answer; the others factorise `a`, as does any solver given
  // an empty split.
  virtual Status FactorizeSplit(const Eigen::SparseMatrix<double>& a,
                                const VolumetricSplit& split) {
    return Factorize(a);
  }
  // Across the ranks of an MPI job, a solver that reads only this rank's
  // share of each matrix it is given: one flag per node of its layout, set
  // for the nodes whose columns (by symmetry, rows) this rank hands to
  // PETSc. The other columns of a matrix may then be left out (empty or
  // anything), which a partitioned assembly does (AssemblyOptions::
  // own_nodes). Null, the default: the solver reads whole matrices (one
  // process; CHOLMOD, Eigen's, PCG; PRESSURE_SCHUR, which forms its blocks
  // from the whole tangent; AUTO until it has chosen).
  virtual const std::vector<char>* OwnNodes() const { return nullptr; }
};

// Where the unknowns of a system sit: for free unknown i, its node
// dof_of_unknown[i] / 3 and direction dof_of_unknown[i] % 3, and every
// node's coordinates [m]. Multigrid builds its coarse spaces from the rigid
// motions of these nodes (the elasticity operator's near-null space) and
// groups each node's three unknowns; without a layout it falls back to
// scalar aggregation, which converges far more slowly on elasticity.
struct UnknownLayout {
  std::vector<int> dof_of_unknown;  // increasing; 3 * node + direction
  std::vector<double> coordinates;  // 3 per node, node-major [m]
  int num_nodes() const { return static_cast<int>(coordinates.size() / 3); }
};

// The tunable parts of the linear solve (analysis.linear_solver_options),
// defaults declared here once; SolveScene echoes them in the summary.
struct LinearSolverSettings {
  // AMG: the preconditioner under conjugate gradients.
  enum class Preconditioner {
    kGamg,       // PETSc's smoothed aggregation, rigid-body near-null space
    kBoomerAmg,  // hypre's BoomerAMG (classical AMG), unknowns grouped by node
    // A tangent given with its volume constraints (VolumetricSplit): its
    // displacement-pressure form by FGMRES with a Schur-complement field
    // split, GAMG on the displacements; a tangent without them: GAMG.
    kPressureSchur,
  };
  Preconditioner preconditioner = Preconditioner::kGamg;
  // AMG: the solve ends when ||b - A x|| <= relative_tolerance ||b||. Newton
  // tests its own residual, so an inexact correction costs iterations, never
  // accuracy; a linear analysis's answer is this solve, hence tight.
  double relative_tolerance = 1e-10;
  // AMG: conjugate-gradient iterations per solve before it counts as not
  // converged (and falls back to MUMPS when the system is small enough).
  int max_iterations = 1000;
  // GAMG: the graph threshold dropping weak couplings before aggregation
  // (0..0.5; larger: smaller coarse grids, more iterations).
  double gamg_threshold = 0.01;
  // BoomerAMG: the strong-connection threshold (0..1; 0.5 suits 3D elasticity).
  double boomeramg_strong_threshold = 0.5;
  // AUTO: CHOLMOD factorises a system whose supernodal factor, predicted by
  // its symbolic analysis, takes at most this many megabytes; a larger one
  // goes to AMG. 0 (the default): a quarter of the memory the solve may
  // take (SolveMemoryBytes: the machine's, or the address-space limit
  // pba-server gives each job), as Newton holds two factorisations and the
  // mesh, the tangent and the solver's work need the rest. The exact direct
  // solve is kept wherever it fits: on nearly incompressible tissue it is
  // faster than AMG at the sizes a factor fits, and AMG on TET4_ANP at
  // K/mu = 1e3 may not converge at all (docs/performance.md, "Linear
  // solvers").
  int auto_direct_max_factor_mb = 0;
  // The budget when the machine's memory cannot be read.
  static constexpr int kFallbackDirectFactorMb = 2000;
  // AMG: a solve that does not converge is redone by MUMPS when the system
  // has at most this many unknowns; above, the increment fails with the
  // iterative solver's message.
  int fallback_direct_max_unknowns = 250000;

  const char* PreconditionerName() const;
};

// Which backend an implicit analysis factorises with (analysis.linear_solver).
struct LinearSolverOptions {
  enum class Kind {
    kAuto,       // CHOLMOD while its factor fits settings.auto_direct_max_factor_mb, else AMG
    kCholmod,    // supernodal sparse Cholesky (SuiteSparse)
    kEigenLdlt,  // Eigen's simplicial LDL^T, the fallback
    kPcg,        // conjugate gradients with incomplete Cholesky (CreatePcgSolver)
    kAmg,        // PETSc conjugate gradients with algebraic multigrid (CreateAmgSolver)
    kMumps,      // PETSc + MUMPS parallel sparse LDL^T (CreateMumpsSolver)
  };
  Kind kind = Kind::kAuto;
  LinearSolverSettings settings;
  // Set by the analysis: the unknowns' nodes and coordinates, for AMG. Not
  // owned; may be null (AMG then aggregates scalar unknowns).
  const UnknownLayout* layout = nullptr;
  // Set by the caller to stop an iterative solve early (the analysis passes
  // SolveOptions::cancel): PCG and AMG look at it every iteration and their
  // Solve returns Status::Cancelled. Direct factorisations cannot be
  // interrupted: CHOLMOD's, MUMPS's and Eigen's run to the end once started
  // (seconds to minutes on a large mesh) and the flag is seen after them.
  // Not owned; may be null.
  const std::atomic<bool>* cancel = nullptr;
  // The threads a factorisation may use (CHOLMOD's and its BLAS's):
  // SolveScene sets the solve's.
  ThreadContext threads;

  // "AUTO", "CHOLMOD", "EIGEN_LDLT", "PCG", "AMG" or "MUMPS": the scene's
  // name for the kind.
  const char* KindName() const;
};

std::unique_ptr<LinearSolver> CreateLinearSolver(const LinearSolverOptions& options);

// A positive definite matrix has a positive diagonal: the check the
// iterative solvers make before iterating (an incomplete factorisation or a
// multigrid would shift or smooth past such a matrix and CG would wander).
// Status::Numerical names the first entry that is not positive and finite.
Status CheckPositiveDiagonal(const Eigen::SparseMatrix<double>& a);

// The backends (linear/cholmod_solver.cc, linear/eigen_ldlt_solver.cc,
// linear/pcg_solver.cc).
// CHOLMOD's OpenMP teams and its BLAS's threads are bounded by `threads`
// during each factorisation and solve (LibraryThreadScope).
std::unique_ptr<LinearSolver> CreateCholmodSolver(const ThreadContext& threads);
std::unique_ptr<LinearSolver> CreateEigenLdltSolver();
// Iterative: conjugate gradients with an incomplete Cholesky preconditioner,
// aiming at ||b - A x|| / ||b|| <= 1e-12 in at most max(1000, 10 n)
// iterations. Factorize computes the preconditioner (and keeps a copy of
// `a`); Solve fails with Status::Numerical, naming the iterations and the
// residual reached, when the true residual ends above 1e-8. After a solve,
// Name() carries its iteration count and residual. A set `*cancel` (may be
// null) ends a solve within an iteration with Status::Cancelled.
std::unique_ptr<LinearSolver> CreatePcgSolver(const std::atomic<bool>* cancel = nullptr);

// PETSc's conjugate gradients preconditioned by algebraic multigrid
// (settings.preconditioner), to settings.relative_tolerance in at most
// settings.max_iterations. Factorize builds the multigrid hierarchy (reusing
// the prolongation while the pattern stays: Newton's tangents); Solve checks
// the true residual and, when the iteration did not converge, redoes the
// solve with MUMPS if the system has at most
// settings.fallback_direct_max_unknowns unknowns, else fails with
// Status::Numerical naming the iterations and the residual reached. Name()
// carries the iteration counts and fallbacks.
std::unique_ptr<LinearSolver> CreateAmgSolver(const LinearSolverSettings& settings,
                                              const UnknownLayout* layout,
                                              const std::atomic<bool>* cancel);
// The PRESSURE_SCHUR preconditioner's solver (CreateAmgSolver gives it for
// that setting): FactorizeSplit takes the displacement-pressure form of
// VolumetricSplit, solved by flexible GMRES preconditioned by the upper
// block-triangular factor [A b^T; 0 S] of [A b^T; b -1/w], with one GAMG
// V-cycle for A^-1 and a diagonal for the Schur complement
// S = -1/w - b A^-1 b^T: the pressure mass matrix over the shear modulus,
// spectrally equivalent to b A^-1 b^T for an inf-sup stable pair, once A
// also holds a share of the volumetric stiffness (the "grad-div" term; see
// pressure_schur_solver.cc). The constraints shape only the preconditioner:
// A is K less their term, so the operator is K's whatever they are. The
// tolerance and the checks are AMG's, on the true residual of K; a solve
// that does not converge (within settings.max_iterations, or three times
// the iterations of the last converged solve) is redone by MUMPS on K below
// settings.fallback_direct_max_unknowns, else fails naming the iterations
// and the residual. A tangent given without a split goes to GAMG.
std::unique_ptr<LinearSolver> CreatePressureSchurSolver(const LinearSolverSettings& settings,
                                                        const UnknownLayout* layout,
                                                        const std::atomic<bool>* cancel);
// PETSc's interface to MUMPS, the multifrontal sparse direct solver, as a
// symmetric LDL^T: the matrix's inertia tells a tangent that is not positive
// definite (Status::Numerical), as CHOLMOD's failed pivot does.
// With a `layout` (not owned; may be null) it factorises the system
// expanded to whole nodes, split between MPI ranks by node as AMG's is (and
// then gives OwnNodes); without one, an even share of the unknowns per rank.
std::unique_ptr<LinearSolver> CreateMumpsSolver(const UnknownLayout* layout = nullptr);
// AUTO: on the first Factorize, CHOLMOD when the factor its symbolic
// analysis predicts takes at most settings.auto_direct_max_factor_mb, else
// AMG; Name() says which and why.
std::unique_ptr<LinearSolver> CreateAutoSolver(const LinearSolverOptions& options);

// CHOLMOD's symbolic analysis of `a` (lower triangle read): the memory its
// supernodal factor would take [bytes] and the factorisation's flops,
// without computing it. Seconds on a million unknowns.
struct FactorPrediction {
  double bytes = 0;
  double flops = 0;
};
Status PredictCholmodFactor(const Eigen::SparseMatrix<double>& a, const ThreadContext& threads,
                            FactorPrediction* prediction);

}  // namespace pba
