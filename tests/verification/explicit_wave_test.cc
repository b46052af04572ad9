// Verification of EXPLICIT_DYNAMIC on the 1D strain column of
// VALIDATION.md: a column whose sides are symmetry planes, so that every
// element strains along its axis only, of a material with the volumetric
// energy (K / 2)(J - 1)^2 and a vanishing shear modulus: P11 = K (lambda -
// 1) exactly, the linear wave equation. A piston driving one end at v =
// 100 m/s sends a front at c0 = sqrt(K / rho) = 1451.13 m/s with the
// pressure rho c0 v = 150.92 MPa behind it. Also: the energy balance, and
// a time step above the stability limit caught rather than silently wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

constexpr double kBulk = 2.19e9, kDensity = 1040, kPiston = 100;  // Pa, kg/m^3, m/s
constexpr double kLength = 100;                                   // column [mm]

double WaveSpeed() { return std::sqrt(kBulk / kDensity); }

SceneSpec Column(ElementType element, double size_mm, double end_s) {
  SceneSpec s;
  s.name = "wave column";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {2, 2, kLength};
  s.mesh.element = element;
  s.mesh.element_size_mm = size_mm;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean.shear_modulus_pa = 100;  // mu / K = 5e-8: P11 = K (lambda - 1)
  s.material.neo_hookean.bulk_modulus_pa = kBulk;
  s.material.density_kg_per_m3 = kDensity;
  BoundaryConditionSpec piston;
  piston.set = "bottom";
  piston.kind = K::kVelocity;
  piston.velocity_m_per_s = {std::nullopt, std::nullopt, kPiston};
  s.boundary_conditions = {
      piston, Condition("x_min", K::kSymmetry, {}), Condition("x_max", K::kSymmetry, {}),
      Condition("y_min", K::kSymmetry, {}), Condition("y_max", K::kSymmetry, {})};
  s.analysis.type = AnalysisSpec::Type::kExplicitDynamic;
  s.analysis.time.end_time_s = end_s;
  s.analysis.time.curve = {{0, 1}, {end_s, 1}};  // the piston's speed from the start
  for (double z : {20.0, 40.0, 60.0}) {
    SensorSpec sensor;
    sensor.name = "z" + std::to_string(static_cast<int>(z));
    sensor.position_mm = {1.01, 0.99, z};
    s.outputs.sensors.push_back(sensor);
  }
  s.outputs.sensor_interval_s = 5e-8;
  // The plateau is read over 25 us: a cutoff of 100 kHz settles within it
  // (10 kHz, the default for the impact scenes, would take some 100 us).
  s.outputs.filter_cutoff_hz = 1e5;
  return s;
}

int Column(const Solution& s, const std::string& name) {
  for (std::size_t i = 0; i < s.sensor_columns.size(); ++i) {
    if (s.sensor_columns[i] == name) return static_cast<int>(i);
  }
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// The time at which column `c` first reaches `level`, interpolated.
double Arrival(const Solution& s, int c, double level) {
  for (std::size_t k = 1; k < s.sensor_rows.size(); ++k) {
    const double a = s.sensor_rows[k - 1][c], b = s.sensor_rows[k][c];
    if (a < level && b >= level) {
      const double t0 = s.sensor_rows[k - 1][0], t1 = s.sensor_rows[k][0];
      return t0 + (level - a) / (b - a) * (t1 - t0);
    }
  }
  return NAN;
}

double MeanOver(const Solution& s, int c, double t0, double t1) {
  double sum = 0;
  int n = 0;
  for (const std::vector<double>& row : s.sensor_rows) {
    if (row[0] >= t0 && row[0] <= t1) sum += row[c], ++n;
  }
  return n > 0 ? sum / n : NAN;
}

void CheckWave(ElementType element, double size_mm) {
  const double end_s = 60e-6;
  Solution solution;
  SolveOptions options;
  const Status status = SolveScene(Column(element, size_mm, end_s), options, &solution);
  ASSERT_TRUE(status.ok()) << status.message();
  const ExplicitSummary& run = solution.summary.explicit_run;
  const double plateau = kDensity * WaveSpeed() * kPiston;  // 150.92 MPa
  // Speed: the front's half-height between the sensors at 20 and 60 mm.
  const int p20 = Column(solution, "z20 pressure [Pa]");
  const int p60 = Column(solution, "z60 pressure [Pa]");
  const double t20 = Arrival(solution, p20, plateau / 2), t60 = Arrival(solution, p60, plateau / 2);
  const double speed = 40e-3 / (t60 - t20);
  // The plateau behind the front at 20 mm, filtered, well after the front
  // (it arrives at 13.8 us) and before the reflection from the free end.
  const double filtered =
      MeanOver(solution, Column(solution, "z20 pressure [Pa] filtered"), 30e-6, 55e-6);
  std::printf(
      "%s %.2g mm: %lld steps of %.3g us, wave speed %.2f m/s (%.3f %%), plateau %.4g MPa "
      "(%.3f %%), energy balance %.3g %%, %.3g element updates/s\n",
      solution.summary.element_type.c_str(), size_mm, static_cast<long long>(run.steps),
      run.first_step_s * 1e6, speed, 100 * (speed / WaveSpeed() - 1), filtered / 1e6,
      100 * (filtered / plateau - 1), 100 * run.max_energy_error, run.element_updates_per_s);
  EXPECT_NEAR(speed / WaveSpeed(), 1, 0.01);
  EXPECT_NEAR(filtered / plateau, 1, 0.02);
  EXPECT_LT(run.max_energy_error, 0.01);
  EXPECT_GT(run.external_work_j, 0);
  // Peaks are reported per sensor and ordered in time along the column.
  ASSERT_EQ(solution.summary.sensor_peaks.size(), 9u);
  EXPECT_GT(solution.summary.sensor_peaks[0].peak_filtered, 0.9 * plateau);
}

TEST(ExplicitWave, Tet4AnpColumnCarriesTheFrontAtTheWaveSpeed) {
  CheckWave(ElementType::kTet4Anp, 0.5);
}

TEST(ExplicitWave, Hex8ColumnCarriesTheFrontAtTheWaveSpeed) { CheckWave(ElementType::kHex8, 0.5); }

TEST(ExplicitWave, StepAboveTheStabilityLimitIsCaught) {
  SceneSpec scene = Column(ElementType::kHex8, 0.5, 30e-6);
  scene.analysis.explicit_dynamics.time_step_factor = 1.6;
  Solution solution;
  const Status status = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), Status::Code::kNumerical) << status.message();
  EXPECT_NE(status.message().find("step"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("above the stability limit"), std::string::npos)
      << status.message();
}

}  // namespace
}  // namespace pba

namespace pba {
namespace {

// Selective mass scaling: bricks of one size all below a step twice their
// own take four times their density, so the front runs at half the speed
// and three times the model's mass is added.
TEST(ExplicitWave, MassScalingSlowsTheScaledElementsWave) {
  Solution plain;
  ASSERT_TRUE(SolveScene(Column(ElementType::kHex8, 0.5, 1e-6), SolveOptions(), &plain).ok());
  SceneSpec scene = Column(ElementType::kHex8, 0.5, 100e-6);
  scene.analysis.explicit_dynamics.mass_scaling_step_s =
      2 * plain.summary.explicit_run.first_step_s;
  // A gentle piston and no linear bulk viscosity: the elements' steps stay
  // where the scaling put them (a compressing element's step shrinks, and
  // during the run it would take more mass, as a crushed one should).
  scene.boundary_conditions[0].velocity_m_per_s[2] = 1;
  scene.analysis.explicit_dynamics.bulk_viscosity_linear = 0;
  Solution solution;
  const Status status = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.message();
  const ExplicitSummary& run = solution.summary.explicit_run;
  EXPECT_NEAR(run.first_step_s / plain.summary.explicit_run.first_step_s, 2, 1e-9);
  // Every element at the start; during the run the elements the front
  // compresses take a little more (their steps shrink by the compression
  // and the bulk viscosity).
  EXPECT_GE(run.mass_scaled_elements, static_cast<int>(solution.summary.elements));
  EXPECT_NEAR(run.added_mass_kg / run.model_mass_kg, 3, 0.03);
  const int p20 = Column(solution, "z20 pressure [Pa]"),
            p60 = Column(solution, "z60 pressure [Pa]");
  // Half the speed; the plateau doubles, rho' c' v = 4 rho (c / 2) v.
  const double plateau = 2 * kDensity * WaveSpeed() * 1.0;
  const double speed =
      40e-3 / (Arrival(solution, p60, plateau / 2) - Arrival(solution, p20, plateau / 2));
  std::printf("mass-scaled column: %d elements, %.3g kg added to %.3g kg, wave speed %.2f m/s\n",
              run.mass_scaled_elements, run.added_mass_kg, run.model_mass_kg, speed);
  EXPECT_NEAR(speed / (WaveSpeed() / 2), 1, 0.01);
  EXPECT_LT(run.max_energy_error, 0.01);
}

}  // namespace
}  // namespace pba
