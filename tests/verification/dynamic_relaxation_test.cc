// DYNAMIC_RELAXATION against NONLINEAR_STATIC on the same scenes: the
// explicit engine damped to rest must find the implicit solver's
// equilibrium (the same average-nodal-pressure tetrahedron, so the same
// discrete problem) to within its tolerance.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

SceneSpec Block(double height_mm) {
  SceneSpec s;
  s.name = "block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, height_mm};
  s.mesh.element = ElementType::kTet4Anp;
  s.mesh.element_size_mm = 2;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean.shear_modulus_pa = 1000;
  s.material.neo_hookean.bulk_modulus_pa = 1e5;
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  return s;
}

struct Compared {
  Solution implicit, relaxed;
  double implicit_s = 0, relaxed_s = 0;
};

Compared Solve(SceneSpec scene) {
  Compared c;
  auto t0 = std::chrono::steady_clock::now();
  Status status = SolveScene(scene, SolveOptions(), &c.implicit);
  EXPECT_TRUE(status.ok()) << status.message();
  auto t1 = std::chrono::steady_clock::now();
  scene.analysis.type = AnalysisSpec::Type::kDynamicRelaxation;
  scene.analysis.explicit_dynamics.relaxation_tolerance = 1e-5;
  status = SolveScene(scene, SolveOptions(), &c.relaxed);
  EXPECT_TRUE(status.ok()) << status.message();
  auto t2 = std::chrono::steady_clock::now();
  c.implicit_s = std::chrono::duration<double>(t1 - t0).count();
  c.relaxed_s = std::chrono::duration<double>(t2 - t1).count();
  return c;
}

// Largest nodal difference over the largest displacement.
double DisplacementDifference(const Solution& a, const Solution& b) {
  double diff = 0, largest = 0;
  for (std::size_t i = 0; i < a.displacement_mm.size(); ++i) {
    diff = std::max(diff, std::abs(a.displacement_mm[i] - b.displacement_mm[i]));
    largest = std::max(largest, std::abs(a.displacement_mm[i]));
  }
  return diff / largest;
}

TEST(DynamicRelaxation, CompressedBlockMatchesTheImplicitSolution) {
  SceneSpec scene = Block(10);
  scene.boundary_conditions = {
      Condition("bottom", K::kSymmetry, {}), Condition("x_min", K::kSymmetry, {}),
      Condition("y_min", K::kSymmetry, {}),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -2.0})};
  const Compared c = Solve(scene);
  const double fi = c.implicit.summary.reactions[3].force_n[2],
               fr = c.relaxed.summary.reactions[3].force_n[2];
  const double du = DisplacementDifference(c.implicit, c.relaxed);
  std::printf(
      "20 %% compression: reaction %.6g N implicit, %.6g N relaxed (%.2e); displacement "
      "difference %.2e; %lld steps; %.3g s against %.3g s\n",
      fi, fr, fr / fi - 1, du, static_cast<long long>(c.relaxed.summary.explicit_run.steps),
      c.relaxed_s, c.implicit_s);
  EXPECT_TRUE(c.relaxed.summary.explicit_run.converged);
  EXPECT_NEAR(fr / fi, 1, 1e-3);
  EXPECT_LT(du, 1e-3);
}

TEST(DynamicRelaxation, ShearedColumnMatchesTheImplicitSolution) {
  // A column fixed at its base under a dead traction on its top, down and
  // sideways: it shortens and bends.
  SceneSpec scene = Block(30);
  BoundaryConditionSpec traction;
  traction.set = "top";
  traction.kind = K::kTraction;
  traction.traction_pa = {10, 0, -30};
  scene.boundary_conditions = {Condition("bottom", K::kFixed, {}), traction};
  const Compared c = Solve(scene);
  const double du = DisplacementDifference(c.implicit, c.relaxed);
  std::printf(
      "sheared column: max displacement %.6g mm implicit, %.6g mm relaxed; displacement "
      "difference %.2e; %lld steps; %.3g s against %.3g s\n",
      c.implicit.summary.max_displacement_mm, c.relaxed.summary.max_displacement_mm, du,
      static_cast<long long>(c.relaxed.summary.explicit_run.steps), c.relaxed_s, c.implicit_s);
  EXPECT_NEAR(c.relaxed.summary.max_displacement_mm / c.implicit.summary.max_displacement_mm, 1,
              1e-3);
  EXPECT_LT(du, 2e-3);
}

}  // namespace
}  // namespace pba
