// How a finite-strain Newton step grows with the number of unknowns: a
// neo-Hookean cube, bottom fixed, top pressed 10 % in two increments, meshed
// ever finer with TET4_ANP and TET10; per Newton iteration, the time of
// assembly, of the linear solves (factorisation and substitution, or
// incomplete factorisation and CG iterations) and of the residuals, and the
// process's peak memory. The direct solver's rows are nearly incompressible
// (K / mu = 1e3); the PCG rows, which reach about 1e6 unknowns, are
// compressible (K / mu = 10, Poisson's ratio 0.45), because CG's iterations
// grow with K / mu (see docs/performance.md). AMG's rows run the same
// sizes at K / mu = 10, 1e3 and 1e4. A benchmark, not a test:
// scripts/bench.sh runs the direct solver's rows for docs/performance.md;
// `--benchmark_filter` picks rows (peak memory is the row's own only when
// it runs alone).
#include <benchmark/benchmark.h>

#include "common/bench_solve.h"
#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

// The linear solver argument.
AnalysisSpec::LinearSolver Solver(int64_t code, LinearSolverSpec* options) {
  switch (code) {
    case 1:
      return AnalysisSpec::LinearSolver::kPcg;
    case 2:
      return AnalysisSpec::LinearSolver::kAmg;
    case 3:
      options->preconditioner = LinearSolverSpec::Preconditioner::kBoomerAmg;
      return AnalysisSpec::LinearSolver::kAmg;
    case 4:
      return AnalysisSpec::LinearSolver::kMumps;
    case 5:
      options->preconditioner = LinearSolverSpec::Preconditioner::kPressureSchur;
      return AnalysisSpec::LinearSolver::kAmg;
    default:
      return AnalysisSpec::LinearSolver::kCholmod;
  }
}

// Arguments: cells per cube edge; the element (0 = TET4_ANP, 1 = TET10,
// 2 = TET10_MD); the linear solver (0 = CHOLMOD, 1 = PCG, 2 = AMG with
// GAMG, 3 = AMG with BoomerAMG, 4 = MUMPS, 5 = AMG with PRESSURE_SCHUR);
// K / mu.
void BM_NewtonScaling(benchmark::State& state) {
  const ElementType elements[] = {ElementType::kTet4Anp, ElementType::kTet10,
                                  ElementType::kTet10Md};
  SceneSpec s = testing::NeoHookeanCube(elements[state.range(1)], 10.0 / state.range(0),
                                        1000.0 * static_cast<double>(state.range(3)), 1.0, 2,
                                        AnalysisSpec::LinearSolver::kCholmod);
  s.analysis.linear_solver = Solver(state.range(2), &s.analysis.linear_solver_options);
  s.outputs.reaction_sets = {"top"};
  Solution solution;
  if (!testing::SolveEachIteration(state, s, &solution)) return;
  const Summary& m = solution.summary;
  const double iterations = std::max(1, m.newton_iterations);
  state.counters["dofs"] = static_cast<double>(m.dofs);
  state.counters["iterations"] = m.newton_iterations;
  state.counters["assembly_per_it_s"] = m.newton_assembly_s / iterations;
  state.counters["solve_per_it_s"] = m.newton_linear_solve_s / iterations;
  state.counters["residual_per_it_s"] = m.newton_residual_s / iterations;
  state.counters["reaction_N"] = m.reactions.at(0).force_n[2];
  // The iterative solvers' names carry their CG iterations and residuals.
  if (state.range(2) != 0) state.SetLabel(m.linear_solver);
  state.counters["peak_rss_mb"] = testing::PeakRssMb();
}

// The direct solver's rows, then PCG's from about 1e4 to 1e6 unknowns
// (TET4_ANP has about 3 (n + 1)^3 unknowns for n cells per edge, TET10
// about 3 (2 n + 1)^3), and PCG on the smallest meshes at K / mu = 100 and
// 1e3, to show what near incompressibility costs it.
void ScalingRows(benchmark::internal::Benchmark* b) {
  b->ArgNames({"cells", "tet10", "pcg", "k_mu"});  // names kept: docs filter by them
  for (int n : {10, 20, 30}) b->Args({n, 0, 0, 1000});
  for (int n : {5, 10, 15}) b->Args({n, 1, 0, 1000});
  for (int n : {14, 32, 46}) b->Args({n, 0, 1, 10});
  for (int n : {7, 16, 23, 34}) b->Args({n, 1, 1, 10});
  for (int k_mu : {100, 1000}) {
    b->Args({14, 0, 1, k_mu});
    b->Args({7, 1, 1, k_mu});
  }
  // AMG (GAMG, then BoomerAMG) from about 1e4 to 1e6 unknowns, compressible
  // and nearly incompressible; MUMPS beside CHOLMOD.
  for (int k_mu : {10, 1000, 10000}) {
    for (int n : {7, 16, 23, 34}) b->Args({n, 1, 2, k_mu});
    for (int n : {14, 32}) b->Args({n, 0, 2, k_mu});
  }
  for (int n : {7, 16}) b->Args({n, 1, 3, 1000});
  for (int n : {10, 15}) b->Args({n, 1, 4, 1000});
  // TET10_MD, nearly incompressible: the displacement-pressure split
  // against CHOLMOD, from about 1e4 to 1e5 unknowns and K / mu 1e2 to 1e4.
  for (int k_mu : {100, 1000, 10000}) {
    for (int n : {8, 16}) b->Args({n, 2, 5, k_mu});
  }
  for (int n : {8, 16}) b->Args({n, 2, 0, 1000});
}

BENCHMARK(BM_NewtonScaling)
    ->Apply(ScalingRows)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
