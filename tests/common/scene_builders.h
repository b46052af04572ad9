// Small builders for SceneSpec in tests and benchmarks.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "pba/scene.h"

namespace pba::testing {

// A boundary condition on face set `set`; `value` holds the prescribed
// displacement components [mm] of a kDisplacement condition.
inline BoundaryConditionSpec Condition(const std::string& set, BoundaryConditionSpec::Kind kind,
                                       std::array<std::optional<double>, 3> value = {}) {
  BoundaryConditionSpec bc;
  bc.set = set;
  bc.kind = kind;
  bc.displacement_mm = value;
  return bc;
}

// A 20 x 20 x 30 mm block, bottom fixed, top pressed 1.5 mm (the quickstart
// and benchmark block), of linear elastic soft tissue (E = 3 kPa, nu = 0.45).
inline SceneSpec SoftBlock(double element_size_mm, AnalysisSpec::LinearSolver solver) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 30};
  s.mesh.element_size_mm = element_size_mm;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -1.5})};
  s.analysis.linear_solver = solver;
  return s;
}

// A 10 mm neo-Hookean cube (mu = 1 kPa, bulk modulus `bulk_pa`), bottom
// fixed, top pressed `press_mm`, NONLINEAR_STATIC from `increments` (0: the
// default) initial increments.
inline SceneSpec NeoHookeanCube(ElementType element, double element_size_mm, double bulk_pa,
                                double press_mm, int increments,
                                AnalysisSpec::LinearSolver solver) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "neo-hookean cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = element_size_mm;
  s.mesh.element = element;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, bulk_pa};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -press_mm})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  s.analysis.nonlinear.increments = increments;
  s.analysis.linear_solver = solver;
  return s;
}

}  // namespace pba::testing
