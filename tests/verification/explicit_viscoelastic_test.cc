// EXPLICIT_DYNAMIC with relaxing tissue (Prony internal variables in the
// TLED elements) against QUASI_STATIC on the same slow compression: when
// the loading is far slower than the waves, the explicit run must find the
// quasi-static forces, at the end of the ramp and after the hold.
#include <gtest/gtest.h>

#include <cmath>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

// A 10 mm cube on symmetry planes, Ogden tissue with one fast relaxation
// term (g = 0.5, tau = 0.2 s), its top moved down 1 mm over 0.5 s, held to
// `end_s`. The ramp is slow against the cube's waves (1 ms to cross it),
// so that the stress its start sets ringing, rho c v = 20 Pa, is small
// beside the 1.4 kPa of the compression and has died out by its end.
SceneSpec Compression(AnalysisSpec::Type type, double end_s) {
  SceneSpec s;
  s.name = "relaxing cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element = ElementType::kTet4Anp;
  s.mesh.element_size_mm = 2.5;
  s.material.kind = MaterialSpec::Kind::kOgden;
  s.material.ogden.terms = {{842, -4.7}};
  s.material.ogden.bulk_modulus_pa = 1e5;
  s.material.density_kg_per_m3 = 1040;
  s.material.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  s.material.viscoelastic.g = {0.5};
  s.material.viscoelastic.tau_s = {0.2};
  s.boundary_conditions = {Condition("bottom", K::kSymmetry, {}),
                           Condition("x_min", K::kSymmetry, {}),
                           Condition("y_min", K::kSymmetry, {}),
                           Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -1.0})};
  s.analysis.type = type;
  s.analysis.time.end_time_s = end_s;
  s.analysis.time.curve = {{0, 0}, {0.5, 1}};
  if (end_s > 0.5) s.analysis.time.curve.push_back({end_s, 1});
  if (type == AnalysisSpec::Type::kQuasiStatic) {
    s.analysis.time.max_step_s = 0.01;
  } else {
    // A little damping against that ringing (the cube's lowest modes are
    // near 1000 rad/s); its drag on the moving tissue, alpha times the
    // mass times the mean speed, is 2e-5 N.
    s.analysis.explicit_dynamics.mass_damping_per_s = 20;
  }
  s.outputs.reaction_sets = {"top"};
  return s;
}

double TopForce(AnalysisSpec::Type type, double end_s, int64_t* steps) {
  Solution solution;
  const Status status = SolveScene(Compression(type, end_s), SolveOptions(), &solution);
  EXPECT_TRUE(status.ok()) << status.message();
  if (steps != nullptr) *steps = solution.summary.explicit_run.steps;
  return solution.summary.reactions.empty() ? NAN : solution.summary.reactions[0].force_n[2];
}

TEST(ExplicitViscoelastic, SlowCompressionFindsTheQuasiStaticForces) {
  double explicit_force[2];
  const double ends[2] = {0.5, 2.0};
  for (int k = 0; k < 2; ++k) {
    const double end_s = ends[k];
    int64_t steps = 0;
    const double quasi = TopForce(AnalysisSpec::Type::kQuasiStatic, end_s, nullptr);
    const double dynamic = TopForce(AnalysisSpec::Type::kExplicitDynamic, end_s, &steps);
    std::printf("t = %g s: top force %.5g N quasi-static, %.5g N explicit (%lld steps), %+.2f %%\n",
                end_s, quasi, dynamic, static_cast<long long>(steps), 100 * (dynamic / quasi - 1));
    EXPECT_NEAR(dynamic / quasi, 1, 0.01);
    explicit_force[k] = dynamic;
  }
  // And the relaxation shows: the held force has fallen.
  EXPECT_LT(std::abs(explicit_force[1]), 0.8 * std::abs(explicit_force[0]));
}

}  // namespace
}  // namespace pba
