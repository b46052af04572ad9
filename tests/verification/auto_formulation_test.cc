// formulation: AUTO: each decision with its reason, the reduced model's
// answer against the full one, and the estimate the summary gives of the
// difference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/scene_builders.h"
#include "material/material_field.h"
#include "pba/solve.h"
#include "scene/formulation.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

// A 10 mm cube of neo-Hookean tissue on symmetry planes, its top pressed
// down by `strain` of its height.
SceneSpec Cube(double strain, AnalysisSpec::Type type,
               ElementType element = ElementType::kTet4Anp) {
  SceneSpec s;
  s.name = "cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element = element;
  s.mesh.element_size_mm = 2.5;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, 1e5};
  s.boundary_conditions = {
      Condition("bottom", K::kFixed, {}),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -10 * strain})};
  s.analysis.type = type;
  s.outputs.reaction_sets = {"top"};
  s.formulation = Formulation::kAuto;
  return s;
}

const ModelDecision* Find(const Summary& summary, const std::string& aspect) {
  for (const ModelDecision& d : summary.decisions) {
    if (d.aspect == aspect) return &d;
  }
  return nullptr;
}

double TopForce(const Solution& s) { return s.summary.reactions.at(0).force_n[2]; }

TEST(AutoFormulationTest, SmallStrainIsSolvedLinearlyAndTheEstimateSaysHowClose) {
  Solution reduced, full;
  const auto nonlinear = AnalysisSpec::Type::kNonlinearStatic;
  ASSERT_TRUE(SolveScene(Cube(0.002, nonlinear, ElementType::kHex8), {}, &reduced).ok());
  SceneSpec written = Cube(0.002, nonlinear, ElementType::kHex8);
  written.formulation = Formulation::kAsWritten;
  ASSERT_TRUE(SolveScene(written, {}, &full).ok());
  const ModelDecision* d = Find(reduced.summary, "finite strain");
  ASSERT_NE(d, nullptr);
  EXPECT_TRUE(d->reduces);
  EXPECT_NE(d->decision.find("LINEAR_STATIC"), std::string::npos) << d->decision;
  EXPECT_NE(d->reason.find("largest strain"), std::string::npos) << d->reason;
  EXPECT_NE(reduced.summary.analysis.find("linear"), std::string::npos);
  // The reduced answer is close to the full one, and the coarse estimate
  // is of the same order as the true difference.
  const double truth = std::abs(TopForce(reduced) / TopForce(full) - 1);
  ASSERT_TRUE(reduced.summary.reduction.estimated) << reduced.summary.reduction.note;
  std::printf("0.2 %% strain: reduced vs full %.3g %%, estimated %.3g %% (%s)\n", 100 * truth,
              100 * reduced.summary.reduction.relative_difference,
              reduced.summary.reduction.quantity.c_str());
  EXPECT_LT(truth, 0.01);
  EXPECT_LT(reduced.summary.reduction.relative_difference, 0.02);
}

TEST(AutoFormulationTest, SmallStrainOnAverageNodalPressureTetsTakesOneIncrement) {
  Solution solution;
  ASSERT_TRUE(SolveScene(Cube(0.002, AnalysisSpec::Type::kNonlinearStatic), {}, &solution).ok());
  const ModelDecision* d = Find(solution.summary, "finite strain");
  ASSERT_NE(d, nullptr);
  EXPECT_TRUE(d->reduces);
  EXPECT_NE(d->decision.find("one load increment"), std::string::npos) << d->decision;
  EXPECT_EQ(solution.summary.increments.size(), 1u);
  ASSERT_TRUE(solution.summary.reduction.estimated);
  EXPECT_LT(solution.summary.reduction.relative_difference, 1e-6);
}

TEST(AutoFormulationTest, LargeStrainKeepsFiniteStrain) {
  Solution solution;
  ASSERT_TRUE(SolveScene(Cube(0.2, AnalysisSpec::Type::kNonlinearStatic), {}, &solution).ok());
  const ModelDecision* d = Find(solution.summary, "finite strain");
  ASSERT_NE(d, nullptr);
  EXPECT_FALSE(d->reduces);
  EXPECT_EQ(d->decision, "kept");
  EXPECT_FALSE(solution.summary.reduction.estimated);
  EXPECT_NE(solution.summary.analysis.find("nonlinear"), std::string::npos);
}

TEST(AutoFormulationTest, RelaxationFarFasterThanTheLoadingFoldsIntoTheLongTermModulus) {
  SceneSpec s = Cube(0.1, AnalysisSpec::Type::kQuasiStatic);
  s.material.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  s.material.viscoelastic.g = {0.5, 0.2};
  s.material.viscoelastic.tau_s = {0.02, 5};
  s.analysis.time.end_time_s = 10;
  Solution reduced, full;
  ASSERT_TRUE(SolveScene(s, {}, &reduced).ok());
  s.formulation = Formulation::kAsWritten;
  ASSERT_TRUE(SolveScene(s, {}, &full).ok());
  const ModelDecision* d = Find(reduced.summary, "viscoelasticity");
  ASSERT_NE(d, nullptr);
  EXPECT_TRUE(d->reduces);
  EXPECT_NE(d->decision.find("1 of 2"), std::string::npos) << d->decision;
  // The full model resolves the fast term with steps of 20 ms while the
  // load changes; the reduced one has relaxed it and steps freely.
  const double truth = std::abs(TopForce(reduced) / TopForce(full) - 1);
  std::printf("tau 20 ms folded: reduced vs full %.3g %%, estimated %.3g %%; %zu vs %zu steps\n",
              100 * truth, 100 * reduced.summary.reduction.relative_difference,
              reduced.summary.time_steps.size(), full.summary.time_steps.size());
  EXPECT_LT(truth, 0.01);
  EXPECT_LT(reduced.summary.time_steps.size(), full.summary.time_steps.size());
}

TEST(ReduceStructuresTest, KeepsTheStructuresOutputsAndLoadsName) {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kAtlas;
  s.geometry.patches = {PatchSpec::Ball("push", "surface:Putamen", {0, 0, 0}, 5)};
  s.boundary_conditions = {Condition("push", K::kDisplacement, {0.0, 0.0, -1.0}),
                           Condition("interface:Thalamus: pulvinar|Ventricles", K::kPressure, {})};
  s.outputs.structure_displacements = {"Nucleus caudatus"};
  SceneSpec reduced = s;
  std::vector<ModelDecision> decisions;
  ReduceStructures(s, &reduced, &decisions);
  EXPECT_EQ(reduced.geometry.atlas.structures,
            (std::vector<std::string>{"Nucleus caudatus", "Putamen", "Thalamus: pulvinar",
                                      "Ventricles"}));
  EXPECT_TRUE(reduced.geometry.atlas.merge_rest);
  ASSERT_EQ(decisions.size(), 1u);
  EXPECT_TRUE(decisions[0].reduces);
  // Naming none leaves the atlas whole.
  SceneSpec plain;
  plain.geometry.kind = GeometrySpec::Kind::kAtlas;
  SceneSpec same = plain;
  decisions.clear();
  ReduceStructures(plain, &same, &decisions);
  EXPECT_TRUE(same.geometry.atlas.structures.empty());
  EXPECT_FALSE(same.geometry.atlas.merge_rest);
  EXPECT_TRUE(decisions.empty());
}

TEST(ReduceRelaxationTest, RelaxedTermsScaleTheModulusAndFrozenTermsDropOut) {
  double scale = 0;
  const PronySeries kept =
      ReduceRelaxation(PronySeries{{0.5, 0.2, 0.1}, {0.001, 5, 1e6}}, 0.01, 1e3, &scale);
  EXPECT_DOUBLE_EQ(scale, 0.5);
  ASSERT_EQ(kept.g.size(), 1u);
  EXPECT_DOUBLE_EQ(kept.g[0], 0.4);
  EXPECT_DOUBLE_EQ(kept.tau_s[0], 5);
  // G(t)/G0 of the reduced series times the scale is the full one wherever
  // exp(-t/0.001) = 0 and exp(-t/1e6) = 1.
  const PronySeries all{{0.5, 0.2, 0.1}, {0.001, 5, 1e6}};
  for (double t : {0.1, 1.0, 10.0}) {
    EXPECT_NEAR(scale * kept.Relaxation(t), all.Relaxation(t), 1e-6) << t;
  }
}

}  // namespace
}  // namespace pba
