// Speed beside error for the linear static solve: wall time per phase and the
// Zienkiewicz-Zhu error estimate as the mesh of the quickstart block is
// refined, with the direct (CHOLMOD) and the iterative (PCG) linear solver.
// A benchmark, not a test: scripts/bench.sh runs it and writes the table in
// docs/performance.md.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "common/bench_solve.h"
#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

// Argument: element size in tenths of a millimetre.
void BM_LinearStaticBlock(benchmark::State& state, AnalysisSpec::LinearSolver linear_solver) {
  const SceneSpec scene = testing::SoftBlock(state.range(0) / 10.0, linear_solver);
  Solution solution;
  if (!testing::SolveEachIteration(state, scene, &solution)) return;
  const Summary& s = solution.summary;
  state.counters["dofs"] = static_cast<double>(s.dofs);
  state.counters["zz_error_pct"] = 100 * s.error.relative_error;
  // -log10 of ||K u - f|| / ||f||: digits of the linear solve (a plain
  // counter would print 1e-13 as 0).
  state.counters["residual_digits"] =
      s.relative_residual > 0 ? -std::log10(s.relative_residual) : 99;
  for (const PhaseTime& phase : s.phases) state.counters[phase.phase + "_s"] = phase.seconds;
  // The process's peak resident memory so far: the row's own only when it
  // runs alone (--benchmark_filter), as for the figures in docs/performance.md.
  state.counters["peak_rss_mb"] = testing::PeakRssMb();
  state.SetLabel(s.linear_solver);
}

BENCHMARK_CAPTURE(BM_LinearStaticBlock, cholmod, AnalysisSpec::LinearSolver::kCholmod)
    ->Arg(40)
    ->Arg(20)
    ->Arg(13)
    ->Arg(10)
    ->Arg(7)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

BENCHMARK_CAPTURE(BM_LinearStaticBlock, pcg, AnalysisSpec::LinearSolver::kPcg)
    ->Arg(40)
    ->Arg(20)
    ->Arg(13)
    ->Arg(10)
    ->Arg(7)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
