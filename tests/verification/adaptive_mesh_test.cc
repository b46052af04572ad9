// mesh.adapt: refinement where the estimated error is, measured against
// uniform refinement on a problem whose exact energy bounds every answer.
//
// The block is pressed on half of its top (x <= 10 mm) and free on the
// other half, so the strain is singular along the line where the pressed
// half meets the free one, and along the base's edges. Only displacements
// are prescribed, so every conforming finite-element answer stores at
// least the exact strain energy U, and its energy-norm error is
// sqrt(2 (U_h - U)): of two meshes, the one with the lower energy is the
// closer, without knowing U. The patch's edge lies on element faces of
// every mesh here (nodes at x = 10 mm), so every mesh solves the same
// problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

SceneSpec HalfPressedBlock(double element_size_mm, double target_error_percent) {
  SceneSpec s;
  s.name = "half-pressed block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 10};
  s.geometry.patches = {PatchSpec::HalfSpace("pressed", "top", {10, 0, 10}, {-1, 0, 0})};
  s.mesh.element = ElementType::kTet4;
  s.mesh.element_size_mm = element_size_mm;
  s.mesh.adapt.target_error_percent = target_error_percent;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("pressed", K::kDisplacement, {0.0, 0.0, -0.2})};
  s.analysis.type = AnalysisSpec::Type::kLinearStatic;
  s.analysis.linear_solver = AnalysisSpec::LinearSolver::kCholmod;
  s.outputs.reaction_sets = {"pressed"};
  return s;
}

Solution Solve(const SceneSpec& scene) {
  Solution solution;
  SolveOptions options;
  options.threads = 2;
  const Status status = SolveScene(scene, options, &solution);
  EXPECT_TRUE(status.ok()) << status.ToString();
  return solution;
}

TEST(AdaptiveMeshTest, ReachesTheTargetCloserThanAUniformMeshWithMoreElements) {
  const Solution adaptive = Solve(HalfPressedBlock(2.5, 20));
  const Adaptation& a = adaptive.summary.adaptation;
  ASSERT_TRUE(a.adapted);
  EXPECT_TRUE(a.reached) << a.stop_reason;
  ASSERT_GE(a.cycles.size(), 3u) << "the coarse mesh's estimate is above 30 %";
  EXPECT_GT(a.cycles.front().relative_error, 0.3);
  EXPECT_LE(a.cycles.back().relative_error, 0.2);
  EXPECT_EQ(a.cycles.back().relative_error, adaptive.summary.error.relative_error);
  EXPECT_EQ(a.cycles.back().elements, adaptive.summary.elements);
  EXPECT_EQ(a.cycles.back().marked, 0);
  for (std::size_t k = 1; k < a.cycles.size(); ++k) {
    EXPECT_GT(a.cycles[k].elements, a.cycles[k - 1].elements);
    EXPECT_EQ(a.cycles[k - 1].marked > 0, true);
    EXPECT_FALSE(a.cycles[k].changed_quantity.empty());
  }
  // The bounds as run are echoed with the other options.
  const auto option = [&](const std::string& name) {
    for (const auto& [key, value] : adaptive.summary.options)
      if (key == name) return value;
    return std::string("(absent)");
  };
  EXPECT_EQ(option("mesh.adapt.target_error_percent"), "20 %");
  EXPECT_EQ(option("mesh.adapt.max_cycles"), "6");
  EXPECT_EQ(option("mesh.adapt.max_elements"), "500000");
  EXPECT_EQ(option("mesh.adapt.refine_fraction"), "0.5");
  // The result is the last cycle's mesh.
  EXPECT_EQ(static_cast<int64_t>(adaptive.tets.size()), 4 * a.cycles.back().elements);
  EXPECT_EQ(static_cast<int64_t>(adaptive.nodes_mm.size()), 3 * a.cycles.back().nodes);

  // Uniform elements of a quarter of the size: over four times as many
  // elements, and still farther from the exact answer.
  const Solution uniform = Solve(HalfPressedBlock(0.625, 0));
  EXPECT_FALSE(uniform.summary.adaptation.adapted);
  EXPECT_GT(uniform.summary.elements, 4 * a.cycles.back().elements);
  EXPECT_LT(adaptive.summary.strain_energy_j, uniform.summary.strain_energy_j);
}

// Each cycle refines the one before (nested meshes, the same problem): the
// energy can only fall, cycle after cycle, towards the exact one.
TEST(AdaptiveMeshTest, EveryCycleLowersTheEnergy) {
  double previous = INFINITY;
  for (int cycles = 1; cycles <= 3; ++cycles) {
    SceneSpec scene = HalfPressedBlock(2.5, 1);
    scene.mesh.adapt.max_cycles = cycles;
    const Solution solution = Solve(scene);
    ASSERT_EQ(solution.summary.adaptation.cycles.size(), static_cast<std::size_t>(cycles));
    EXPECT_LT(solution.summary.strain_energy_j, previous) << cycles << " cycles";
    previous = solution.summary.strain_energy_j;
  }
}

// Where the answer is exact on any mesh (a uniform stretch), the first
// estimate is within the target and nothing is refined.
TEST(AdaptiveMeshTest, AnExactAnswerIsNotRefined) {
  SceneSpec scene = HalfPressedBlock(5, 1);
  scene.geometry.patches.clear();
  scene.boundary_conditions = {
      Condition("bottom", K::kSymmetry), Condition("x_min", K::kSymmetry),
      Condition("y_min", K::kSymmetry),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, 0.1})};
  scene.outputs.reaction_sets = {"top"};
  const Solution solution = Solve(scene);
  const Adaptation& a = solution.summary.adaptation;
  ASSERT_EQ(a.cycles.size(), 1u);
  EXPECT_TRUE(a.reached);
  EXPECT_LT(a.cycles[0].relative_error, 1e-6);
  for (const std::string& note : solution.summary.notes) {
    EXPECT_EQ(note.find("mesh.adapt"), std::string::npos) << note;
  }
}

// Bounds that end the cycles before the target: the summary says which, in
// a warning, and the result is the last mesh solved.
TEST(AdaptiveMeshTest, StopsAtItsBoundsAndWarns) {
  SceneSpec scene = HalfPressedBlock(2.5, 1);
  scene.mesh.adapt.max_cycles = 2;
  Solution solution = Solve(scene);
  const auto warned = [](const Summary& summary, const std::string& text) {
    return std::any_of(summary.notes.begin(), summary.notes.end(), [&](const std::string& n) {
      return n.rfind("warning: mesh.adapt did not reach its target", 0) == 0 &&
             n.find(text) != std::string::npos;
    });
  };
  EXPECT_FALSE(solution.summary.adaptation.reached);
  EXPECT_EQ(solution.summary.adaptation.cycles.size(), 2u);
  EXPECT_TRUE(warned(solution.summary, "mesh.adapt.max_cycles"));

  scene.mesh.adapt.max_cycles = 10;
  scene.mesh.adapt.max_elements = 10000;
  solution = Solve(scene);
  const Adaptation& a = solution.summary.adaptation;
  EXPECT_FALSE(a.reached);
  EXPECT_LE(a.cycles.back().elements, 10000);
  EXPECT_GE(a.cycles.size(), 2u);
  EXPECT_TRUE(warned(solution.summary, "mesh.adapt.max_elements (10000)"));
  // Each cycle's phase is in the summary, and the wall time counts them.
  double cycles_s = 0;
  for (const AdaptCycle& c : a.cycles) cycles_s += c.wall_time_s;
  EXPECT_NEAR(solution.summary.wall_time_s, cycles_s, 1e-9 + 1e-9 * cycles_s);
}

// Finite strain, 4- and 10-node elements: the cycles run and the estimate
// falls; the 10-node mesh's mid-edge nodes come after refinement.
TEST(AdaptiveMeshTest, FiniteStrainAndQuadraticElements) {
  for (const ElementType element : {ElementType::kTet4Anp, ElementType::kTet10}) {
    SceneSpec scene = HalfPressedBlock(2.5, 1);
    scene.mesh.element = element;
    scene.mesh.adapt.max_cycles = 3;
    scene.material.kind = MaterialSpec::Kind::kNeoHookean;
    scene.material.neo_hookean = {1000, 10000};
    scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
    const Solution solution = Solve(scene);
    const Adaptation& a = solution.summary.adaptation;
    ASSERT_EQ(a.cycles.size(), 3u) << ElementName(element);
    EXPECT_LT(a.cycles.back().relative_error, a.cycles.front().relative_error);
    EXPECT_GT(a.cycles.back().elements, a.cycles.front().elements);
    const int per_element = element == ElementType::kTet10 ? 10 : 4;
    EXPECT_EQ(static_cast<int64_t>(solution.tets.size()), per_element * a.cycles.back().elements);
  }
}

// The estimate against the true error, in linear elasticity and at finite
// strain (neo-Hookean, pressed 10 %, plain TET4: conforming, so its
// energy too bounds the exact one). The exact energy is extrapolated from
// three uniform meshes (Aitken), which gives each mesh's true relative
// error in the energy norm, sqrt(2 (U_h - U)) over sqrt(2 (U_h - U) +
// 2 U_h); the estimate's effectivity, estimate over true error, must lie
// within 0.5..2 on every mesh.
TEST(AdaptiveMeshTest, TheEstimateTracksTheTrueErrorAtSmallAndFiniteStrain) {
  for (const bool finite : {false, true}) {
    std::vector<double> energy, estimate;
    for (const double h : {5.0, 2.5, 1.25}) {
      SceneSpec scene = HalfPressedBlock(h, 0);
      if (finite) {
        scene.material.kind = MaterialSpec::Kind::kNeoHookean;
        scene.material.neo_hookean = {1000, 9667};  // nu = 0.45 at small strain
        scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
        scene.boundary_conditions[1].displacement_mm = {0.0, 0.0, -1.0};
      }
      const Solution solution = Solve(scene);
      energy.push_back(solution.summary.strain_energy_j);
      estimate.push_back(solution.summary.error.relative_error);
    }
    ASSERT_GT(energy[0], energy[1]);
    ASSERT_GT(energy[1], energy[2]);
    const double exact =
        (energy[0] * energy[2] - energy[1] * energy[1]) / (energy[0] + energy[2] - 2 * energy[1]);
    ASSERT_GT(exact, 0);
    ASSERT_LT(exact, energy[2]);
    for (std::size_t k = 0; k < energy.size(); ++k) {
      const double e2 = 2 * (energy[k] - exact);
      const double truth = std::sqrt(e2 / (e2 + 2 * energy[k]));
      const double effectivity = estimate[k] / truth;
      std::printf("%s strain, mesh %zu: estimate %.3g, true error %.3g, effectivity %.2f\n",
                  finite ? "finite" : "small", k, estimate[k], truth, effectivity);
      EXPECT_GE(effectivity, 0.5);
      EXPECT_LE(effectivity, 2.0);
    }
  }
}

TEST(AdaptiveMeshTest, RefusesWhatItCannotAdapt) {
  Solution solution;
  const auto field_of = [&](const SceneSpec& scene) {
    return SolveScene(scene, SolveOptions(), &solution).field();
  };
  SceneSpec scene = HalfPressedBlock(2.5, 10);
  scene.mesh.element = ElementType::kHex8;
  EXPECT_EQ(field_of(scene), "mesh.adapt");
  scene = HalfPressedBlock(2.5, 100);
  EXPECT_EQ(field_of(scene), "mesh.adapt.target_error_percent");
  scene = HalfPressedBlock(2.5, 0);
  scene.mesh.adapt.max_cycles = 3;
  EXPECT_EQ(field_of(scene), "mesh.adapt.target_error_percent");
  scene = HalfPressedBlock(2.5, 10);
  scene.mesh.adapt.refine_fraction = 1.5;
  EXPECT_EQ(field_of(scene), "mesh.adapt.refine_fraction");
  scene = HalfPressedBlock(2.5, 10);
  scene.mesh.adapt.max_elements = -1;
  EXPECT_EQ(field_of(scene), "mesh.adapt.max_elements");
  scene = HalfPressedBlock(2.5, 10);
  scene.mesh.adapt.max_cycles = 21;
  EXPECT_EQ(field_of(scene), "mesh.adapt.max_cycles");
  scene = HalfPressedBlock(2.5, 10);
  scene.material.kind = MaterialSpec::Kind::kNeoHookean;
  scene.material.neo_hookean = {1000, 10000};
  scene.analysis.type = AnalysisSpec::Type::kQuasiStatic;
  scene.analysis.time.end_time_s = 1;
  SolveOptions restart;
  restart.restart_from = "checkpoint.h5";
  const Status refused = SolveScene(scene, restart, &solution);
  EXPECT_EQ(refused.field(), "restart_from");
  EXPECT_NE(refused.message().find("mesh.adapt"), std::string::npos);
}

}  // namespace
}  // namespace pba
