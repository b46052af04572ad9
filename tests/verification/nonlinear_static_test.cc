// Verification of the finite-strain static solve against closed forms and
// its own hard cases: homogeneous uniaxial stress (which linear tetrahedra
// represent exactly, so the answer must match the material point to solver
// precision), the small-strain limit, path independence under step cutting,
// and a clear failure when the prescribed motion inverts elements.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>

#include "common/scene_builders.h"
#include "material/factory.h"
#include "material/hyperelastic.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;

using testing::Condition;

MaterialSpec NeoHookean(double mu, double bulk) {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kNeoHookean;
  m.neo_hookean = {mu, bulk};
  return m;
}

MaterialSpec MooneyRivlin(double c10, double c01, double bulk) {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kMooneyRivlin;
  m.mooney_rivlin = {c10, c01, bulk};
  return m;
}

MaterialSpec BrainOgden(double bulk) {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kOgden;
  m.ogden.terms = {{842, -4.7}};
  m.ogden.bulk_modulus_pa = bulk;
  return m;
}

// A 10 mm cube on symmetry planes (x_min, y_min, bottom roll), its top moved
// to stretch `lambda`: homogeneous uniaxial stress.
SceneSpec UniaxialCube(const MaterialSpec& material, double lambda) {
  SceneSpec s;
  s.name = "uniaxial cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = 2.5;
  s.material = material;
  s.boundary_conditions = {
      Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
      Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
      Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, 10 * (lambda - 1)})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  s.outputs.reaction_sets = {"top"};
  return s;
}

// The material point's answer: nominal stress P and lateral stretch of
// homogeneous uniaxial stress at `lambda` (Newton on S_xx = 0 with
// lambda_x = lambda_y). The closed forms of VALIDATION.md check this in the
// material unit tests.
struct PointAnswer {
  double nominal_stress = 0;
  double lateral_stretch = 1;
};
PointAnswer MaterialPoint(const MaterialSpec& spec, double lambda) {
  const auto material = MakeHyperelasticMaterial(spec);
  double lateral = 1 / std::sqrt(lambda);
  for (int i = 0; i < 60; ++i) {
    const Eigen::Matrix3d f = Eigen::Vector3d(lateral, lateral, lambda).asDiagonal();
    const Vector6d s = material->Stress(f);
    const Matrix6d c = material->Tangent(f);
    lateral -= s(0) / ((c(0, 0) + c(0, 1)) * lateral);
  }
  const Eigen::Matrix3d f = Eigen::Vector3d(lateral, lateral, lambda).asDiagonal();
  return {lambda * material->Stress(f)(2), lateral};
}

struct UniaxialCase {
  std::string name;
  MaterialSpec material;
  double lambda;
};
void PrintTo(const UniaxialCase& c, std::ostream* os) { *os << c.name; }

class UniaxialTest : public ::testing::TestWithParam<UniaxialCase> {};

// Linear tetrahedra hold a homogeneous deformation exactly: the top reaction
// over the reference area is the material point's nominal stress to the
// Newton tolerance (1e-8 relative residual), and every node sits where the
// homogeneous motion puts it.
TEST_P(UniaxialTest, MatchesTheMaterialPoint) {
  const UniaxialCase& c = GetParam();
  Solution solution;
  const Status status = SolveScene(UniaxialCube(c.material, c.lambda), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const PointAnswer expected = MaterialPoint(c.material, c.lambda);
  const double area = 1e-4;  // m^2, reference
  ASSERT_EQ(solution.summary.reactions.size(), 1u);
  const double nominal = solution.summary.reactions[0].force_n[2] / area;
  EXPECT_NEAR(nominal, expected.nominal_stress, 1e-6 * std::abs(expected.nominal_stress));
  const std::size_t nodes = solution.nodes_mm.size() / 3;
  double worst = 0;
  for (std::size_t i = 0; i < nodes; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double stretch = k == 2 ? c.lambda : expected.lateral_stretch;
      worst = std::max(worst, std::abs(solution.displacement_mm[3 * i + k] -
                                       (stretch - 1) * solution.nodes_mm[3 * i + k]));
    }
  }
  EXPECT_LT(worst, 1e-7);  // mm
  for (double j : solution.jacobian) {
    EXPECT_NEAR(j, c.lambda * expected.lateral_stretch * expected.lateral_stretch, 1e-9);
  }
  EXPECT_FALSE(solution.summary.increments.empty());
  EXPECT_GT(solution.summary.newton_iterations, 0);
  std::printf("%s: P = %.6f Pa (material point %.6f), %zu increments, %d iterations, %.3f s\n",
              c.name.c_str(), nominal, expected.nominal_stress, solution.summary.increments.size(),
              solution.summary.newton_iterations, solution.summary.wall_time_s);
}

INSTANTIATE_TEST_SUITE_P(
    Materials, UniaxialTest,
    ::testing::Values(UniaxialCase{"neo_hookean_tension", NeoHookean(1000, 1e6), 1.3},
                      UniaxialCase{"neo_hookean_compression", NeoHookean(1000, 1e6), 0.7},
                      UniaxialCase{"mooney_rivlin_compression", MooneyRivlin(300, 200, 5e5), 0.8},
                      UniaxialCase{"ogden_brain_compression", BrainOgden(842e3), 0.7},
                      UniaxialCase{"ogden_brain_tension", BrainOgden(842e3), 1.3},
                      UniaxialCase{"neo_hookean_half_height", NeoHookean(1000, 1e5), 0.5}),
    [](const auto& info) { return info.param.name; });

// Nearly incompressible (K / mu = 1e6, brain-like): still solves, and lands
// on the incompressible closed form mu (lambda - lambda^-2) within O(mu/K).
TEST(NonlinearStatic, BrainLikeIncompressibilitySolves) {
  Solution solution;
  const Status status =
      SolveScene(UniaxialCube(NeoHookean(1000, 1e9), 0.8), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const double exact = 1000 * (0.8 - 1 / (0.8 * 0.8));
  EXPECT_NEAR(solution.summary.reactions[0].force_n[2] / 1e-4, exact, 1e-5 * std::abs(exact));
}

// Symmetry conditions on the three planes are the rollers written out.
TEST(NonlinearStatic, SymmetryPlanesActAsRollers) {
  SceneSpec rollers = UniaxialCube(BrainOgden(842e3), 0.8);
  SceneSpec mirrored = rollers;
  mirrored.boundary_conditions = {
      Condition("bottom", K::kSymmetry), Condition("x_min", K::kSymmetry),
      Condition("y_min", K::kSymmetry), rollers.boundary_conditions.back()};
  Solution a, b;
  ASSERT_TRUE(SolveScene(rollers, SolveOptions(), &a).ok());
  const Status status = SolveScene(mirrored, SolveOptions(), &b);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(a.summary.dofs, b.summary.dofs);
  EXPECT_NEAR(b.summary.reactions[0].force_n[2], a.summary.reactions[0].force_n[2],
              1e-9 * std::abs(a.summary.reactions[0].force_n[2]));
}

// VALIDATION.md, brain-like ratios: K / mu from 10 to 1e6 all solve, and the
// lambda = 0.8 answer approaches the incompressible one as K / mu grows,
// never stiffening away from it.
TEST(NonlinearStatic, EveryBrainLikeRatioSolvesAndApproachesIncompressibility) {
  const double exact = 1000 * (0.8 - 1 / (0.8 * 0.8));
  double previous = INFINITY;
  for (double ratio : {10.0, 100.0, 1e3, 1e4, 1e5, 1e6}) {
    Solution solution;
    const Status status =
        SolveScene(UniaxialCube(NeoHookean(1000, 1000 * ratio), 0.8), SolveOptions(), &solution);
    ASSERT_TRUE(status.ok()) << "K / mu = " << ratio << ": " << status.ToString();
    const double error = std::abs(solution.summary.reactions[0].force_n[2] / 1e-4 - exact);
    EXPECT_LT(error, previous) << "K / mu = " << ratio;
    previous = error;
  }
  EXPECT_LT(previous, 1e-5 * std::abs(exact));
}

// Bonded compression of a cylinder (inhomogeneous): tiny motion agrees with
// the linear solve; one increment that cannot converge is cut back and the
// answer equals the one reached in many small increments (hyperelasticity is
// path independent).
SceneSpec BondedCylinder(double squeeze_mm, int increments) {
  SceneSpec s;
  s.name = "bonded cylinder";
  s.geometry.kind = GeometrySpec::Kind::kCylinder;
  s.geometry.cylinder = {5, 10};
  s.mesh.element_size_mm = 1.25;
  s.material = NeoHookean(1000, 2e4);
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -squeeze_mm})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  s.analysis.nonlinear.increments = increments;
  return s;
}

// The small-strain limit of the same element.
TEST(NonlinearStatic, SmallMotionAgreesWithLinearElasticity) {
  SceneSpec nonlinear = BondedCylinder(0.001, 1);
  nonlinear.mesh.element = ElementType::kTet4;  // the same element as the linear solve
  SceneSpec linear = nonlinear;
  linear.analysis.type = AnalysisSpec::Type::kLinearStatic;
  Solution a, b;
  ASSERT_TRUE(SolveScene(nonlinear, SolveOptions(), &a).ok());
  ASSERT_TRUE(SolveScene(linear, SolveOptions(), &b).ok());
  const double fa = a.summary.reactions[1].force_n[2], fb = b.summary.reactions[1].force_n[2];
  // Geometric and material nonlinearity enter at O(strain) = 1e-4.
  EXPECT_NEAR(fa, fb, 5e-4 * std::abs(fb));
  EXPECT_LT(a.summary.increments.size(), 3u);
}

TEST(NonlinearStatic, CutsBackAndReachesThePathIndependentAnswer) {
  SceneSpec hard = BondedCylinder(4, 1);  // 40 % in one step
  hard.analysis.nonlinear.max_iterations = 3;
  Solution one, many;
  const Status status = SolveScene(hard, SolveOptions(), &one);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_GT(one.summary.increment_cuts, 0);
  ASSERT_TRUE(SolveScene(BondedCylinder(4, 40), SolveOptions(), &many).ok());
  const double f1 = one.summary.reactions[1].force_n[2], f2 = many.summary.reactions[1].force_n[2];
  EXPECT_NEAR(f1, f2, 1e-6 * std::abs(f2));
  EXPECT_LT(f2, 0);
  // Stiffening in compression: the reaction exceeds the linear one.
  SceneSpec linear = BondedCylinder(4, 1);
  linear.analysis.type = AnalysisSpec::Type::kLinearStatic;
  Solution lin;
  ASSERT_TRUE(SolveScene(linear, SolveOptions(), &lin).ok());
  EXPECT_GT(std::abs(f2), std::abs(lin.summary.reactions[1].force_n[2]));
  std::printf(
      "bonded cylinder 40 %%: one step with %d cuts -> %.6g N; 40 steps -> %.6g N; "
      "linear %.6g N\n",
      one.summary.increment_cuts, f1, f2, lin.summary.reactions[1].force_n[2]);
}

// Pressing the top through the bottom cannot be solved: the run must end
// with a clear numerical error, not NaNs and not a hang.
TEST(NonlinearStatic, InvertingMotionFailsClearly) {
  SceneSpec s = BondedCylinder(11, 2);
  s.analysis.nonlinear.min_increment = 1e-3;
  Solution solution;
  const Status status = SolveScene(s, SolveOptions(), &solution);
  ASSERT_EQ(status.code(), Status::Code::kNumerical) << status.ToString();
  EXPECT_NE(status.message().find("could not be applied beyond"), std::string::npos)
      << status.message();
}

TEST(NonlinearStatic, LinearElasticMaterialIsRefused) {
  SceneSpec s = BondedCylinder(1, 2);
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  Solution solution;
  const Status status = SolveScene(s, SolveOptions(), &solution);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "material");
}

}  // namespace
}  // namespace pba
