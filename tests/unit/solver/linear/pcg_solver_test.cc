// The conjugate-gradient backend: it agrees with CHOLMOD on an assembled
// linear-elastic stiffness and through whole linear and nonlinear solves,
// and a matrix that is not positive definite ends in an error that says so,
// not in NaN.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "assembly/assembler.h"
#include "common/linear_systems.h"
#include "common/scene_builders.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::AssembleSoftTissue;
using testing::Condition;
using testing::ShiftedLaplacian;
using testing::SoftBlock;

double RelativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

TEST(PcgSolver, MatchesCholmodOnAnAssembledStiffness) {
  const SceneSpec scene = SoftBlock(2.5, AnalysisSpec::LinearSolver::kPcg);
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  LinearSystem system;
  ASSERT_TRUE(AssembleSoftTissue(model, 0.45, &system).ok());
  ASSERT_GT(system.k.rows(), 1000);

  const auto cholmod = CreateCholmodSolver(ThreadContext());
  Eigen::VectorXd direct;
  ASSERT_TRUE(cholmod->Factorize(system.k).ok());
  ASSERT_TRUE(cholmod->Solve(system.rhs, &direct).ok());

  const auto pcg = CreatePcgSolver();
  Eigen::VectorXd iterative;
  const Status factorized = pcg->Factorize(system.k);
  ASSERT_TRUE(factorized.ok()) << factorized.ToString();
  const Status solved = pcg->Solve(system.rhs, &iterative);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_LT(RelativeDifference(iterative, direct), 1e-8);
  EXPECT_LT((system.k * iterative - system.rhs).norm() / system.rhs.norm(), 1e-11);
  // The name reports the solve.
  EXPECT_NE(pcg->Name().find("iterations"), std::string::npos) << pcg->Name();

  // A second right-hand side reuses the preconditioner; a fresh solver of
  // the same kind gives the same answer.
  const Eigen::VectorXd rhs2 = 2 * system.rhs;
  ASSERT_TRUE(pcg->Solve(rhs2, &iterative).ok());
  EXPECT_LT(RelativeDifference(iterative, 2 * direct), 1e-8);
  const auto other = pcg->NewOfSameKind();
  ASSERT_TRUE(other->Factorize(system.k).ok());
  ASSERT_TRUE(other->Solve(system.rhs, &iterative).ok());
  EXPECT_LT(RelativeDifference(iterative, direct), 1e-8);
}

TEST(PcgSolver, KeepsItsOwnCopyOfTheMatrix) {
  // Newton solves with an older factorisation after the matrix it came from
  // is gone.
  Eigen::SparseMatrix<double> a(3, 3);
  a.insert(0, 0) = 4;
  a.insert(1, 1) = 5;
  a.insert(2, 2) = 6;
  a.insert(0, 1) = a.insert(1, 0) = 1;
  a.makeCompressed();
  const auto pcg = CreatePcgSolver();
  {
    Eigen::SparseMatrix<double> copy = a;
    ASSERT_TRUE(pcg->Factorize(copy).ok());
  }
  const Eigen::VectorXd b = Eigen::Vector3d(1, 2, 3);
  Eigen::VectorXd x;
  ASSERT_TRUE(pcg->Solve(b, &x).ok());
  EXPECT_LT((a * x - b).norm(), 1e-12 * b.norm());
}

// A cancel is seen inside the CG iteration, not only between Newton
// iterations: a set flag ends a solve at once with Status::Cancelled, and a
// fresh solver of the same kind looks at the same flag. Cleared, the same
// solver solves.
TEST(PcgSolver, CancelEndsTheIteration) {
  const SceneSpec scene = SoftBlock(2.5, AnalysisSpec::LinearSolver::kPcg);
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  LinearSystem system;
  ASSERT_TRUE(AssembleSoftTissue(model, 0.45, &system).ok());
  std::atomic<bool> cancel{true};
  LinearSolverOptions options;
  options.kind = LinearSolverOptions::Kind::kPcg;
  options.cancel = &cancel;
  const auto pcg = CreateLinearSolver(options);
  ASSERT_TRUE(pcg->Factorize(system.k).ok());
  Eigen::VectorXd x;
  const Status cancelled = pcg->Solve(system.rhs, &x);
  EXPECT_EQ(cancelled.code(), Status::Code::kCancelled) << cancelled.ToString();
  EXPECT_NE(cancelled.message().find("conjugate gradients"), std::string::npos)
      << cancelled.message();
  const auto other = pcg->NewOfSameKind();
  ASSERT_TRUE(other->Factorize(system.k).ok());
  EXPECT_EQ(other->Solve(system.rhs, &x).code(), Status::Code::kCancelled);
  cancel = false;
  const Status solved = pcg->Solve(system.rhs, &x);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_LT((system.k * x - system.rhs).norm() / system.rhs.norm(), 1e-11);
}

TEST(PcgSolver, NegativeDiagonalIsNotPositiveDefinite) {
  const auto pcg = CreatePcgSolver();
  const Status status = pcg->Factorize(ShiftedLaplacian(50, 3.0));
  EXPECT_EQ(status.code(), Status::Code::kNumerical);
  EXPECT_NE(status.message().find("not positive definite"), std::string::npos) << status.message();
  // No solve with a failed factorisation.
  Eigen::VectorXd x;
  EXPECT_FALSE(pcg->Solve(Eigen::VectorXd::Ones(50), &x).ok());
}

TEST(PcgSolver, FarFromPositiveDefiniteFailsInThePreconditioner) {
  // Positive diagonal, but eigenvalues 0.1 - 2 cos(k pi / (n + 1)), about
  // half of them negative: no diagonal shift the incomplete factorisation
  // tries makes it positive definite.
  const auto pcg = CreatePcgSolver();
  const Status status = pcg->Factorize(ShiftedLaplacian(200, 1.9));
  EXPECT_EQ(status.code(), Status::Code::kNumerical);
  EXPECT_NE(status.message().find("incomplete Cholesky"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("CHOLMOD"), std::string::npos) << status.message();
}

TEST(PcgSolver, UnheldBodyEndsWithAClearErrorNotNan) {
  // The stiffness of a block held nowhere is singular (six rigid-body modes)
  // with a positive diagonal, so the preconditioner is computed; CG cannot
  // reach a load that the rigid modes would balance, and must say so after
  // its bounded number of iterations.
  SceneSpec scene = SoftBlock(5.0, AnalysisSpec::LinearSolver::kPcg);
  scene.boundary_conditions.clear();
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  LinearSystem system;
  ASSERT_TRUE(AssembleSoftTissue(model, 0.45, &system).ok());
  ASSERT_EQ(system.k.rows(), 3 * model.mesh.num_nodes());
  // A load along z on every node: the rigid translation takes it all.
  Eigen::VectorXd b = Eigen::VectorXd::Zero(system.k.rows());
  for (int n = 0; n < model.mesh.num_nodes(); ++n) b(3 * n + 2) = 1e-3;

  const auto pcg = CreatePcgSolver();
  Eigen::VectorXd x;
  Status status = pcg->Factorize(system.k);
  if (status.ok()) status = pcg->Solve(b, &x);
  ASSERT_EQ(status.code(), Status::Code::kNumerical);
  const std::string& message = status.message();
  EXPECT_EQ(message.find("nan"), std::string::npos) << message;
  EXPECT_NE(message.find("did not converge"), std::string::npos) << message;
  EXPECT_NE(message.find("iterations"), std::string::npos) << message;
  EXPECT_NE(message.find("CHOLMOD"), std::string::npos) << message;
}

TEST(PcgSolver, SolveSceneMatchesCholmod) {
  Solution cholmod, pcg;
  Status status =
      SolveScene(SoftBlock(2.5, AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod);
  ASSERT_TRUE(status.ok()) << status.ToString();
  status = SolveScene(SoftBlock(2.5, AnalysisSpec::LinearSolver::kPcg), SolveOptions(), &pcg);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(pcg.summary.linear_solver.rfind("conjugate gradient", 0), 0u)
      << pcg.summary.linear_solver;
  EXPECT_LT(pcg.summary.relative_residual, 1e-11);
  ASSERT_EQ(pcg.displacement_mm.size(), cholmod.displacement_mm.size());
  const Eigen::Map<const Eigen::VectorXd> u_pcg(pcg.displacement_mm.data(),
                                                pcg.displacement_mm.size());
  const Eigen::Map<const Eigen::VectorXd> u_direct(cholmod.displacement_mm.data(),
                                                   cholmod.displacement_mm.size());
  EXPECT_LT(RelativeDifference(u_pcg, u_direct), 1e-8);
  EXPECT_NEAR(pcg.summary.strain_energy_j, cholmod.summary.strain_energy_j,
              1e-8 * cholmod.summary.strain_energy_j);
}

TEST(PcgSolver, NonlinearNeoHookeanSceneMatchesCholmod) {
  // A 10 mm cube, bottom fixed, top pressed 1 mm (10 %), neo-Hookean with
  // K / mu = 100: compressible enough for CG to converge in few iterations.
  auto scene = [](AnalysisSpec::LinearSolver solver) {
    SceneSpec s;
    s.name = "neo-hookean cube";
    s.geometry.kind = GeometrySpec::Kind::kBox;
    s.geometry.box.size_mm = {10, 10, 10};
    s.mesh.element_size_mm = 2.5;
    s.material.kind = MaterialSpec::Kind::kNeoHookean;
    s.material.neo_hookean = {1000, 1e5};
    s.boundary_conditions = {Condition("bottom", K::kFixed),
                             Condition("top", K::kDisplacement, {0.0, 0.0, -1.0})};
    s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
    s.analysis.linear_solver = solver;
    return s;
  };
  Solution cholmod, pcg;
  Status status = SolveScene(scene(AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod);
  ASSERT_TRUE(status.ok()) << status.ToString();
  status = SolveScene(scene(AnalysisSpec::LinearSolver::kPcg), SolveOptions(), &pcg);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(pcg.summary.relative_residual, 1e-8);
  ASSERT_EQ(pcg.displacement_mm.size(), cholmod.displacement_mm.size());
  const Eigen::Map<const Eigen::VectorXd> u_pcg(pcg.displacement_mm.data(),
                                                pcg.displacement_mm.size());
  const Eigen::Map<const Eigen::VectorXd> u_direct(cholmod.displacement_mm.data(),
                                                   cholmod.displacement_mm.size());
  EXPECT_LT(RelativeDifference(u_pcg, u_direct), 1e-7);
  ASSERT_EQ(pcg.summary.reactions.size(), cholmod.summary.reactions.size());
  EXPECT_NEAR(pcg.summary.reactions[0].force_n[2], cholmod.summary.reactions[0].force_n[2],
              1e-7 * std::abs(cholmod.summary.reactions[0].force_n[2]));
}

}  // namespace
}  // namespace pba
