// The PETSc backends (AMG under conjugate gradients, MUMPS) and AUTO: they
// agree with CHOLMOD on assembled stiffnesses and through whole solves; a
// matrix that is not positive definite, an iteration that does not
// converge and a cancel each end in the Status that says so, never in an
// unconverged answer passed on as converged.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/SparseCore>
#include <atomic>
#include <string>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "common/linear_systems.h"
#include "common/scene_builders.h"
#include "core/format.h"
#include "linear/linear_solver.h"
#include "linear/petsc_runtime.h"
#include "material/linear_elastic.h"
#include "pba/solve.h"
#include "scene/model_builder.h"
#include "scene/problem.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::AssembleBlock;
using testing::AssembleSoftTissue;
using testing::BlockSystem;
using testing::Condition;
using testing::NeoHookeanCube;
using testing::ShiftedLaplacian;
using testing::SoftBlock;

void Assemble(double element_size_mm, double poisson, BlockSystem* out) {
  const Status assembled = AssembleBlock(element_size_mm, poisson, out);
  ASSERT_TRUE(assembled.ok()) << assembled.ToString();
}

double RelativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

double Residual(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& x,
                const Eigen::VectorXd& b) {
  return (a * x - b).norm() / b.norm();
}

// Iterations of the last solve, read from the name ("... last: N iterations").
int LastIterations(const std::string& name) {
  const std::size_t at = name.find("last: ");
  if (at == std::string::npos) return -1;
  return std::stoi(name.substr(at + 6));
}

TEST(AmgSolver, GamgWithRigidBodyModesMatchesCholmod) {
  BlockSystem b;
  Assemble(2.0, 0.45, &b);
  ASSERT_GT(b.system.k.rows(), 5000);
  LinearSolverSettings settings;
  const auto amg = CreateAmgSolver(settings, &b.layout, nullptr);
  Eigen::VectorXd x;
  Status status = amg->Factorize(b.system.k);
  ASSERT_TRUE(status.ok()) << status.ToString();
  status = amg->Solve(b.system.rhs, &x);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(Residual(b.system.k, x, b.system.rhs), 10 * settings.relative_tolerance);
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
  const std::string name = amg->Name();
  EXPECT_NE(name.find("GAMG"), std::string::npos) << name;
  EXPECT_EQ(name.find("MUMPS"), std::string::npos) << name;  // converged on its own
  // Multigrid with the rigid-body modes: tens of iterations, where
  // incomplete Cholesky needs hundreds on this block.
  const int with_modes = LastIterations(name);
  EXPECT_GT(with_modes, 0) << name;
  EXPECT_LT(with_modes, 80) << name;

  // Without the layout, scalar aggregation still converges, more slowly.
  const auto scalar = CreateAmgSolver(settings, nullptr, nullptr);
  ASSERT_TRUE(scalar->Factorize(b.system.k).ok());
  ASSERT_TRUE(scalar->Solve(b.system.rhs, &x).ok());
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
  EXPECT_NE(scalar->Name().find("scalar aggregation"), std::string::npos) << scalar->Name();
  EXPECT_GT(LastIterations(scalar->Name()), with_modes) << scalar->Name();
}

TEST(AmgSolver, BoomerAmgMatchesCholmod) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  LinearSolverSettings settings;
  settings.preconditioner = LinearSolverSettings::Preconditioner::kBoomerAmg;
  const auto amg = CreateAmgSolver(settings, &b.layout, nullptr);
  Eigen::VectorXd x;
  ASSERT_TRUE(amg->Factorize(b.system.k).ok());
  const Status status = amg->Solve(b.system.rhs, &x);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
  EXPECT_NE(amg->Name().find("BoomerAMG"), std::string::npos) << amg->Name();
  EXPECT_EQ(amg->Name().find("MUMPS"), std::string::npos) << amg->Name();
}

TEST(AmgSolver, RefactorisesNewValuesOnTheSamePatternAndKeepsItsMatrix) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  const auto amg = CreateAmgSolver(LinearSolverSettings(), &b.layout, nullptr);
  Eigen::VectorXd x;
  ASSERT_TRUE(amg->Factorize(b.system.k).ok());
  ASSERT_TRUE(amg->Solve(b.system.rhs, &x).ok());
  {
    // Twice as stiff: half the displacement. The caller's matrix is gone
    // before the solve (Newton's modified step).
    Eigen::SparseMatrix<double> stiffer = 2 * b.system.k;
    ASSERT_TRUE(amg->Factorize(stiffer).ok());
  }
  ASSERT_TRUE(amg->Solve(b.system.rhs, &x).ok());
  EXPECT_LT(RelativeDifference(x, 0.5 * b.direct), 1e-7);
  const auto other = amg->NewOfSameKind();
  ASSERT_TRUE(other->Factorize(b.system.k).ok());
  ASSERT_TRUE(other->Solve(b.system.rhs, &x).ok());
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
}

// Newton's next tangent reuses the last multigrid hierarchy; when that one
// no longer serves (here: the next matrix is far less compressible and the
// iteration limit leaves no room), the solve is redone once with a
// hierarchy built for the new matrix, not handed to MUMPS.
TEST(AmgSolver, ALaggedHierarchyThatFailsIsRebuiltBeforeAnyFallback) {
  BlockSystem compressible, stiff;
  Assemble(2.5, 0.3, &compressible);
  Assemble(2.5, 0.49, &stiff);
  ASSERT_EQ(compressible.system.k.nonZeros(), stiff.system.k.nonZeros());
  Eigen::VectorXd x;
  // What a fresh hierarchy needs for the stiff matrix.
  const auto fresh = CreateAmgSolver(LinearSolverSettings(), &stiff.layout, nullptr);
  ASSERT_TRUE(fresh->Factorize(stiff.system.k).ok());
  ASSERT_TRUE(fresh->Solve(stiff.system.rhs, &x).ok());
  const int needed = LastIterations(fresh->Name());
  ASSERT_GT(needed, 0);

  LinearSolverSettings settings;
  settings.max_iterations = needed + 2;
  settings.fallback_direct_max_unknowns = 0;
  const auto amg = CreateAmgSolver(settings, &compressible.layout, nullptr);
  ASSERT_TRUE(amg->Factorize(compressible.system.k).ok());
  ASSERT_TRUE(amg->Solve(compressible.system.rhs, &x).ok());
  ASSERT_NE(amg->Name().find("1 multigrid setups"), std::string::npos) << amg->Name();
  ASSERT_TRUE(amg->Factorize(stiff.system.k).ok());  // reuses the hierarchy
  const Status status = amg->Solve(stiff.system.rhs, &x);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(RelativeDifference(x, stiff.direct), 1e-7);
  EXPECT_NE(amg->Name().find("2 multigrid setups"), std::string::npos) << amg->Name();
  EXPECT_EQ(amg->Name().find("MUMPS"), std::string::npos) << amg->Name();
}

TEST(AmgSolver, NotConvergedIsRedoneByMumpsOrRefused) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  LinearSolverSettings settings;
  settings.max_iterations = 2;  // far too few
  const auto amg = CreateAmgSolver(settings, &b.layout, nullptr);
  Eigen::VectorXd x;
  ASSERT_TRUE(amg->Factorize(b.system.k).ok());
  Status status = amg->Solve(b.system.rhs, &x);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-9);
  EXPECT_NE(amg->Name().find("1 redone by MUMPS"), std::string::npos) << amg->Name();

  // No fallback allowed: the solve fails and says why.
  settings.fallback_direct_max_unknowns = 0;
  const auto strict = CreateAmgSolver(settings, &b.layout, nullptr);
  ASSERT_TRUE(strict->Factorize(b.system.k).ok());
  status = strict->Solve(b.system.rhs, &x);
  ASSERT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
  EXPECT_NE(status.message().find("did not converge: 2 iterations"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("fallback_direct_max_unknowns"), std::string::npos)
      << status.message();
}

TEST(AmgSolver, IndefiniteMatrixEndsNamingItNotInAnAnswer) {
  // Positive diagonal, about half the eigenvalues negative: CG cannot
  // converge, and MUMPS, the fallback, finds the negative pivots.
  const auto amg = CreateAmgSolver(LinearSolverSettings(), nullptr, nullptr);
  Eigen::VectorXd x;
  ASSERT_TRUE(amg->Factorize(ShiftedLaplacian(200, 1.9)).ok());
  const Status status = amg->Solve(Eigen::VectorXd::Ones(200), &x);
  ASSERT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
  EXPECT_NE(status.message().find("did not converge"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("not positive definite"), std::string::npos) << status.message();
  // A negative diagonal is refused before any iteration.
  const Status negative = amg->Factorize(ShiftedLaplacian(50, 3.0));
  EXPECT_EQ(negative.code(), Status::Code::kNumerical);
  EXPECT_NE(negative.message().find("diagonal entry"), std::string::npos) << negative.message();
  EXPECT_FALSE(amg->Solve(Eigen::VectorXd::Ones(50), &x).ok());
}

TEST(AmgSolver, CancelEndsTheIteration) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  std::atomic<bool> cancel{true};
  LinearSolverOptions options;
  options.kind = LinearSolverOptions::Kind::kAmg;
  options.layout = &b.layout;
  options.cancel = &cancel;
  const auto amg = CreateLinearSolver(options);
  ASSERT_TRUE(amg->Factorize(b.system.k).ok());
  Eigen::VectorXd x;
  const Status cancelled = amg->Solve(b.system.rhs, &x);
  EXPECT_EQ(cancelled.code(), Status::Code::kCancelled) << cancelled.ToString();
  cancel = false;
  const Status solved = amg->Solve(b.system.rhs, &x);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
}

TEST(MumpsSolver, MatchesCholmodAndTellsIndefiniteAndSingular) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  const auto mumps = CreateMumpsSolver();
  Eigen::VectorXd x;
  Status status = mumps->Factorize(b.system.k);
  ASSERT_TRUE(status.ok()) << status.ToString();
  ASSERT_TRUE(mumps->Solve(b.system.rhs, &x).ok());
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-10);
  EXPECT_NE(mumps->Name().find("MUMPS"), std::string::npos);

  status = mumps->Factorize(ShiftedLaplacian(100, 1.0));
  ASSERT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
  EXPECT_NE(status.message().find("negative"), std::string::npos) << status.message();
  EXPECT_FALSE(mumps->Solve(Eigen::VectorXd::Ones(100), &x).ok());

  // A body held nowhere: six rigid-body modes, a singular matrix.
  SceneSpec scene = SoftBlock(5.0, AnalysisSpec::LinearSolver::kMumps);
  scene.boundary_conditions.clear();
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  LinearSystem system;
  ASSERT_TRUE(AssembleSoftTissue(model, 0.45, &system).ok());
  status = mumps->Factorize(system.k);
  EXPECT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
}

TEST(AutoSolver, ChoosesBySizeAndSaysWhy) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  LinearSolverOptions options;  // AUTO is the default
  ASSERT_EQ(options.kind, LinearSolverOptions::Kind::kAuto);
  options.layout = &b.layout;
  Eigen::VectorXd x;
  const auto small = CreateLinearSolver(options);
  ASSERT_TRUE(small->Factorize(b.system.k).ok());
  ASSERT_TRUE(small->Solve(b.system.rhs, &x).ok());
  EXPECT_EQ(x, b.direct);  // CHOLMOD itself
  EXPECT_EQ(small->Name().rfind("CHOLMOD", 0), 0u) << small->Name();
  EXPECT_NE(small->Name().find("AUTO: " + std::to_string(b.system.k.rows()) + " unknowns"),
            std::string::npos)
      << small->Name();
  // The default budget: a quarter of the memory the solve may take.
  EXPECT_NE(small->Name().find("MB (a quarter of the "), std::string::npos) << small->Name();
  EXPECT_NE(small->Name().find(" GiB the solve may take)"), std::string::npos) << small->Name();
  // The prediction is CHOLMOD's own: between the matrix's lower triangle
  // and a dense triangle.
  FactorPrediction prediction;
  ASSERT_TRUE(PredictCholmodFactor(b.system.k, ThreadContext(), &prediction).ok());
  const double n = static_cast<double>(b.system.k.rows());
  EXPECT_GT(prediction.bytes, 8.0 * (b.system.k.nonZeros() + n) / 2);
  EXPECT_LT(prediction.bytes, 8.0 * n * n);
  EXPECT_GT(prediction.flops, 0);

  // A budget the scene sets, below this factor.
  ASSERT_GT(prediction.bytes, 1024.0 * 1024.0);
  options.settings.auto_direct_max_factor_mb = 1;
  const auto large = CreateLinearSolver(options);
  ASSERT_TRUE(large->Factorize(b.system.k).ok());
  ASSERT_TRUE(large->Solve(b.system.rhs, &x).ok());
  EXPECT_LT(RelativeDifference(x, b.direct), 1e-7);
  EXPECT_NE(large->Name().find("GAMG"), std::string::npos) << large->Name();
  EXPECT_NE(large->Name().find("MB > 1 MB (linear_solver_options.auto_direct_max_factor_mb)"),
            std::string::npos)
      << large->Name();
}

// AUTO's default budget follows what the process may take: under an
// address-space limit below the machine's memory (pba-server's
// --solver-memory), a quarter of that limit.
TEST(AutoSolver, DefaultBudgetIsAQuarterOfTheMemoryTheSolveMayTake) {
  BlockSystem b;
  Assemble(2.5, 0.45, &b);
  const double physical =
      static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  ASSERT_GT(physical, 0);
  EXPECT_DOUBLE_EQ(SolveMemoryBytes(), physical);
  struct rlimit saved {};
  ASSERT_EQ(::getrlimit(RLIMIT_AS, &saved), 0);
  // Half the machine, but not below what this test process has mapped.
  const rlim_t limit = static_cast<rlim_t>(physical / 2);
  if (saved.rlim_max != RLIM_INFINITY && saved.rlim_max < limit) GTEST_SKIP();
  struct rlimit lowered = saved;
  lowered.rlim_cur = limit;
  ASSERT_EQ(::setrlimit(RLIMIT_AS, &lowered), 0);
  const double memory = SolveMemoryBytes();
  LinearSolverOptions options;
  options.layout = &b.layout;
  const auto solver = CreateLinearSolver(options);
  const Status status = solver->Factorize(b.system.k);
  ASSERT_EQ(::setrlimit(RLIMIT_AS, &saved), 0);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_DOUBLE_EQ(memory, static_cast<double>(limit));
  const std::string budget = Format("<= %.0f MB (a quarter of the %.1f GiB the solve may take)",
                                    static_cast<double>(limit) / 4 / (1024.0 * 1024.0),
                                    static_cast<double>(limit) / (1 << 30));
  EXPECT_NE(solver->Name().find(budget), std::string::npos) << solver->Name();
}

Eigen::Map<const Eigen::VectorXd> Displacement(const Solution& s) {
  return {s.displacement_mm.data(), static_cast<Eigen::Index>(s.displacement_mm.size())};
}

TEST(LinearSolverScenes, AmgAndMumpsSolveTheLinearBlockAsCholmodDoes) {
  Solution cholmod, amg, mumps;
  ASSERT_TRUE(
      SolveScene(SoftBlock(2.5, AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod)
          .ok());
  Status status =
      SolveScene(SoftBlock(2.5, AnalysisSpec::LinearSolver::kAmg), SolveOptions(), &amg);
  ASSERT_TRUE(status.ok()) << status.ToString();
  status = SolveScene(SoftBlock(2.5, AnalysisSpec::LinearSolver::kMumps), SolveOptions(), &mumps);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(RelativeDifference(Displacement(amg), Displacement(cholmod)), 1e-7);
  EXPECT_LT(RelativeDifference(Displacement(mumps), Displacement(cholmod)), 1e-10);
  EXPECT_NE(amg.summary.linear_solver.find("GAMG"), std::string::npos) << amg.summary.linear_solver;
  // The options as they ran are in the summary.
  bool echoed = false;
  for (const auto& [name, value] : amg.summary.options) {
    if (name == "analysis.linear_solver_options.relative_tolerance") echoed = value == "1e-10";
  }
  EXPECT_TRUE(echoed);
}

TEST(LinearSolverScenes, NonlinearNeoHookeanWithAmgMatchesCholmod) {
  const auto scene = [](AnalysisSpec::LinearSolver solver) {
    // TET4_ANP, K / mu = 100, pressed 20 % in five increments.
    return NeoHookeanCube(ElementType::kDefault, 2.0, 1e5, 2.0, 0, solver);
  };
  Solution cholmod, amg;
  ASSERT_TRUE(
      SolveScene(scene(AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod).ok());
  const Status status = SolveScene(scene(AnalysisSpec::LinearSolver::kAmg), SolveOptions(), &amg);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_LT(amg.summary.relative_residual, 1e-8);
  // Both converged to Newton's tolerance on the same equations.
  EXPECT_LT(RelativeDifference(Displacement(amg), Displacement(cholmod)), 1e-6);
  EXPECT_NEAR(amg.summary.strain_energy_j, cholmod.summary.strain_energy_j,
              1e-7 * cholmod.summary.strain_energy_j);
}

// Nearly incompressible (K / mu = 1e3) and pressed 10 %: Newton meets
// tangents that are not positive definite far from equilibrium. CHOLMOD
// tells them by a failed factorisation, CG by negative curvature during
// the solve; either way Newton takes the same substitute steps, so AMG
// follows CHOLMOD's path (same increments and iterations) to the same
// answer, and its lagged multigrid is set up fewer times than it solves.
TEST(LinearSolverScenes, IndefiniteTangentsTakeTheSameNewtonPathWithAmg) {
  const auto scene = [](AnalysisSpec::LinearSolver solver) {
    return NeoHookeanCube(ElementType::kTet10, 2.5, 1e6, 1.0, 2, solver);
  };
  Solution cholmod, amg;
  ASSERT_TRUE(
      SolveScene(scene(AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod).ok());
  const Status status = SolveScene(scene(AnalysisSpec::LinearSolver::kAmg), SolveOptions(), &amg);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(amg.summary.newton_iterations, cholmod.summary.newton_iterations);
  bool substituted = false;
  for (const std::string& note : amg.summary.notes) {
    substituted = substituted || note.find("not positive definite") != std::string::npos;
    EXPECT_EQ(note.find("cut back"), std::string::npos) << note;
  }
  EXPECT_TRUE(substituted);
  EXPECT_LT(RelativeDifference(Displacement(amg), Displacement(cholmod)), 1e-6);
  const std::string& name = amg.summary.linear_solver;
  const std::size_t solves = name.find(" solves");
  const std::size_t setups = name.find(" multigrid setups");
  ASSERT_NE(setups, std::string::npos) << name;
  const int solve_count = std::stoi(name.substr(name.rfind('(', solves) + 1));
  const int setup_count = std::stoi(name.substr(name.rfind(' ', setups - 1) + 1));
  EXPECT_LT(setup_count, solve_count) << name;
}

TEST(LinearSolverSettings, DefaultsAndValidationNameTheField) {
  LinearSolverSpec spec;
  LinearSolverSettings s = LinearSolverSettingsFromSpec(spec);
  EXPECT_TRUE(ValidateLinearSolverSettings(s).ok());
  EXPECT_EQ(s.relative_tolerance, LinearSolverSettings().relative_tolerance);
  spec.relative_tolerance = 0.5;
  Status status = ValidateLinearSolverSettings(LinearSolverSettingsFromSpec(spec));
  EXPECT_EQ(status.field(), "analysis.linear_solver_options.relative_tolerance");
  spec = LinearSolverSpec();
  spec.gamg_threshold = 0.0;  // explicitly zero is allowed
  EXPECT_EQ(LinearSolverSettingsFromSpec(spec).gamg_threshold, 0.0);
  spec.gamg_threshold = 0.9;
  status = ValidateLinearSolverSettings(LinearSolverSettingsFromSpec(spec));
  EXPECT_EQ(status.field(), "analysis.linear_solver_options.gamg_threshold");
  spec = LinearSolverSpec();
  spec.max_iterations = -3;
  status = ValidateLinearSolverSettings(LinearSolverSettingsFromSpec(spec));
  EXPECT_EQ(status.field(), "analysis.linear_solver_options.max_iterations");
  spec = LinearSolverSpec();
  spec.fallback_direct_max_unknowns = 0;  // never
  EXPECT_EQ(LinearSolverSettingsFromSpec(spec).fallback_direct_max_unknowns, 0);
}

}  // namespace
}  // namespace pba
