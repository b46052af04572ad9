// Speed beside error for the finite-strain solve: a quarter of a bonded brain
// tissue cube (symmetry planes x = 0 and y = 0, bottom fixed, top pressed
// 20 % and held sideways), Ogden brain fit with K / mu = 1e4, on refined
// meshes, with each element: the average nodal pressure tetrahedron, the
// plain one, the 10-node tetrahedron and the mean-dilatation hexahedron. A
// benchmark, not a test: scripts/bench.sh runs it for docs/performance.md.
#include <benchmark/benchmark.h>

#include <string>

#include "common/bench_solve.h"
#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using testing::Condition;

SceneSpec BondedQuarterCube(double element_size_mm, ElementType element) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "bench-bonded-brain-cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = element_size_mm;
  s.mesh.element = element;
  s.material.kind = MaterialSpec::Kind::kOgden;
  s.material.ogden.terms = {{842, -4.7}};
  s.material.ogden.bulk_modulus_pa = 842e4;
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
                           Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -2.0})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  s.outputs.reaction_sets = {"top"};
  return s;
}

// Arguments: element size in hundredths of a millimetre; the element, an
// index into kElements; 1 for the PCG linear solver instead of CHOLMOD.
constexpr ElementType kElements[] = {ElementType::kTet4, ElementType::kTet4Anp, ElementType::kTet10,
                                     ElementType::kHex8};

void BM_NonlinearBondedCube(benchmark::State& state) {
  SceneSpec scene = BondedQuarterCube(state.range(0) / 100.0, kElements[state.range(1)]);
  if (state.range(2)) scene.analysis.linear_solver = AnalysisSpec::LinearSolver::kPcg;
  Solution solution;
  if (!testing::SolveEachIteration(state, scene, &solution)) return;
  const Summary& s = solution.summary;
  state.counters["dofs"] = static_cast<double>(s.dofs);
  state.counters["increments"] = static_cast<double>(s.increments.size());
  state.counters["iterations"] = s.newton_iterations;
  state.counters["reaction_mN"] = 1e3 * s.reactions.at(0).force_n[2];
  state.counters["zz_error_pct"] = 100 * s.error.relative_error;
  for (const PhaseTime& phase : s.phases) state.counters[phase.phase + "_s"] = phase.seconds;
}

BENCHMARK(BM_NonlinearBondedCube)
    ->ArgNames({"h_mm_x100", "element", "pcg"})
    ->ArgsProduct({{250, 125}, {1, 2, 3, 0}, {0}})
    // The iterative solver on the nearly incompressible case.
    ->Args({125, 1, 1})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
