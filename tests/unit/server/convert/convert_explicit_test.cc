// The explicit analyses through the proto: scene YAML -> pba.v1.Scene ->
// SceneSpec for the explicit controls, velocity conditions, cylinder
// impactors and sensors, the field paths of bad values, and the explicit
// run's summary on its way back (proto and text).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "codec/summary_text.h"
#include "codec/yaml_codec.h"
#include "convert/convert.h"

namespace pba {
namespace {

constexpr const char* kImpact = R"(
name: impact
geometry: {box: {size_mm: [10, 10, 20]}}
mesh: {element: HEX8}
material: {density_kg_per_m3: 1040, neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
boundary_conditions:
  - {set: bottom, velocity: {x_m_per_s: 0, z_m_per_s: 2.5}}
contacts:
  - {name: bolt, set: top, shape: CYLINDER_ROUNDED, position_mm: [5, 5, 21], radius_mm: 2,
     motion_mm: [0, 0, -5], penalty_factor: 2}
  - {name: rod, set: top, shape: CYLINDER_FLAT, position_mm: [2, 2, 21], radius_mm: 1}
analysis:
  type: EXPLICIT_DYNAMIC
  time: {end_time_s: 0.002, curve: [{time_s: 0, amplitude: 0}, {time_s: 0.001, amplitude: 1}]}
  explicit_dynamics:
    time_step_factor: 0.6
    bulk_viscosity_linear: 0.1
    mass_damping_per_s: 10
    hourglass_coefficient: 0.1
    output_interval_s: 1.0e-5
    erosion_strain: 1.5
outputs:
  sensors:
    - {name: centre, position_mm: [5, 5, 10]}
    - {name: low, position_mm: [5, 5, 2], radius_mm: 1.5}
  sensor_interval_s: 2.0e-6
  filter_cutoff_hz: 5000
  filter_order: 6
)";

v1::Scene Proto(const std::string& yaml) {
  v1::Scene scene;
  codec::ParseError error;
  EXPECT_TRUE(codec::ParseYaml(yaml, &scene, &error)) << error.ToString();
  return scene;
}

TEST(SceneFromProto, ExplicitDynamicsWithEveryNewField) {
  const v1::Scene scene = Proto(kImpact);
  SceneSpec s;
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_EQ(s.analysis.type, AnalysisSpec::Type::kExplicitDynamic);
  EXPECT_EQ(s.analysis.time.end_time_s, 0.002);
  ASSERT_EQ(s.analysis.time.curve.size(), 2u);
  const ExplicitSpec& e = s.analysis.explicit_dynamics;
  EXPECT_EQ(e.time_step_factor, 0.6);
  ASSERT_TRUE(e.bulk_viscosity_linear.has_value());
  EXPECT_EQ(*e.bulk_viscosity_linear, 0.1);
  EXPECT_FALSE(e.bulk_viscosity_quadratic.has_value());  // unset: the default
  EXPECT_EQ(e.mass_damping_per_s, 10);
  EXPECT_EQ(e.hourglass_coefficient, 0.1);
  EXPECT_EQ(e.output_interval_s, 1e-5);
  EXPECT_EQ(e.erosion_strain, 1.5);
  EXPECT_EQ(e.relaxation_tolerance, 0);

  ASSERT_EQ(s.boundary_conditions.size(), 1u);
  const BoundaryConditionSpec& piston = s.boundary_conditions[0];
  EXPECT_EQ(piston.kind, BoundaryConditionSpec::Kind::kVelocity);
  ASSERT_TRUE(piston.velocity_m_per_s[0].has_value());  // a zero component is given
  EXPECT_EQ(*piston.velocity_m_per_s[0], 0);
  EXPECT_FALSE(piston.velocity_m_per_s[1].has_value());
  EXPECT_EQ(*piston.velocity_m_per_s[2], 2.5);
  EXPECT_FALSE(piston.displacement_mm[2].has_value());

  ASSERT_EQ(s.contacts.size(), 2u);
  EXPECT_EQ(s.contacts[0].shape, ContactSpec::Shape::kCylinderRounded);
  EXPECT_EQ(s.contacts[0].radius_mm, 2);
  EXPECT_EQ(s.contacts[0].penalty_factor, 2);
  EXPECT_EQ(s.contacts[1].shape, ContactSpec::Shape::kCylinderFlat);

  ASSERT_EQ(s.outputs.sensors.size(), 2u);
  EXPECT_EQ(s.outputs.sensors[0].name, "centre");
  EXPECT_EQ(s.outputs.sensors[0].radius_mm, 0);
  EXPECT_EQ(s.outputs.sensors[1].position_mm, (std::array<double, 3>{5, 5, 2}));
  EXPECT_EQ(s.outputs.sensors[1].radius_mm, 1.5);
  EXPECT_EQ(s.outputs.sensor_interval_s, 2e-6);
  EXPECT_EQ(s.outputs.filter_cutoff_hz, 5000);
  EXPECT_EQ(s.outputs.filter_order, 6);

  EXPECT_TRUE(ValidateSceneProto(scene).ok()) << ValidateSceneProto(scene).ToString();
}

TEST(SceneFromProto, DynamicRelaxation) {
  const v1::Scene scene = Proto(R"(
geometry: {box: {size_mm: [10, 10, 10]}}
material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, pressure: {pressure_pa: 50}}
analysis: {type: DYNAMIC_RELAXATION, explicit_dynamics: {relaxation_tolerance: 1.0e-5}}
)");
  SceneSpec s;
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_EQ(s.analysis.type, AnalysisSpec::Type::kDynamicRelaxation);
  EXPECT_EQ(s.analysis.explicit_dynamics.relaxation_tolerance, 1e-5);
  EXPECT_TRUE(ValidateSceneProto(scene).ok()) << ValidateSceneProto(scene).ToString();
}

TEST(SceneFromProto, ExplicitFieldPathsOfBadValues) {
  const v1::Scene scene = Proto(kImpact);
  SceneSpec spec;
  v1::Scene bad = scene;
  bad.mutable_analysis()->set_type(static_cast<v1::Analysis::Type>(17));
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "analysis.type");
  bad = scene;
  bad.mutable_contacts(1)->set_shape(static_cast<v1::Contact::Shape>(17));
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "contacts[1].shape");
  bad = scene;
  bad.mutable_outputs()->mutable_sensors(1)->add_position_mm(1);
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "outputs.sensors[1].position_mm");
  // Values the validation refuses, through the proto.
  bad = scene;
  bad.mutable_boundary_conditions(0)->mutable_velocity()->Clear();
  EXPECT_EQ(ValidateSceneProto(bad).field(), "boundary_conditions[0].velocity");
  bad = scene;
  bad.mutable_analysis()->mutable_explicit_dynamics()->set_bulk_viscosity_quadratic(-1);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "analysis.explicit_dynamics.bulk_viscosity_quadratic");
  bad = scene;
  bad.mutable_analysis()->set_type(v1::Analysis::NONLINEAR_STATIC);
  bad.mutable_analysis()->clear_time();
  EXPECT_EQ(ValidateSceneProto(bad).field(), "analysis.explicit_dynamics.time_step_factor");
  bad = scene;
  bad.mutable_outputs()->mutable_sensors(0)->set_name("a b");
  EXPECT_EQ(ValidateSceneProto(bad).field(), "outputs.sensors[0].name");
  bad = scene;
  bad.mutable_material()->set_density_kg_per_m3(0);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "material.density_kg_per_m3");
}

Summary ExplicitRunSummary() {
  Summary s;
  s.scene_name = "impact";
  ExplicitSummary& e = s.explicit_run;
  e.ran = true;
  e.steps = 12345;
  e.end_time_s = 0.002;
  e.stable_step_s = 2.5e-7;
  e.first_step_s = 1.5e-7;
  e.last_step_s = 1.25e-7;
  e.step_reductions = 2;
  e.controlling_element = "element 812, length 0.41 mm";
  e.kinetic_j = 0.5;
  e.internal_j = 0.25;
  e.hourglass_j = 0.01;
  e.contact_j = 0.02;
  e.damping_j = 0.03;
  e.eroded_j = 0.04;
  e.external_work_j = 0.85;
  e.max_energy_error = 0.012;
  e.eroded_elements = 3;
  e.eroded_mass_kg = 2e-6;
  e.contact_stiffness_min_n_per_m = 150;
  e.contact_stiffness_max_n_per_m = 900;
  e.element_updates_per_s = 2.5e7;
  s.sensor_peaks = {{"centre", "pressure_pa", 15000, 1.1e-4, 12000, 1.2e-4},
                    {"centre", "speed_m_per_s", 3.5, 2e-4, 3.1, 2.1e-4}};
  return s;
}

TEST(SummaryToProto, CarriesTheExplicitRunAndTheSensorPeaks) {
  const v1::Summary proto = SummaryToProto(ExplicitRunSummary());
  ASSERT_TRUE(proto.results().has_explicit_run());
  const v1::ExplicitRun& e = proto.results().explicit_run();
  EXPECT_TRUE(e.ran());
  EXPECT_EQ(e.steps(), 12345);
  EXPECT_EQ(e.end_time_s(), 0.002);
  EXPECT_EQ(e.stable_step_s(), 2.5e-7);
  EXPECT_EQ(e.first_step_s(), 1.5e-7);
  EXPECT_EQ(e.last_step_s(), 1.25e-7);
  EXPECT_EQ(e.step_reductions(), 2);
  EXPECT_EQ(e.controlling_element(), "element 812, length 0.41 mm");
  EXPECT_EQ(e.kinetic_j(), 0.5);
  EXPECT_EQ(e.internal_j(), 0.25);
  EXPECT_EQ(e.hourglass_j(), 0.01);
  EXPECT_EQ(e.contact_j(), 0.02);
  EXPECT_EQ(e.damping_j(), 0.03);
  EXPECT_EQ(e.eroded_j(), 0.04);
  EXPECT_EQ(e.external_work_j(), 0.85);
  EXPECT_EQ(e.max_energy_error(), 0.012);
  EXPECT_EQ(e.eroded_elements(), 3);
  EXPECT_EQ(e.eroded_mass_kg(), 2e-6);
  EXPECT_EQ(e.contact_stiffness_min_n_per_m(), 150);
  EXPECT_EQ(e.contact_stiffness_max_n_per_m(), 900);
  EXPECT_EQ(e.element_updates_per_s(), 2.5e7);
  EXPECT_FALSE(e.converged());
  ASSERT_EQ(proto.results().sensor_peaks_size(), 2);
  const v1::SensorPeak& p = proto.results().sensor_peaks(1);
  EXPECT_EQ(p.sensor(), "centre");
  EXPECT_EQ(p.quantity(), "speed_m_per_s");
  EXPECT_EQ(p.peak_raw(), 3.5);
  EXPECT_EQ(p.time_raw_s(), 2e-4);
  EXPECT_EQ(p.peak_filtered(), 3.1);
  EXPECT_EQ(p.time_filtered_s(), 2.1e-4);

  // A static solve carries neither.
  const v1::Summary plain = SummaryToProto(Summary());
  EXPECT_FALSE(plain.results().has_explicit_run());
  EXPECT_EQ(plain.results().sensor_peaks_size(), 0);
}

TEST(FormatSummary, ExplicitRunAndSensorPeaks) {
  const std::string text = codec::FormatSummary(SummaryToProto(ExplicitRunSummary()));
  for (const char* part :
       {"explicit           12345 steps to 0.002 s, stable step 2.5e-07 s, first 1.5e-07 s, "
        "last 1.25e-07 s, 2 reductions",
        "controlling      element 812, length 0.41 mm", "kinetic 0.5, internal 0.25",
        "external work 0.85", "largest error 1.2 %", "eroded           3 elements, 2e-06 kg",
        "impactor penalty 150 .. 900 N/m per node", "2.5e+07 element updates/s", "peak raw",
        "centre           pressure_pa"}) {
    EXPECT_NE(text.find(part), std::string::npos) << part << "\n" << text;
  }
  // No Newton, no linear solve, no relaxation in an explicit dynamic run.
  EXPECT_EQ(text.find("linear residual"), std::string::npos) << text;
  EXPECT_EQ(text.find("relaxation"), std::string::npos) << text;

  Summary relaxed;
  relaxed.explicit_run.ran = true;
  relaxed.explicit_run.converged = true;
  relaxed.explicit_run.relative_residual = 3e-5;
  const std::string rest = codec::FormatSummary(SummaryToProto(relaxed));
  EXPECT_NE(rest.find("relaxation       converged, out-of-balance force 3.00e-05"),
            std::string::npos)
      << rest;
  EXPECT_EQ(rest.find("eroded    "), std::string::npos) << rest;
  EXPECT_EQ(rest.find("peak raw"), std::string::npos) << rest;
  EXPECT_EQ(codec::FormatSummary(SummaryToProto(Summary())).find("explicit"), std::string::npos);
}

}  // namespace
}  // namespace pba
