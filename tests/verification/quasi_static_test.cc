// Verification of QUASI_STATIC: finite strain through time with a
// quasi-linear viscoelastic material, on homogeneous uniaxial stress, which
// 4-node tetrahedra represent exactly, so the force on the cube's top must
// follow the material point's ramp-and-hold answer (material/viscoelastic.h)
// to the time integration's accuracy; rate dependence and relaxation to the
// long-term modulus; growth of a free body to (1 + strain)^3 its volume.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>

#include "common/scene_builders.h"
#include "material/factory.h"
#include "material/viscoelastic.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

constexpr double kSide = 10;  // cube edge [mm]

// Brain tissue of the viscoelastic ramps of VALIDATION.md: Ogden mu = 842 Pa,
// alpha = -4.7, with the thesis's two-term relaxation; K = 1000 mu.
MaterialSpec BrainQlv() {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kOgden;
  m.ogden.terms = {{842, -4.7}};
  m.ogden.bulk_modulus_pa = 842e3;
  m.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  m.viscoelastic.g = {0.45, 0.365};
  m.viscoelastic.tau_s = {0.5, 50};
  return m;
}

// The cube on symmetry planes, its top moved down by `strain` * side over
// `ramp_s`, then held until `end_s`.
SceneSpec RampAndHold(double strain, double ramp_s, double end_s, double max_step_s) {
  SceneSpec s;
  s.name = "relaxing cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {kSide, kSide, kSide};
  s.mesh.element = ElementType::kTet4Anp;
  s.mesh.element_size_mm = 5;
  s.material = BrainQlv();
  s.boundary_conditions = {
      Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
      Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
      Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -strain * kSide})};
  s.analysis.type = AnalysisSpec::Type::kQuasiStatic;
  s.analysis.time.end_time_s = end_s;
  s.analysis.time.max_step_s = max_step_s;
  s.analysis.time.initial_step_s = std::min(max_step_s, ramp_s / 4);
  s.analysis.time.curve = {{0, 0}, {ramp_s, 1}};
  if (end_s > ramp_s) s.analysis.time.curve.push_back({end_s, 1});
  s.outputs.reaction_sets = {"top"};
  return s;
}

// The top's force [N] in the history row at time t (the last row at or
// before it).
double TopForceAt(const Solution& solution, double t) {
  const auto& columns = solution.history_columns;
  const auto z = std::find(columns.begin(), columns.end(), "reaction top z [N]");
  EXPECT_NE(z, columns.end());
  double force = NAN;
  for (const auto& row : solution.history) {
    if (row[0] <= t * (1 + 1e-9)) force = row[z - columns.begin()];
  }
  return force;
}

// The material point's nominal stress times the reference area [N].
double PointForce(double strain, double ramp_s, double hold_s) {
  const MaterialSpec spec = BrainQlv();
  const auto material = MakeHyperelasticMaterial(spec);
  const PronySeries series{spec.viscoelastic.g, spec.viscoelastic.tau_s};
  double p = 0;
  const Status status = UniaxialRampAndHold(*material, series, strain / ramp_s, 1 - strain, 2000,
                                            hold_s, hold_s > 0 ? 4000 : 0, &p);
  EXPECT_TRUE(status.ok()) << status.ToString();
  return p * kSide * kSide * 1e-6;
}

TEST(QuasiStaticTest, RampFollowsTheMaterialPointToTheTimeIntegrationsAccuracy) {
  Solution solution;
  const Status status = SolveScene(RampAndHold(0.1, 1.0, 1.0, 0.02), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  // The reaction on the top pulls it back up: minus the compressive force.
  const double fe = TopForceAt(solution, 1.0);
  const double point = PointForce(0.1, 1.0, 0);
  std::printf("ramp to 10 %% in 1 s: FE %.6g N, material point %.6g N (%.3g %%), %zu steps\n", fe,
              point, 100 * (fe / point - 1), solution.summary.time_steps.size());
  EXPECT_NEAR(fe / point, 1, 2e-3);
}

TEST(QuasiStaticTest, HoldRelaxesTowardsTheLongTermModulus) {
  Solution solution;
  // 600 s = 12 tau_max: the held stress is within exp(-12) of its limit.
  const Status status = SolveScene(RampAndHold(0.1, 1.0, 600, 100), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const double peak = TopForceAt(solution, 1.0), end = TopForceAt(solution, 600);
  const double point = PointForce(0.1, 1.0, 599);
  std::printf("held 599 s: FE %.6g N, material point %.6g N, peak %.6g N, %zu steps\n", end, point,
              peak, solution.summary.time_steps.size());
  EXPECT_NEAR(end / point, 1, 2e-3);
  // Relaxed well below the peak; the hold took few steps (they grow once
  // the curve is flat).
  EXPECT_LT(std::abs(end), 0.5 * std::abs(peak));
  EXPECT_LT(solution.summary.time_steps.size(), 200u);
  // The force decays monotonically through the hold.
  double previous = INFINITY;
  for (const auto& row : solution.history) {
    if (row[0] <= 1.0) continue;
    const double f = std::abs(TopForceAt(solution, row[0]));
    EXPECT_LE(f, previous * (1 + 1e-9)) << "at t = " << row[0];
    previous = f;
  }
}

// The summary's strain energy is the tissue's stored energy: for relaxing
// tissue its long-term part (once relaxed, the energy of the long-term
// elastic material at the same deformation; never the step's incremental
// potential, which Newton minimises and which may be negative), the tissue's
// alone where a plane presses it.
TEST(QuasiStaticTest, StrainEnergyIsTheTissuesStoredEnergy) {
  // Held 600 s (12 tau_max): relaxed to within exp(-12).
  Solution relaxing;
  Status status = SolveScene(RampAndHold(0.1, 1.0, 600, 100), SolveOptions(), &relaxing);
  ASSERT_TRUE(status.ok()) << status.ToString();
  // The same compression of the long-term elastic material.
  SceneSpec elastic = RampAndHold(0.1, 1.0, 1.0, 0.25);
  const PronySeries series{elastic.material.viscoelastic.g, elastic.material.viscoelastic.tau_s};
  elastic.material.ogden.terms[0].mu_pa *= series.LongTermFactor();
  elastic.material.viscoelastic = ViscoelasticSpec();
  elastic.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  elastic.analysis.time = decltype(elastic.analysis.time)();
  Solution relaxed;
  status = SolveScene(elastic, SolveOptions(), &relaxed);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const double held = relaxing.summary.strain_energy_j, long_term = relaxed.summary.strain_energy_j;
  std::printf("strain energy held 599 s %.8g J, long-term elastic %.8g J\n", held, long_term);
  EXPECT_GT(long_term, 0);
  EXPECT_NEAR(held / long_term, 1, 1e-4);
  bool noted = false;
  for (const std::string& note : relaxing.summary.notes) {
    noted = noted || note.find("strain energy of relaxing tissue") != std::string::npos;
  }
  EXPECT_TRUE(noted);

  // The top pressed by a frictionless plane instead of prescribed: the
  // same compression (to a tight penetration tolerance), the same energy.
  SceneSpec pressed = elastic;
  pressed.boundary_conditions.pop_back();
  ContactSpec plane;
  plane.name = "plate";
  plane.set = "top";
  plane.shape = ContactSpec::Shape::kPlane;
  plane.position_mm = {5, 5, kSide + 2};  // moved down to touch the top
  plane.start_touching = true;
  plane.axis = {0, 0, -1};
  plane.motion_mm = {0, 0, -0.1 * kSide};
  plane.penetration_tolerance_mm = 1e-5;
  pressed.contacts = {plane};
  Solution contact;
  status = SolveScene(pressed, SolveOptions(), &contact);
  ASSERT_TRUE(status.ok()) << status.ToString();
  std::printf("strain energy pressed by a plane %.8g J, prescribed %.8g J\n",
              contact.summary.strain_energy_j, long_term);
  EXPECT_NEAR(contact.summary.strain_energy_j / long_term, 1, 1e-3);
}

TEST(QuasiStaticTest, FasterRampsAreStiffer) {
  double last = 0;
  for (double ramp_s : {100.0, 10.0, 1.0, 0.1}) {
    Solution solution;
    const Status status =
        SolveScene(RampAndHold(0.1, ramp_s, ramp_s, ramp_s / 20), SolveOptions(), &solution);
    ASSERT_TRUE(status.ok()) << status.ToString();
    const double force = std::abs(TopForceAt(solution, ramp_s));
    std::printf("ramp over %g s: %.6g N\n", ramp_s, force);
    EXPECT_GT(force, last * 1.01);
    last = force;
  }
}

TEST(QuasiStaticTest, AFreeGrowingBodyGrowsStressFree) {
  SceneSpec s = RampAndHold(0, 1.0, 1.0, 0.25);
  s.boundary_conditions.pop_back();  // the top is free
  s.material.viscoelastic = ViscoelasticSpec();
  InclusionSpec all;
  all.name = "growing";
  all.centre_mm = {5, 5, 5};
  all.radius_mm = 100;
  all.material = s.material;
  all.growth_strain = 0.1;
  s.inclusions = {all};
  s.outputs.structure_displacements = {"growing"};
  Solution solution;
  const Status status = SolveScene(s, SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  // Homogeneous growth: every length 1.1 times its own, J = 1.331, no stress.
  double max_top = 0;
  for (std::size_t i = 0; i < solution.jacobian.size(); ++i) {
    EXPECT_NEAR(solution.jacobian[i], 1.331, 1e-6);
  }
  for (std::size_t i = 0; i < solution.displacement_mm.size() / 3; ++i) {
    max_top = std::max(max_top, solution.displacement_mm[3 * i + 2]);
  }
  EXPECT_NEAR(max_top, 1.0, 1e-6);
  EXPECT_LT(solution.summary.max_von_mises_pa, 1e-6);
  ASSERT_EQ(solution.summary.structure_displacements.size(), 1u);
  EXPECT_NEAR(solution.summary.structure_displacements[0].max_mm, std::sqrt(3.0), 1e-6);
}

TEST(QuasiStaticTest, RelaxationNeedsOnePointElements) {
  SceneSpec s = RampAndHold(0.1, 1.0, 1.0, 0.25);
  s.mesh.element = ElementType::kHex8;
  Solution solution;
  const Status status = SolveScene(s, SolveOptions(), &solution);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("TET4_ANP"), std::string::npos) << status.ToString();
}

}  // namespace
}  // namespace pba
