// The PETSc backends shared by the ranks of an MPI job: run under
// `mpirun -np 2` (tests/unit/solver/CMakeLists.txt), as a user's
// `mpirun -np 2 pba-solve` is. Each rank hands PETSc its own rows, of the
// whole system or of the share of it a partitioned assembly leaves it;
// every rank must end with the answer one process gets (CHOLMOD's,
// computed on each rank alone), and ranks that hold different systems
// must stop, never mix them.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "common/linear_systems.h"
#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_runtime.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

using testing::AssembleBlock;
using testing::BlockSystem;
using testing::ShiftedLaplacian;
using testing::SoftBlock;

void Assemble(double element_size_mm, BlockSystem* out) {
  const Status assembled = AssembleBlock(element_size_mm, 0.45, out);
  ASSERT_TRUE(assembled.ok()) << assembled.ToString();
}

double RelativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

// Factorises `k` and solves for the block's load; the status of either.
Status FactorizeAndSolve(LinearSolver* solver, const Eigen::SparseMatrix<double>& k,
                         const BlockSystem& block, Eigen::VectorXd* x) {
  PBA_RETURN_IF_ERROR(solver->Factorize(k));
  return solver->Solve(block.system.rhs, x);
}

// AMG with `settings` (to a relative tolerance of 1e-12), with the
// unknowns' layout or without, across the ranks: CHOLMOD's answer to 1e-8.
void ExpectAmgGivesTheDirectAnswer(double element_size_mm, LinearSolverSettings settings,
                                   bool with_layout) {
  BlockSystem block;
  Assemble(element_size_mm, &block);
  settings.relative_tolerance = 1e-12;
  const auto amg = CreateAmgSolver(settings, with_layout ? &block.layout : nullptr, nullptr);
  Eigen::VectorXd x;
  const Status solved = FactorizeAndSolve(amg.get(), block.system.k, block, &x);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_LT(RelativeDifference(x, block.direct), 1e-8);
}

TEST(PetscRanks, TwoRanksAreRunning) {
  const ProcessRanks ranks = CurrentRanks();
  EXPECT_EQ(ranks.size, 2);
  EXPECT_GE(ranks.on_node, 1);
}

TEST(PetscRanks, GamgSharedByTwoRanksGivesTheDirectAnswer) {
  BlockSystem block;
  Assemble(2.0, &block);
  LinearSolverSettings settings;
  settings.relative_tolerance = 1e-12;
  const auto amg = CreateAmgSolver(settings, &block.layout, nullptr);
  Eigen::VectorXd x;
  const Status solved = FactorizeAndSolve(amg.get(), block.system.k, block, &x);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_LT(RelativeDifference(x, block.direct), 1e-8);
  EXPECT_NE(amg->Name().find("on 2 MPI ranks"), std::string::npos) << amg->Name();
  EXPECT_EQ(amg->Name().find("redone by MUMPS"), std::string::npos) << amg->Name();
  // Newton's next tangent: same pattern, new values (the lagged hierarchy).
  const Eigen::SparseMatrix<double> stiffer = 2.0 * block.system.k;
  ASSERT_TRUE(FactorizeAndSolve(amg.get(), stiffer, block, &x).ok());
  EXPECT_LT(RelativeDifference(2.0 * x, block.direct), 1e-8);
}

TEST(PetscRanks, BoomerAmgSharedByTwoRanksGivesTheDirectAnswer) {
  LinearSolverSettings settings;
  settings.preconditioner = LinearSolverSettings::Preconditioner::kBoomerAmg;
  ExpectAmgGivesTheDirectAnswer(2.5, settings, true);
}

TEST(PetscRanks, ScalarAggregationWithoutLayoutSplitsTheUnknowns) {
  ExpectAmgGivesTheDirectAnswer(3.0, LinearSolverSettings(), false);
}

TEST(PetscRanks, MumpsSharedByTwoRanksIsExactAndRefactorises) {
  BlockSystem block;
  Assemble(2.5, &block);
  const auto mumps = CreateMumpsSolver();
  Eigen::VectorXd x;
  ASSERT_TRUE(FactorizeAndSolve(mumps.get(), block.system.k, block, &x).ok());
  EXPECT_LT(RelativeDifference(x, block.direct), 1e-11);
  EXPECT_NE(mumps->Name().find("on 2 MPI ranks"), std::string::npos) << mumps->Name();
  const Eigen::SparseMatrix<double> stiffer = 4.0 * block.system.k;
  ASSERT_TRUE(FactorizeAndSolve(mumps.get(), stiffer, block, &x).ok());
  EXPECT_LT(RelativeDifference(4.0 * x, block.direct), 1e-11);
}

TEST(PetscRanks, MumpsInertiaAcrossRanksTellsAnIndefiniteMatrix) {
  // Eigenvalues 2 - shift - 2 cos(k pi / 201): shift 0.5 makes about a
  // third of them negative, whichever rank holds their rows.
  const auto mumps = CreateMumpsSolver();
  const Status indefinite = mumps->Factorize(ShiftedLaplacian(200, 0.5));
  EXPECT_EQ(indefinite.code(), Status::Code::kNumerical) << indefinite.ToString();
  EXPECT_NE(indefinite.message().find("negative"), std::string::npos) << indefinite.message();
  const Status definite = mumps->Factorize(ShiftedLaplacian(200, -0.1));
  EXPECT_TRUE(definite.ok()) << definite.ToString();
}

TEST(PetscRanks, AutoTakesMumpsWhereOneProcessWouldTakeCholmod) {
  BlockSystem block;
  Assemble(3.0, &block);
  LinearSolverOptions options;
  options.layout = &block.layout;
  const auto solver = CreateLinearSolver(options);
  Eigen::VectorXd x;
  ASSERT_TRUE(FactorizeAndSolve(solver.get(), block.system.k, block, &x).ok());
  EXPECT_LT(RelativeDifference(x, block.direct), 1e-11);
  EXPECT_NE(solver->Name().find("MUMPS"), std::string::npos) << solver->Name();
  EXPECT_NE(solver->Name().find("AUTO"), std::string::npos) << solver->Name();
  // Beyond the budget, AMG across the ranks.
  options.settings.auto_direct_max_factor_mb = 1;
  const auto iterative = CreateLinearSolver(options);
  ASSERT_TRUE(FactorizeAndSolve(iterative.get(), block.system.k, block, &x).ok());
  EXPECT_NE(iterative->Name().find("GAMG"), std::string::npos) << iterative->Name();
}

// The matrix a partitioned assembly leaves a rank: the columns of its own
// nodes, nothing else.
Eigen::SparseMatrix<double> OwnColumns(const Eigen::SparseMatrix<double>& k,
                                       const UnknownLayout& layout, const std::vector<char>& own) {
  Eigen::SparseMatrix<double> part = k;
  part.prune([&](Eigen::Index, Eigen::Index col, double) {
    return own[layout.dof_of_unknown[col] / 3] != 0;
  });
  return part;
}

TEST(PetscRanks, SolversGivenOnlyTheirRanksColumnsGiveTheWholeAnswer) {
  BlockSystem block;
  Assemble(2.5, &block);
  LinearSolverSettings settings;
  settings.relative_tolerance = 1e-12;
  const std::unique_ptr<LinearSolver> solvers[] = {
      CreateAmgSolver(settings, &block.layout, nullptr), CreateMumpsSolver(&block.layout)};
  for (const auto& solver : solvers) {
    SCOPED_TRACE(solver->Name());
    const std::vector<char>* own = solver->OwnNodes();
    ASSERT_NE(own, nullptr);
    ASSERT_EQ(static_cast<int>(own->size()), block.layout.num_nodes());
    // The ranks share the nodes out, each some.
    double mine = std::count(own->begin(), own->end(), 1), all = mine;
    ASSERT_TRUE(SumOverRanks(&all, 1).ok());
    EXPECT_GT(mine, 0);
    EXPECT_EQ(all, block.layout.num_nodes());
    const Eigen::SparseMatrix<double> part = OwnColumns(block.system.k, block.layout, *own);
    EXPECT_LT(part.nonZeros(), block.system.k.nonZeros());
    Eigen::VectorXd x;
    const Status solved = FactorizeAndSolve(solver.get(), part, block, &x);
    ASSERT_TRUE(solved.ok()) << solved.ToString();
    EXPECT_LT(RelativeDifference(x, block.direct), 1e-8);
  }
  // A diagonal entry that is not positive in one rank's columns: every
  // rank stops, naming it.
  const std::vector<char>& own = *solvers[0]->OwnNodes();
  Eigen::SparseMatrix<double> part = OwnColumns(block.system.k, block.layout, own);
  Eigen::Index first = -1;
  for (Eigen::Index j = 0; j < part.cols() && first < 0; ++j) {
    if (own[block.layout.dof_of_unknown[j] / 3]) first = j;
  }
  double named = 0;
  if (CurrentRanks().rank == 1) {
    part.coeffRef(first, first) = -1;
    named = static_cast<double>(first);
  }
  ASSERT_TRUE(SumOverRanks(&named, 1).ok());
  const auto amg = CreateAmgSolver(settings, &block.layout, nullptr);
  const Status status = amg->Factorize(part);
  EXPECT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
  EXPECT_NE(status.message().find(Format("diagonal entry %d is -1", static_cast<int>(named))),
            std::string::npos)
      << status.message();
}

TEST(PetscRanks, RanksHoldingDifferentMatricesStopInsteadOfMixingThem) {
  BlockSystem block;
  Assemble(3.0, &block);
  const double scale = 1.0 + CurrentRanks().rank;  // 1 on rank 0, 2 on rank 1
  // Whole matrices (no layout) are compared whole.
  const auto mumps_whole = CreateMumpsSolver();
  Status status = mumps_whole->Factorize(scale * block.system.k);
  EXPECT_EQ(status.code(), Status::Code::kInternal) << status.ToString();
  EXPECT_NE(status.message().find("different stiffness matrices"), std::string::npos)
      << status.message();
  // A layout's systems, of which a rank may hold only its columns, by their
  // meshes: rank 1's is moved.
  UnknownLayout moved = block.layout;
  for (double& c : moved.coordinates) c *= scale;
  const auto amg = CreateAmgSolver(LinearSolverSettings(), &moved, nullptr);
  status = amg->Factorize(block.system.k);
  EXPECT_EQ(status.code(), Status::Code::kInternal) << status.ToString();
  EXPECT_NE(status.message().find("different meshes"), std::string::npos) << status.message();
  // The same matrix but different right-hand sides.
  const auto mumps = CreateMumpsSolver();
  ASSERT_TRUE(mumps->Factorize(block.system.k).ok());
  Eigen::VectorXd x;
  status = mumps->Solve(scale * block.system.rhs, &x);
  EXPECT_EQ(status.code(), Status::Code::kInternal) << status.ToString();
  EXPECT_NE(status.message().find("right-hand sides"), std::string::npos) << status.message();
}

TEST(PetscRanks, ScenesWithoutASharedSolveAreRefusedOnRanks) {
  SceneSpec scene = SoftBlock(3.0, AnalysisSpec::LinearSolver::kCholmod);
  // ValidateScene knows it runs on two ranks.
  Status status = ValidateScene(scene);
  EXPECT_EQ(status.field(), "analysis.linear_solver") << status.ToString();
  EXPECT_NE(status.message().find("AUTO, AMG or MUMPS"), std::string::npos) << status.message();
  scene.analysis.linear_solver = AnalysisSpec::LinearSolver::kMumps;
  EXPECT_TRUE(ValidateScene(scene).ok()) << ValidateScene(scene).ToString();
}

}  // namespace
}  // namespace pba

// Its own main: MPI starts before the tests, and only rank 0 prints them
// (a failure on rank 1 still fails the run through its exit code).
int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  pba::SolveRanks ranks;
  const pba::Status joined = pba::JoinRanks(&ranks);
  if (!joined.ok() || ranks.size != 2) {
    std::fprintf(stderr, "petsc_mpi_test: run it as mpirun -np 2 (%s, %d rank(s))\n",
                 joined.ToString().c_str(), ranks.size);
    return 1;
  }
  if (ranks.rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int result = RUN_ALL_TESTS();
  if (result != 0) std::fprintf(stderr, "petsc_mpi_test: failures on rank %d\n", ranks.rank);
  return result;
}
