// The summary SolveProblem fills: material parameters as the scene gave
// them, and a warning when an element that locks meets a nearly
// incompressible material (issue 18: nu = 0.4999999 on TET4 answered 7,700
// times too stiff under a summary that read "nu = 0.5").
#include "api/solve_problem.h"

#include <gtest/gtest.h>

#include <string>

#include "pba/solve.h"

namespace pba {
namespace {

SceneSpec Block(ElementType element, double nu) {
  SceneSpec scene;
  scene.name = "locking";
  scene.geometry.kind = GeometrySpec::Kind::kBox;
  scene.geometry.box.size_mm = {4, 4, 8};
  scene.mesh.element_size_mm = 2;
  scene.mesh.element = element;
  scene.material.kind = MaterialSpec::Kind::kLinearElastic;
  scene.material.linear_elastic = {3000, nu};
  BoundaryConditionSpec bottom{"bottom", BoundaryConditionSpec::Kind::kFixed, {}};
  BoundaryConditionSpec top{"top", BoundaryConditionSpec::Kind::kDisplacement, {}};
  top.displacement_mm[2] = -0.4;
  scene.boundary_conditions = {bottom, top};
  return scene;
}

std::string LockingWarning(const Summary& summary) {
  for (const std::string& note : summary.notes) {
    if (note.find("locks when nearly incompressible") != std::string::npos) return note;
  }
  return "";
}

TEST(SolveProblemSummary, PoissonsRatioIsPrintedAsGiven) {
  Solution solution;
  ASSERT_TRUE(SolveScene(Block(ElementType::kTet4, 0.4999999), {}, &solution).ok());
  EXPECT_NE(solution.summary.material.find("nu = 0.4999999"), std::string::npos)
      << solution.summary.material;
  Solution usual;
  ASSERT_TRUE(SolveScene(Block(ElementType::kTet4, 0.45), {}, &usual).ok());
  EXPECT_NE(usual.summary.material.find("E = 3000 Pa, nu = 0.45"), std::string::npos)
      << usual.summary.material;
}

TEST(SolveProblemSummary, LockingElementAndNearlyIncompressibleMaterialWarn) {
  Solution solution;
  ASSERT_TRUE(SolveScene(Block(ElementType::kTet4, 0.4999999), {}, &solution).ok());
  const std::string warning = LockingWarning(solution.summary);
  ASSERT_FALSE(warning.empty());
  EXPECT_NE(warning.find("TET4 locks"), std::string::npos) << warning;
  EXPECT_NE(warning.find("K / mu = 5e+06"), std::string::npos) << warning;
  // It names the elements that do not lock.
  EXPECT_NE(warning.find("TET4_ANP"), std::string::npos) << warning;
  EXPECT_NE(warning.find("HEX8"), std::string::npos) << warning;

  Solution full_bricks;
  ASSERT_TRUE(SolveScene(Block(ElementType::kHex8Full, 0.4999), {}, &full_bricks).ok());
  EXPECT_NE(LockingWarning(full_bricks.summary).find("HEX8_FULL locks"), std::string::npos);
}

TEST(SolveProblemSummary, NoWarningBelowTheBoundOrOnElementsThatDoNotLock) {
  Solution compressible;
  ASSERT_TRUE(SolveScene(Block(ElementType::kTet4, 0.45), {}, &compressible).ok());
  EXPECT_EQ(LockingWarning(compressible.summary), "");
  // nu = 0.4995 is K / mu = 999 (the tissue library's 1e3).
  Solution library_like;
  ASSERT_TRUE(SolveScene(Block(ElementType::kTet4, 0.4995), {}, &library_like).ok());
  EXPECT_EQ(LockingWarning(library_like.summary), "");
  Solution mean_dilatation;
  ASSERT_TRUE(SolveScene(Block(ElementType::kHex8, 0.4999999), {}, &mean_dilatation).ok());
  EXPECT_EQ(LockingWarning(mean_dilatation.summary), "");
}

}  // namespace
}  // namespace pba
