// What the solver benchmarks (tests/bench) share: a scene solved once per
// benchmark iteration, and the process's peak memory.
#pragma once

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include "pba/solve.h"

namespace pba::testing {

// Solves `scene` in every iteration of `state` into `solution`. On failure
// the row is marked skipped with the solver's message and false returned.
inline bool SolveEachIteration(benchmark::State& state, const SceneSpec& scene,
                               Solution* solution) {
  for (auto _ : state) {
    const Status status = SolveScene(scene, SolveOptions(), solution);
    if (!status.ok()) {
      state.SkipWithError(status.ToString().c_str());
      return false;
    }
  }
  return true;
}

// The process's peak resident memory so far (getrusage ru_maxrss) [MB]:
// a row's own only when it runs alone.
inline double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

}  // namespace pba::testing
