// Speed beside error for the linear static solve: wall time per phase and the
// Zienkiewicz-Zhu error estimate as the mesh of the quickstart block is
// refined. A benchmark, not a test: scripts/bench.sh runs it and writes the
// table in docs/performance.md.
#include <benchmark/benchmark.h>

#include <string>

#include "pba/solve.h"

namespace pba {
namespace {

SceneSpec Block(double element_size_mm) {
  SceneSpec s;
  s.name = "bench-block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 30};
  s.mesh.element_size_mm = element_size_mm;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  BoundaryConditionSpec bottom;
  bottom.set = "bottom";
  bottom.kind = BoundaryConditionSpec::Kind::kFixed;
  BoundaryConditionSpec top;
  top.set = "top";
  top.kind = BoundaryConditionSpec::Kind::kDisplacement;
  top.displacement_mm = {0.0, 0.0, -1.5};
  s.boundary_conditions = {bottom, top};
  return s;
}

// Argument: element size in tenths of a millimetre.
void BM_LinearStaticBlock(benchmark::State& state) {
  const SceneSpec scene = Block(state.range(0) / 10.0);
  Solution solution;
  for (auto _ : state) {
    const Status status = SolveScene(scene, SolveOptions(), &solution);
    if (!status.ok()) {
      state.SkipWithError(status.ToString().c_str());
      return;
    }
  }
  const Summary& s = solution.summary;
  state.counters["dofs"] = static_cast<double>(s.dofs);
  state.counters["zz_error_pct"] = 100 * s.error.relative_error;
  for (const PhaseTime& phase : s.phases) state.counters[phase.phase + "_s"] = phase.seconds;
}

BENCHMARK(BM_LinearStaticBlock)
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
