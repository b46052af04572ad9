// How a finite-strain Newton step grows with the number of unknowns: a
// nearly incompressible neo-Hookean cube (K / mu = 1e3), bottom fixed, top
// pressed 10 % in two increments, meshed ever finer with TET4_ANP and TET10;
// per Newton iteration, the time of assembly, of the linear solves
// (factorisation and substitution) and of the residuals, and the process's
// peak memory. A benchmark, not a test: scripts/bench.sh runs it for
// docs/performance.md; `--benchmark_filter` picks rows (peak memory is the
// row's own only when it runs alone).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using testing::Condition;

// Arguments: cells per cube edge; the element (0 = TET4_ANP, 1 = TET10);
// the linear solver (0 = CHOLMOD, 1 = PCG, for rows added by hand).
void BM_NewtonScaling(benchmark::State& state) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "bench-scaling";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = 10.0 / state.range(0);
  s.mesh.element = state.range(1) ? ElementType::kTet10 : ElementType::kTet4Anp;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, 1e6};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -1.0})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  s.analysis.nonlinear.increments = 2;
  s.analysis.linear_solver =
      state.range(2) ? AnalysisSpec::LinearSolver::kPcg : AnalysisSpec::LinearSolver::kCholmod;
  s.outputs.reaction_sets = {"top"};
  Solution solution;
  for (auto _ : state) {
    const Status status = SolveScene(s, SolveOptions(), &solution);
    if (!status.ok()) {
      state.SkipWithError(status.ToString().c_str());
      return;
    }
  }
  const Summary& m = solution.summary;
  const double iterations = std::max(1, m.newton_iterations);
  state.counters["dofs"] = static_cast<double>(m.dofs);
  state.counters["iterations"] = m.newton_iterations;
  state.counters["assembly_per_it_s"] = m.newton_assembly_s / iterations;
  state.counters["solve_per_it_s"] = m.newton_linear_solve_s / iterations;
  state.counters["residual_per_it_s"] = m.newton_residual_s / iterations;
  state.counters["reaction_N"] = m.reactions.at(0).force_n[2];
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_mb"] = usage.ru_maxrss / 1024.0;
}

BENCHMARK(BM_NewtonScaling)
    ->ArgNames({"cells", "tet10", "pcg"})
    ->Args({10, 0, 0})
    ->Args({20, 0, 0})
    ->Args({30, 0, 0})
    ->Args({5, 1, 0})
    ->Args({10, 1, 0})
    ->Args({15, 1, 0})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
