// Speed beside true error, element by element, on problems whose exact
// answers are known: the thick-walled sphere (VALIDATION.md), linear (Lame,
// E = 3 kPa, nu = 0.49) and nearly incompressible neo-Hookean (K / mu =
// 1e4) inflated by a follower pressure to an inner stretch of 1.5; and the
// uniaxial compression of a cube between frictionless platens (30 %,
// neo-Hookean, K / mu = 1e4), whose homogeneous answer every element
// represents exactly, so that its error is the Newton tolerance's and only
// its time tells the elements apart.
// A benchmark, not a test: scripts/bench.sh runs it for docs/performance.md.
#include <benchmark/benchmark.h>

#include <cmath>

#include "common/bench_solve.h"
#include "common/scene_builders.h"
#include "common/thick_sphere.h"
#include "common/uniaxial.h"

namespace pba {
namespace {

using testing::kSphereInnerMm;
using testing::kSphereOuterMm;

constexpr ElementType kElements[] = {ElementType::kTet4, ElementType::kTet4Anp, ElementType::kTet10,
                                     ElementType::kHex8, ElementType::kTet10Md};

void Report(benchmark::State& state, const Solution& solution, double error) {
  const Summary& s = solution.summary;
  state.counters["dofs"] = static_cast<double>(s.dofs);
  state.counters["true_error_pct"] = 100 * error;
  state.counters["zz_error_pct"] = 100 * s.error.relative_error;
  state.counters["solve_s"] = s.wall_time_s;
  state.counters["iterations"] = s.newton_iterations;
}

// Arguments: element size in tenths of a millimetre; the element (index
// into kElements). True error: the larger relative error of the mean radial
// displacement of the inner and the outer surface.
void BM_LameSphere(benchmark::State& state) {
  const double p = 100, e = 3000, nu = 0.49;
  MaterialSpec material;
  material.kind = MaterialSpec::Kind::kLinearElastic;
  material.linear_elastic = {e, nu};
  const SceneSpec scene =
      testing::PressurisedShell(material, p, state.range(0) / 10.0, kElements[state.range(1)]);
  Solution solution;
  if (!testing::SolveEachIteration(state, scene, &solution)) return;
  double error = 0;
  for (double r : {kSphereInnerMm, kSphereOuterMm}) {
    const double exact = testing::LameDisplacement(p, e, nu, r);
    error = std::max(error, std::abs(testing::MeanRadialDisplacement(solution, r) / exact - 1));
  }
  Report(state, solution, error);
}

// True error: of the inner stretch against 1.5.
void BM_InflatedSphere(benchmark::State& state) {
  const double mu = 1000, stretch = 1.5;
  MaterialSpec material;
  material.kind = MaterialSpec::Kind::kNeoHookean;
  material.neo_hookean = {mu, 1e4 * mu};
  SceneSpec scene =
      testing::PressurisedShell(material, testing::IncompressiblePressure(stretch) * mu,
                                state.range(0) / 10.0, kElements[state.range(1)]);
  scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  Solution solution;
  if (!testing::SolveEachIteration(state, scene, &solution)) return;
  const double la = 1 + testing::MeanRadialDisplacement(solution, kSphereInnerMm) / kSphereInnerMm;
  Report(state, solution, std::abs(la / stretch - 1));
}

// True error: of the top's nominal stress against the closed form.
void BM_Uniaxial(benchmark::State& state) {
  const double mu = 1000, bulk = 1e4 * mu, edge = 10, stretch = 0.7;
  using K = BoundaryConditionSpec::Kind;
  using testing::Condition;
  SceneSpec scene;
  scene.name = "uniaxial";
  scene.geometry.kind = GeometrySpec::Kind::kBox;
  scene.geometry.box.size_mm = {edge, edge, edge};
  scene.mesh.element = kElements[state.range(1)];
  scene.mesh.element_size_mm = state.range(0) / 10.0;
  scene.material.kind = MaterialSpec::Kind::kNeoHookean;
  scene.material.neo_hookean = {mu, bulk};
  scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  scene.boundary_conditions = {
      Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
      Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
      Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, edge * (stretch - 1)})};
  scene.outputs.reaction_sets = {"top"};
  Solution solution;
  if (!testing::SolveEachIteration(state, scene, &solution)) return;
  const double nominal = solution.summary.reactions.at(0).force_n[2] / (edge * edge * 1e-6);
  const double exact = testing::CompressibleUniaxial(mu, bulk, stretch).nominal_stress;
  Report(state, solution, std::abs(nominal / exact - 1));
}

BENCHMARK(BM_LameSphere)
    ->ArgNames({"h_mm_x10", "element"})
    ->ArgsProduct({{50, 25, 12}, {0, 2, 3}})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

BENCHMARK(BM_InflatedSphere)
    ->ArgNames({"h_mm_x10", "element"})
    ->ArgsProduct({{50, 25, 12}, {1, 2, 4, 3}})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

BENCHMARK(BM_Uniaxial)
    ->ArgNames({"h_mm_x10", "element"})
    ->ArgsProduct({{50, 25, 12}, {0, 1, 2, 4, 3}})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
