// ValidateScene on the explicit analyses (solver/scene/validate_explicit.cc
// and the explicit parts of validate.cc and validate_loading.cc): every
// rule refuses naming the field path.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>

#include "pba/scene.h"
#include "scene/unsolved.h"

namespace pba {
namespace {

using Type = AnalysisSpec::Type;

MaterialSpec Tissue() {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kNeoHookean;
  m.neo_hookean = {1000, 1e6};
  m.density_kg_per_m3 = 1040;
  return m;
}

// A box struck by a rounded bolt and pushed by a piston, free otherwise,
// with two sensors and every explicit control set.
SceneSpec ImpactScene() {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 20};
  s.mesh.element = ElementType::kHex8;
  s.material = Tissue();

  BoundaryConditionSpec piston;
  piston.set = "bottom";
  piston.kind = BoundaryConditionSpec::Kind::kVelocity;
  piston.velocity_m_per_s[2] = 2.5;
  s.boundary_conditions = {piston};

  ContactSpec bolt;
  bolt.name = "bolt";
  bolt.set = "top";
  bolt.shape = ContactSpec::Shape::kCylinderRounded;
  bolt.position_mm = {5, 5, 21};
  bolt.radius_mm = 2;
  bolt.motion_mm = {0, 0, -5};
  s.contacts = {bolt};

  s.analysis.type = Type::kExplicitDynamic;
  s.analysis.time.end_time_s = 2e-3;
  s.analysis.time.curve = {{0, 0}, {1e-3, 1}};
  ExplicitSpec& e = s.analysis.explicit_dynamics;
  e.time_step_factor = 0.6;
  e.bulk_viscosity_linear = 0.06;
  e.bulk_viscosity_quadratic = 0;  // off
  e.mass_damping_per_s = 10;
  e.hourglass_coefficient = 0.1;
  e.output_interval_s = 1e-5;
  e.erosion_strain = 1.5;

  s.outputs.sensors = {{"centre", {5, 5, 10}, 0}, {"low_2-b", {5, 5, 2}, 1.5}};
  s.outputs.sensor_interval_s = 2e-6;
  s.outputs.filter_cutoff_hz = 5000;
  s.outputs.filter_order = 4;
  return s;
}

// The static answer by dynamic relaxation: a held box under a pressure.
SceneSpec RelaxationScene() {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 20};
  s.material = Tissue();
  s.material.density_kg_per_m3 = 0;  // fictitious masses
  BoundaryConditionSpec bottom;
  bottom.set = "bottom";
  bottom.kind = BoundaryConditionSpec::Kind::kFixed;
  BoundaryConditionSpec top;
  top.set = "top";
  top.kind = BoundaryConditionSpec::Kind::kPressure;
  top.pressure_pa = 100;
  s.boundary_conditions = {bottom, top};
  s.analysis.type = Type::kDynamicRelaxation;
  s.analysis.explicit_dynamics.relaxation_tolerance = 1e-5;
  s.analysis.explicit_dynamics.time_step_factor = 0.9;
  return s;
}

TEST(ValidateExplicitGoodTest, ImpactAndRelaxationScenesAreAccepted) {
  EXPECT_TRUE(ValidateScene(ImpactScene()).ok()) << ValidateScene(ImpactScene()).ToString();
  EXPECT_TRUE(ValidateScene(RelaxationScene()).ok()) << ValidateScene(RelaxationScene()).ToString();
}

TEST(ValidateExplicitGoodTest, VariantsThatStayValid) {
  SceneSpec s = ImpactScene();
  s.boundary_conditions.clear();  // a free body: its inertia holds it
  s.contacts[0].shape = ContactSpec::Shape::kCylinderFlat;
  s.analysis.time.curve.clear();  // a ramp
  s.analysis.explicit_dynamics = ExplicitSpec();
  s.analysis.explicit_dynamics.time_step_factor = 2;  // unstable, allowed
  s.outputs.sensor_interval_s = 0;                    // 1e-6 s: Nyquist 500 kHz
  s.outputs.filter_cutoff_hz = 4.9e5;
  s.outputs.filter_order = 10;
  s.mesh.element = ElementType::kDefault;
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
  for (ElementType e : {ElementType::kTet4, ElementType::kTet4Anp}) {
    s.mesh.element = e;
    EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
  }
  s.outputs = OutputSpec();  // no sensors
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();

  // A cylinder in a static analysis (the rigid contact's tangent).
  SceneSpec nonlinear = RelaxationScene();
  nonlinear.analysis = AnalysisSpec();
  nonlinear.analysis.type = Type::kNonlinearStatic;
  nonlinear.contacts = ImpactScene().contacts;
  nonlinear.contacts[0].friction = 0.2;
  nonlinear.contacts[0].start_touching = true;
  EXPECT_TRUE(ValidateScene(nonlinear).ok()) << ValidateScene(nonlinear).ToString();
}

// The Abaqus export writes one static step: neither explicit analysis.
TEST(ValidateExplicitGoodTest, TheAbaqusExportRefusesBoth) {
  for (const SceneSpec& s : {ImpactScene(), RelaxationScene()}) {
    const Status status = RefuseUnsupportedFields(s, "exported");
    EXPECT_EQ(status.code(), Status::Code::kFailedPrecondition);
    EXPECT_EQ(status.message().rfind("analysis.type: ", 0), 0u) << status.message();
  }
  EXPECT_NE(RefuseUnsupportedFields(ImpactScene(), "exported").message().find("EXPLICIT_DYNAMIC"),
            std::string::npos);
}

struct Case {
  const char* label;
  std::function<SceneSpec()> scene;
  std::function<void(SceneSpec*)> spoil;
  const char* field;
  const char* message_part;
};

class ValidateExplicitTest : public ::testing::TestWithParam<Case> {};

TEST_P(ValidateExplicitTest, NamesTheField) {
  SceneSpec scene = GetParam().scene();
  GetParam().spoil(&scene);
  const Status status = ValidateScene(scene);
  ASSERT_FALSE(status.ok()) << GetParam().label;
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), GetParam().field) << status.ToString();
  EXPECT_NE(status.message().find(GetParam().message_part), std::string::npos) << status.message();
}

SceneSpec Static() {
  SceneSpec s = RelaxationScene();
  s.analysis = AnalysisSpec();
  s.analysis.type = Type::kNonlinearStatic;
  return s;
}

SceneSpec Linear() {
  SceneSpec s = Static();
  s.analysis.type = Type::kLinearStatic;
  return s;
}

ExplicitSpec& Controls(SceneSpec* s) { return s->analysis.explicit_dynamics; }

INSTANTIATE_TEST_SUITE_P(
    Time, ValidateExplicitTest,
    ::testing::Values(
        Case{"no_end_time", ImpactScene, [](SceneSpec* s) { s->analysis.time.end_time_s = 0; },
             "analysis.time.end_time_s", "EXPLICIT_DYNAMIC needs a positive end time"},
        Case{"initial_step", ImpactScene,
             [](SceneSpec* s) { s->analysis.time.initial_step_s = 1e-6; },
             "analysis.time.initial_step_s", "not used by EXPLICIT_DYNAMIC"},
        Case{"min_step", ImpactScene, [](SceneSpec* s) { s->analysis.time.min_step_s = 1e-9; },
             "analysis.time.min_step_s", "stability limit"},
        Case{"max_step", ImpactScene, [](SceneSpec* s) { s->analysis.time.max_step_s = 1e-5; },
             "analysis.time.max_step_s", "not used by EXPLICIT_DYNAMIC"},
        Case{"curve_decreasing", ImpactScene,
             [](SceneSpec* s) { s->analysis.time.curve[1].first = 0; },
             "analysis.time.curve[1].time_s", "increase strictly"},
        Case{"curve_amplitude_nan", ImpactScene,
             [](SceneSpec* s) { s->analysis.time.curve[0].second = NAN; },
             "analysis.time.curve[0].amplitude", "finite"},
        Case{"time_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { s->analysis.time.end_time_s = 1; }, "analysis.time",
             "this one is DYNAMIC_RELAXATION"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

INSTANTIATE_TEST_SUITE_P(
    Controls, ValidateExplicitTest,
    ::testing::Values(
        Case{"factor_negative", ImpactScene,
             [](SceneSpec* s) { Controls(s).time_step_factor = -0.5; },
             "analysis.explicit_dynamics.time_step_factor", "(0, 2]"},
        Case{"factor_above_two", ImpactScene,
             [](SceneSpec* s) { Controls(s).time_step_factor = 2.5; },
             "analysis.explicit_dynamics.time_step_factor", "(0, 2]"},
        Case{"linear_viscosity_negative", ImpactScene,
             [](SceneSpec* s) { Controls(s).bulk_viscosity_linear = -0.1; },
             "analysis.explicit_dynamics.bulk_viscosity_linear", "[0, 10]"},
        Case{"quadratic_viscosity_nan", ImpactScene,
             [](SceneSpec* s) { Controls(s).bulk_viscosity_quadratic = NAN; },
             "analysis.explicit_dynamics.bulk_viscosity_quadratic", "finite"},
        Case{"quadratic_viscosity_huge", ImpactScene,
             [](SceneSpec* s) { Controls(s).bulk_viscosity_quadratic = 11; },
             "analysis.explicit_dynamics.bulk_viscosity_quadratic", "[0, 10]"},
        Case{"damping_negative", ImpactScene,
             [](SceneSpec* s) { Controls(s).mass_damping_per_s = -1; },
             "analysis.explicit_dynamics.mass_damping_per_s", "non-negative"},
        Case{"damping_infinite", ImpactScene,
             [](SceneSpec* s) { Controls(s).mass_damping_per_s = INFINITY; },
             "analysis.explicit_dynamics.mass_damping_per_s", "finite"},
        Case{"hourglass_above_half", ImpactScene,
             [](SceneSpec* s) { Controls(s).hourglass_coefficient = 0.6; },
             "analysis.explicit_dynamics.hourglass_coefficient", "[0, 0.5]"},
        Case{"output_interval_negative", ImpactScene,
             [](SceneSpec* s) { Controls(s).output_interval_s = -1e-5; },
             "analysis.explicit_dynamics.output_interval_s", "non-negative"},
        Case{"output_interval_beyond_end", ImpactScene,
             [](SceneSpec* s) { Controls(s).output_interval_s = 1; },
             "analysis.explicit_dynamics.output_interval_s", "must not exceed"},
        Case{"erosion_negative", ImpactScene, [](SceneSpec* s) { Controls(s).erosion_strain = -1; },
             "analysis.explicit_dynamics.erosion_strain", "non-negative"},
        Case{"mass_scaling_negative", ImpactScene,
             [](SceneSpec* s) { Controls(s).mass_scaling_step_s = -1e-7; },
             "analysis.explicit_dynamics.mass_scaling_step_s", "non-negative"},
        Case{"mass_scaling_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { Controls(s).mass_scaling_step_s = 1e-7; },
             "analysis.explicit_dynamics.mass_scaling_step_s", "belongs to EXPLICIT_DYNAMIC"},
        Case{"relaxation_tolerance_large", RelaxationScene,
             [](SceneSpec* s) { Controls(s).relaxation_tolerance = 0.1; },
             "analysis.explicit_dynamics.relaxation_tolerance", "[0, 0.1)"},
        // A field the analysis does not read, named as analysis.time is.
        Case{"relaxation_tolerance_in_dynamics", ImpactScene,
             [](SceneSpec* s) { Controls(s).relaxation_tolerance = 1e-4; },
             "analysis.explicit_dynamics.relaxation_tolerance",
             "belongs to DYNAMIC_RELAXATION; this analysis is EXPLICIT_DYNAMIC"},
        Case{"damping_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { Controls(s).mass_damping_per_s = 5; },
             "analysis.explicit_dynamics.mass_damping_per_s", "belongs to EXPLICIT_DYNAMIC"},
        Case{"erosion_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { Controls(s).erosion_strain = 1; },
             "analysis.explicit_dynamics.erosion_strain", "belongs to EXPLICIT_DYNAMIC"},
        Case{"output_interval_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { Controls(s).output_interval_s = 1; },
             "analysis.explicit_dynamics.output_interval_s", "belongs to EXPLICIT_DYNAMIC"},
        Case{"factor_in_linear_static", Linear,
             [](SceneSpec* s) { Controls(s).time_step_factor = 0.5; },
             "analysis.explicit_dynamics.time_step_factor",
             "belongs to EXPLICIT_DYNAMIC and DYNAMIC_RELAXATION; this analysis is LINEAR_STATIC"},
        Case{"viscosity_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { Controls(s).bulk_viscosity_quadratic = 1.5; },
             "analysis.explicit_dynamics.bulk_viscosity_quadratic", "belongs to EXPLICIT_DYNAMIC"},
        Case{"viscosity_in_nonlinear_static", Static,
             [](SceneSpec* s) { Controls(s).bulk_viscosity_linear = 0; },
             "analysis.explicit_dynamics.bulk_viscosity_linear",
             "this analysis is NONLINEAR_STATIC"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

INSTANTIATE_TEST_SUITE_P(
    ElementsAndMaterials, ValidateExplicitTest,
    ::testing::Values(
        Case{"tet10", ImpactScene, [](SceneSpec* s) { s->mesh.element = ElementType::kTet10; },
             "mesh.element", "TET10 is not implemented by the explicit engine"},
        Case{"tet10_md_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { s->mesh.element = ElementType::kTet10Md; }, "mesh.element",
             "DYNAMIC_RELAXATION takes TET4_ANP (the default), TET4 or HEX8"},
        Case{"hex8_full", ImpactScene,
             [](SceneSpec* s) { s->mesh.element = ElementType::kHex8Full; }, "mesh.element",
             "HEX8_FULL"},
        Case{"linear_material", ImpactScene,
             [](SceneSpec* s) {
               s->material.kind = MaterialSpec::Kind::kLinearElastic;
               s->material.linear_elastic = {3000, 0.45};
             },
             "material", "EXPLICIT_DYNAMIC needs a hyperelastic material"},
        Case{"linear_material_in_relaxation", RelaxationScene,
             [](SceneSpec* s) {
               s->material.kind = MaterialSpec::Kind::kLinearElastic;
               s->material.linear_elastic = {3000, 0.45};
             },
             "material", "DYNAMIC_RELAXATION needs a hyperelastic material"},
        Case{"no_density", ImpactScene, [](SceneSpec* s) { s->material.density_kg_per_m3 = 0; },
             "material.density_kg_per_m3", "positive mass density"},
        Case{"inclusion_without_density", ImpactScene,
             [](SceneSpec* s) {
               InclusionSpec core{"core", {5, 5, 10}, 2, Tissue(), 0};
               core.material.density_kg_per_m3 = 0;
               s->inclusions = {core};
             },
             "inclusions[0].material.density_kg_per_m3", "positive mass density"},
        Case{"auto_formulation", ImpactScene,
             [](SceneSpec* s) { s->formulation = Formulation::kAuto; }, "formulation",
             "AUTO is not available for EXPLICIT_DYNAMIC yet"},
        Case{"auto_formulation_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { s->formulation = Formulation::kAuto; }, "formulation",
             "AUTO is not available for DYNAMIC_RELAXATION yet"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

INSTANTIATE_TEST_SUITE_P(
    ConditionsAndContacts, ValidateExplicitTest,
    ::testing::Values(
        Case{"velocity_without_component", ImpactScene,
             [](SceneSpec* s) { s->boundary_conditions[0].velocity_m_per_s[2].reset(); },
             "boundary_conditions[0].velocity", "no component given"},
        Case{"velocity_infinite", ImpactScene,
             [](SceneSpec* s) { s->boundary_conditions[0].velocity_m_per_s[1] = INFINITY; },
             "boundary_conditions[0].velocity.y_m_per_s", "finite number of m/s"},
        Case{"velocity_in_relaxation", RelaxationScene,
             [](SceneSpec* s) {
               s->boundary_conditions[1].kind = BoundaryConditionSpec::Kind::kVelocity;
               s->boundary_conditions[1].velocity_m_per_s[2] = 1;
             },
             "boundary_conditions[1].velocity",
             "belongs to an EXPLICIT_DYNAMIC analysis; this one is DYNAMIC_RELAXATION"},
        Case{"velocity_in_nonlinear_static", Static,
             [](SceneSpec* s) {
               s->boundary_conditions[1].kind = BoundaryConditionSpec::Kind::kVelocity;
               s->boundary_conditions[1].velocity_m_per_s[0] = 1;
             },
             "boundary_conditions[1].velocity", "this one is NONLINEAR_STATIC"},
        Case{"relaxation_free_body", RelaxationScene,
             [](SceneSpec* s) { s->boundary_conditions.erase(s->boundary_conditions.begin()); },
             "boundary_conditions", "no condition holds the body"},
        Case{"contact_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { s->contacts = ImpactScene().contacts; }, "contacts[0]",
             "not supported by DYNAMIC_RELAXATION yet"},
        Case{"impactor_friction", ImpactScene, [](SceneSpec* s) { s->contacts[0].friction = 0.1; },
             "contacts[0].friction", "not modelled in EXPLICIT_DYNAMIC"},
        Case{"impactor_start_touching", ImpactScene,
             [](SceneSpec* s) { s->contacts[0].start_touching = true; },
             "contacts[0].start_touching", "not available in EXPLICIT_DYNAMIC"},
        Case{"cylinder_without_radius", ImpactScene,
             [](SceneSpec* s) { s->contacts[0].radius_mm = 0; }, "contacts[0].radius_mm",
             "a cylinder needs a positive radius"},
        Case{"flat_cylinder_zero_axis", ImpactScene,
             [](SceneSpec* s) {
               s->contacts[0].shape = ContactSpec::Shape::kCylinderFlat;
               s->contacts[0].axis = {0, 0, 0};
             },
             "contacts[0].axis", "must not be zero"},
        Case{"contact_in_linear_static", Linear,
             [](SceneSpec* s) { s->contacts = ImpactScene().contacts; }, "contacts",
             "NONLINEAR_STATIC, QUASI_STATIC or EXPLICIT_DYNAMIC"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

INSTANTIATE_TEST_SUITE_P(
    Sensors, ValidateExplicitTest,
    ::testing::Values(
        Case{"sensor_in_nonlinear_static", Static,
             [](SceneSpec* s) { s->outputs.sensors = ImpactScene().outputs.sensors; },
             "outputs.sensors",
             "belong to an EXPLICIT_DYNAMIC analysis; this one is "
             "NONLINEAR_STATIC"},
        Case{"sensor_in_relaxation", RelaxationScene,
             [](SceneSpec* s) { s->outputs.sensors = ImpactScene().outputs.sensors; },
             "outputs.sensors", "this one is DYNAMIC_RELAXATION"},
        Case{"filter_in_linear_static", Linear,
             [](SceneSpec* s) { s->outputs.filter_cutoff_hz = 100; }, "outputs.filter_cutoff_hz",
             "EXPLICIT_DYNAMIC"},
        Case{"sensor_without_name", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensors[1].name.clear(); }, "outputs.sensors[1].name",
             "needs a name"},
        Case{"sensor_name_with_a_space", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensors[0].name = "the centre"; },
             "outputs.sensors[0].name", "letters, digits"},
        Case{"sensor_name_twice", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensors[1].name = "centre"; }, "outputs.sensors[1].name",
             "already named 'centre'"},
        Case{"sensor_position_nan", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensors[0].position_mm[2] = NAN; },
             "outputs.sensors[0].position_mm[2]", "finite"},
        Case{"sensor_radius_negative", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensors[1].radius_mm = -1; },
             "outputs.sensors[1].radius_mm", "non-negative"},
        Case{"interval_negative", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensor_interval_s = -1e-6; },
             "outputs.sensor_interval_s", "non-negative"},
        Case{"interval_at_end", ImpactScene,
             [](SceneSpec* s) { s->outputs.sensor_interval_s = 2e-3; }, "outputs.sensor_interval_s",
             "below analysis.time.end_time_s"},
        Case{"filter_order_eleven", ImpactScene, [](SceneSpec* s) { s->outputs.filter_order = 11; },
             "outputs.filter_order", "1..10"},
        Case{"filter_order_negative", ImpactScene,
             [](SceneSpec* s) { s->outputs.filter_order = -1; }, "outputs.filter_order", "1..10"},
        Case{"cutoff_negative", ImpactScene, [](SceneSpec* s) { s->outputs.filter_cutoff_hz = -1; },
             "outputs.filter_cutoff_hz", "non-negative"},
        // Samples every 2 us: Nyquist 250 kHz.
        Case{"cutoff_at_nyquist", ImpactScene,
             [](SceneSpec* s) { s->outputs.filter_cutoff_hz = 2.5e5; }, "outputs.filter_cutoff_hz",
             "below half the sampling rate (250000 Hz"},
        // The default interval, 1 us: Nyquist 500 kHz.
        Case{"cutoff_above_default_nyquist", ImpactScene,
             [](SceneSpec* s) {
               s->outputs.sensor_interval_s = 0;
               s->outputs.filter_cutoff_hz = 6e5;
             },
             "outputs.filter_cutoff_hz", "(500000 Hz for samples every 1e-06 s"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

}  // namespace
}  // namespace pba
