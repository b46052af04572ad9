// EXPLICIT_DYNAMIC with rigid impactors (explicit/impactor.h): a bolt
// driven into a block keeps the energy balance (the body's work equals
// what the tissue holds plus what the contact springs hold), leaves little
// penetration, pushes the tissue along with it; with erosion, elements go
// and their mass and energy are accounted for.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

// A 20 mm cube of soft, nearly incompressible tissue (shear waves at 3 m/s,
// pressure waves at 140 m/s) on a fixed base; a
// bolt of radius 3 mm whose tip starts on the top face at its centre is
// driven `depth_mm` down at `speed` m/s, then held.
SceneSpec Impact(ContactSpec::Shape shape, double depth_mm, double speed, double end_s) {
  SceneSpec s;
  s.name = "bolt into a block";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {20, 20, 20};
  s.mesh.element = ElementType::kTet4Anp;
  s.mesh.element_size_mm = 2;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean.shear_modulus_pa = 1e4;
  s.material.neo_hookean.bulk_modulus_pa = 2e7;
  s.material.density_kg_per_m3 = 1040;
  s.boundary_conditions = {Condition("bottom", K::kFixed, {})};
  ContactSpec bolt;
  bolt.name = "bolt";
  bolt.set = "top";
  bolt.shape = shape;
  bolt.radius_mm = 3;
  bolt.position_mm = {10, 10, 20};
  bolt.axis = {0, 0, -1};
  bolt.motion_mm = {0, 0, -depth_mm};
  s.contacts = {bolt};
  s.analysis.type = AnalysisSpec::Type::kExplicitDynamic;
  s.analysis.time.end_time_s = end_s;
  const double travel_s = depth_mm * 1e-3 / speed;
  s.analysis.time.curve = {{0, 0}, {travel_s, 1}, {end_s, 1}};
  SensorSpec below;
  below.name = "below";
  below.position_mm = {10, 10, 12};
  below.radius_mm = 2;
  s.outputs.sensors = {below};
  return s;
}

TEST(ExplicitImpact, BoltKeepsTheEnergyBalanceAndBarelyPenetrates) {
  for (ContactSpec::Shape shape :
       {ContactSpec::Shape::kCylinderFlat, ContactSpec::Shape::kCylinderRounded}) {
    // 1 m/s over 2 ms, then held for 1 ms; damped (the block's lowest
    // mode is near 250 rad/s) so that it settles onto the bolt.
    SceneSpec scene = Impact(shape, 2, 1, 3e-3);
    scene.analysis.explicit_dynamics.mass_damping_per_s = 2000;
    Solution solution;
    const Status status = SolveScene(scene, SolveOptions(), &solution);
    ASSERT_TRUE(status.ok()) << status.field() << ": " << status.message();
    const ExplicitSummary& run = solution.summary.explicit_run;
    ASSERT_EQ(solution.summary.contacts.size(), 1u);
    const ContactSummary& bolt = solution.summary.contacts[0];
    std::printf(
        "%s: %lld steps, force %.4g N (peak %.4g N), penetration %.3g mm, stiffness %.3g..%.3g "
        "N/m, external %.4g J, contact %.3g J, balance %.3g %%, centre moved %.3g mm\n",
        shape == ContactSpec::Shape::kCylinderFlat ? "flat" : "rounded",
        static_cast<long long>(run.steps), bolt.force_n[2], bolt.peak_force_n,
        bolt.max_penetration_mm, run.contact_stiffness_min_n_per_m,
        run.contact_stiffness_max_n_per_m, run.external_work_j, run.contact_j,
        100 * run.max_energy_error, solution.summary.max_displacement_mm);
    // The tissue pushes the bolt back up.
    EXPECT_GT(bolt.force_n[2], 0);
    EXPECT_GE(bolt.peak_force_n, bolt.force_n[2]);
    // Penetration well under an element.
    EXPECT_LT(bolt.max_penetration_mm, 0.25);
    EXPECT_GT(run.contact_stiffness_min_n_per_m, 0);
    EXPECT_GT(run.external_work_j, 0);
    EXPECT_LT(run.max_energy_error, 0.01);
    // The top under the bolt went down with it, nearly the whole 2 mm.
    EXPECT_GT(solution.summary.max_displacement_mm, 1.7);
    EXPECT_LT(solution.summary.max_displacement_mm, 2.3);
  }
}

TEST(ExplicitImpact, ErosionRemovesElementsAndAccountsForThem) {
  SceneSpec scene = Impact(ContactSpec::Shape::kCylinderRounded, 6, 20, 4e-4);
  scene.analysis.explicit_dynamics.erosion_strain = 0.6;
  // Bricks: an element's energy is its own (with average nodal pressure a
  // removed element also changes its neighbours' nodal volume ratios).
  scene.mesh.element = ElementType::kHex8;
  Solution solution;
  const Status status = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.field() << ": " << status.message();
  const ExplicitSummary& run = solution.summary.explicit_run;
  std::printf("eroded %d elements, %.3g g, %.3g J of %.3g J; balance %.3g %%\n",
              run.eroded_elements, run.eroded_mass_kg * 1e3, run.eroded_j, run.external_work_j,
              100 * run.max_energy_error);
  EXPECT_GT(run.eroded_elements, 0);
  EXPECT_GT(run.eroded_mass_kg, 0);
  EXPECT_GT(run.eroded_j, 0);
  EXPECT_LT(run.eroded_j, run.external_work_j);
  EXPECT_LT(run.max_energy_error, 0.01);
}

}  // namespace
}  // namespace pba
