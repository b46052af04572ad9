#include "codec/yaml_codec.h"

#include <gtest/gtest.h>

#include <string>

#include "common/yaml_bombs.h"
#include "pba/v1/scene.pb.h"

namespace pba::codec {
namespace {

constexpr const char* kScene = R"(
name: block
geometry:
  box:
    size_mm: [10, 10, 20]
mesh:
  element: tet4
  element_size_mm: 2.5
material:
  name: tissue
  linear_elastic:
    youngs_modulus_pa: 3.0e3
    poissons_ratio: 0.45
boundary_conditions:
  - set: bottom
    fixed: {}
  - set: top
    displacement: {z_mm: -1}
outputs:
  fields: [displacement, VON_MISES]
)";

TEST(YamlCodecTest, ReadsEveryKindOfField) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(kScene, &scene, &error)) << error.ToString();
  EXPECT_EQ(scene.name(), "block");
  ASSERT_EQ(scene.geometry().box().size_mm_size(), 3);
  EXPECT_DOUBLE_EQ(scene.geometry().box().size_mm(2), 20.0);
  EXPECT_EQ(scene.mesh().element(), v1::MeshOptions::TET4);
  EXPECT_DOUBLE_EQ(scene.material().linear_elastic().youngs_modulus_pa(), 3000.0);
  ASSERT_EQ(scene.boundary_conditions_size(), 2);
  EXPECT_TRUE(scene.boundary_conditions(0).has_fixed());
  const auto& displacement = scene.boundary_conditions(1).displacement();
  EXPECT_FALSE(displacement.has_x_mm());
  ASSERT_TRUE(displacement.has_z_mm());
  EXPECT_DOUBLE_EQ(displacement.z_mm(), -1.0);
  ASSERT_EQ(scene.outputs().fields_size(), 2);
  EXPECT_EQ(scene.outputs().fields(1), v1::Outputs::VON_MISES);
}

TEST(YamlCodecTest, JsonIsAcceptedWithCamelCaseNames) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(R"({"name": "j", "material": {"linearElastic": {"youngsModulusPa": 5}}})",
                        &scene, &error))
      << error.ToString();
  EXPECT_DOUBLE_EQ(scene.material().linear_elastic().youngs_modulus_pa(), 5.0);
}

struct BadCase {
  const char* label;
  const char* yaml;
  const char* field;
  const char* message_part;
  int line;
};

class YamlCodecBadInputTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(YamlCodecBadInputTest, NamesFieldAndLine) {
  const BadCase& c = GetParam();
  v1::Scene scene;
  ParseError error;
  ASSERT_FALSE(ParseYaml(c.yaml, &scene, &error));
  EXPECT_EQ(error.field, c.field);
  EXPECT_NE(error.message.find(c.message_part), std::string::npos) << error.message;
  EXPECT_EQ(error.line, c.line);
  EXPECT_NE(error.ToString().find(c.field), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, YamlCodecBadInputTest,
    ::testing::Values(
        BadCase{"unknown_top", "name: a\ncolour: red\n", "colour", "unknown field 'colour'", 2},
        BadCase{"unknown_nested", "material:\n  linear_elastic:\n    youngs_modulus: 3\n",
                "material.linear_elastic.youngs_modulus", "expected one of: youngs_modulus_pa", 3},
        BadCase{"wrong_type_string", "material:\n  linear_elastic:\n    poissons_ratio: high\n",
                "material.linear_elastic.poissons_ratio", "expected a number, got 'high'", 3},
        BadCase{"quoted_number", "material:\n  linear_elastic:\n    youngs_modulus_pa: \"3000\"\n",
                "material.linear_elastic.youngs_modulus_pa", "got the string '3000'", 3},
        BadCase{"list_expected", "geometry:\n  box:\n    size_mm: 10\n", "geometry.box.size_mm",
                "expected a list", 3},
        BadCase{"mapping_expected", "geometry: box\n", "geometry", "expected a mapping", 1},
        BadCase{"element_in_list", "boundary_conditions:\n  - set: top\n  - sett: bottom\n",
                "boundary_conditions[1].sett", "unknown field", 3},
        BadCase{"bad_enum", "analysis:\n  type: dynamic\n", "analysis.type",
                "expected one of: LINEAR_STATIC", 2},
        BadCase{"two_oneof", "geometry:\n  box: {size_mm: [1, 1, 1]}\n  cylinder: {radius_mm: 1}\n",
                "geometry.cylinder", "only one of the shape choices", 3},
        BadCase{"scalar_for_message", "mesh: 3\n", "mesh", "expected a mapping", 1},
        BadCase{"duplicate_key", "name: a\nmesh: {}\nname: b\n", "name", "given twice", 3}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.label); });

TEST(YamlCodecTest, SyntaxErrorGivesLine) {
  v1::Scene scene;
  ParseError error;
  ASSERT_FALSE(ParseYaml("name: [unclosed\nmesh: {}\n", &scene, &error));
  EXPECT_NE(error.message.find("not valid YAML"), std::string::npos);
  EXPECT_GT(error.line, 0);
}

TEST(YamlCodecTest, AliasesAreRefusedNamingTheAliasAndLine) {
  // A scene of nested aliases once ran the client out of memory.
  const std::string bomb = yaml_bombs::BillionLaughs();
  v1::Scene scene;
  ParseError error;
  EXPECT_FALSE(ParseYaml(bomb + "name: *l9\n", &scene, &error));
  EXPECT_EQ(error.line, 2);
  EXPECT_EQ(error.ToString().rfind("line 2: YAML aliases (*l0) are not accepted", 0), 0u)
      << error.ToString();

  // A harmless-looking one too: an anchored material reused.
  EXPECT_FALSE(
      ParseYaml("name: a\nmaterial: &m {linear_elastic: {youngs_modulus_pa: 5}}\n"
                "x: *m\n",
                &scene, &error));
  EXPECT_EQ(error.line, 3);
  EXPECT_NE(error.message.find("(*m)"), std::string::npos) << error.ToString();
}

TEST(YamlCodecTest, EmptyDocumentIsAnError) {
  v1::Scene scene;
  ParseError error;
  EXPECT_FALSE(ParseYaml("", &scene, &error));
  EXPECT_NE(error.message.find("empty"), std::string::npos);
}

TEST(YamlCodecTest, MissingFileNamesThePath) {
  v1::Scene scene;
  ParseError error;
  EXPECT_FALSE(ReadYamlFile("/nonexistent/scene.yaml", &scene, &error));
  EXPECT_NE(error.ToString().find("/nonexistent/scene.yaml"), std::string::npos);
}

TEST(YamlCodecTest, JsonRoundTrip) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(kScene, &scene, &error));
  v1::Scene again;
  ASSERT_TRUE(ParseYaml(ToJson(scene), &again, &error)) << error.ToString();
  EXPECT_EQ(scene.SerializeAsString(), again.SerializeAsString());
}

// Every key added for time, viscoelasticity, region materials, inclusions,
// contacts, buoyancy and structure displacements.
constexpr const char* kQuasiStaticScene = R"(
name: punch-and-tumour
geometry:
  atlas: {structures: [Putamen, Globus pallidus lateralis]}
material:
  neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1.0e6}
  density_kg_per_m3: 1040
  viscoelastic:
    prony: {g: [0.5, 0.2], tau_s: [0.5, 5]}
material_library: rat-brain-prony
region_materials:
  - structures: [Putamen]
    material:
      ogden: {terms: [{mu_pa: 842, alpha: -4.7}], bulk_modulus_pa: 8.42e8}
      viscoelastic: {exponential: {long_term_ratio: 0.3, beta_per_s: 2}}
inclusions:
  - name: tumour
    centre_mm: [0, 0, 2]
    radius_mm: 3
    growth_strain: 0.1
    material:
      neo_hookean: {shear_modulus_pa: 3000, bulk_modulus_pa: 3.0e6}
      viscoelastic:
        moduli: {long_term_modulus_pa: 300, moduli_pa: [500, 200], tau_s: [0.1, 10]}
boundary_conditions:
  - {set: surface, fixed: {}}
contacts:
  - name: punch
    set: "surface:Putamen"
    shape: flat_punch
    position_mm: [0, 0, 20]
    axis: [0, 0, -1]
    radius_mm: 3
    motion_mm: [0, 0, -2]
    friction: 0.1
    penalty_factor: 50
    penetration_tolerance_mm: 0.01
gravity:
  acceleration_m_per_s2: [0, 0, -9.81]
  fluid_density_kg_per_m3: 1007
  fluid_level_mm: 10
analysis:
  type: quasi_static
  time:
    end_time_s: 10
    initial_step_s: 0.5
    min_step_s: 0.01
    max_step_s: 2
    curve: [{time_s: 0, amplitude: 0}, {time_s: 5, amplitude: 1}, {time_s: 10, amplitude: 1}]
outputs:
  structure_displacements: [Putamen, tumour]
)";

TEST(YamlCodecTest, NewSceneKeysRoundTrip) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(kQuasiStaticScene, &scene, &error)) << error.ToString();
  EXPECT_EQ(scene.material().viscoelastic().prony().tau_s(1), 5.0);
  EXPECT_EQ(scene.material_library(), "rat-brain-prony");
  ASSERT_EQ(scene.region_materials_size(), 1);
  EXPECT_EQ(scene.region_materials(0).material().viscoelastic().exponential().beta_per_s(), 2.0);
  ASSERT_EQ(scene.inclusions_size(), 1);
  EXPECT_EQ(scene.inclusions(0).material().viscoelastic().moduli().moduli_pa(0), 500.0);
  EXPECT_EQ(scene.inclusions(0).growth_strain(), 0.1);
  ASSERT_EQ(scene.contacts_size(), 1);
  EXPECT_EQ(scene.contacts(0).shape(), v1::Contact::FLAT_PUNCH);
  EXPECT_EQ(scene.contacts(0).set(), "surface:Putamen");
  EXPECT_EQ(scene.contacts(0).penetration_tolerance_mm(), 0.01);
  EXPECT_EQ(scene.gravity().fluid_density_kg_per_m3(), 1007.0);
  ASSERT_TRUE(scene.gravity().has_fluid_level_mm());
  EXPECT_EQ(scene.gravity().fluid_level_mm(), 10.0);
  EXPECT_EQ(scene.analysis().type(), v1::Analysis::QUASI_STATIC);
  ASSERT_EQ(scene.analysis().time().curve_size(), 3);
  EXPECT_EQ(scene.analysis().time().curve(1).time_s(), 5.0);
  EXPECT_EQ(scene.outputs().structure_displacements(1), "tumour");

  v1::Scene again;
  ASSERT_TRUE(ParseYaml(ToJson(scene), &again, &error)) << error.ToString();
  EXPECT_EQ(scene.SerializeAsString(), again.SerializeAsString());
}

TEST(YamlCodecTest, ProfilesRoundTrip) {
  const std::string yaml = std::string(kScene) + R"(  profiles:
    - {name: radial, from_mm: [0, 0, 0], to_mm: [12.5, 0, 0], points: 120}
    - name: axis
      from_mm: [5, 5, 0]
      to_mm: [5, 5, 20]
)";
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(yaml, &scene, &error)) << error.ToString();
  ASSERT_EQ(scene.outputs().profiles_size(), 2);
  EXPECT_EQ(scene.outputs().profiles(0).name(), "radial");
  ASSERT_EQ(scene.outputs().profiles(0).to_mm_size(), 3);
  EXPECT_EQ(scene.outputs().profiles(0).to_mm(0), 12.5);
  EXPECT_EQ(scene.outputs().profiles(0).points(), 120);
  EXPECT_EQ(scene.outputs().profiles(1).points(), 0);
  EXPECT_EQ(scene.outputs().profiles(1).from_mm(1), 5.0);
  v1::Scene again;
  ASSERT_TRUE(ParseYaml(ToJson(scene), &again, &error)) << error.ToString();
  EXPECT_EQ(scene.SerializeAsString(), again.SerializeAsString());
  // A misspelt key names its path.
  EXPECT_FALSE(ParseYaml(std::string(kScene) + "  profiles: [{name: r, form_mm: [0, 0, 0]}]\n",
                         &scene, &error));
  EXPECT_NE(error.ToString().find("outputs.profiles[0].form_mm"), std::string::npos)
      << error.ToString();
}

// An impact: the explicit controls (a bulk viscosity given as 0 is given),
// a piston's velocity, a bolt and two sensors.
constexpr const char* kExplicitScene = R"(
name: impact
geometry: {box: {size_mm: [10, 10, 20]}}
mesh: {element: HEX8}
material: {density_kg_per_m3: 1040, neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
boundary_conditions:
  - {set: bottom, velocity: {z_m_per_s: 2.5}}
contacts:
  - {name: bolt, set: top, shape: CYLINDER_ROUNDED, position_mm: [5, 5, 21], radius_mm: 2,
     motion_mm: [0, 0, -5]}
analysis:
  type: EXPLICIT_DYNAMIC
  time: {end_time_s: 0.002, curve: [{time_s: 0, amplitude: 0}, {time_s: 0.001, amplitude: 1}]}
  explicit_dynamics:
    time_step_factor: 0.6
    bulk_viscosity_quadratic: 0
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
  filter_order: 4
)";

TEST(YamlCodecTest, ExplicitSceneKeysRoundTrip) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml(kExplicitScene, &scene, &error)) << error.ToString();
  EXPECT_EQ(scene.analysis().type(), v1::Analysis::EXPLICIT_DYNAMIC);
  const v1::ExplicitDynamics& e = scene.analysis().explicit_dynamics();
  EXPECT_EQ(e.time_step_factor(), 0.6);
  EXPECT_FALSE(e.has_bulk_viscosity_linear());
  ASSERT_TRUE(e.has_bulk_viscosity_quadratic());
  EXPECT_EQ(e.bulk_viscosity_quadratic(), 0.0);
  EXPECT_EQ(e.mass_damping_per_s(), 10.0);
  EXPECT_EQ(e.hourglass_coefficient(), 0.1);
  EXPECT_EQ(e.output_interval_s(), 1e-5);
  EXPECT_EQ(e.erosion_strain(), 1.5);
  EXPECT_EQ(e.relaxation_tolerance(), 0.0);
  ASSERT_EQ(scene.boundary_conditions_size(), 1);
  const v1::Velocity& v = scene.boundary_conditions(0).velocity();
  EXPECT_FALSE(v.has_x_m_per_s());
  ASSERT_TRUE(v.has_z_m_per_s());
  EXPECT_EQ(v.z_m_per_s(), 2.5);
  ASSERT_EQ(scene.contacts_size(), 1);
  EXPECT_EQ(scene.contacts(0).shape(), v1::Contact::CYLINDER_ROUNDED);
  ASSERT_EQ(scene.outputs().sensors_size(), 2);
  EXPECT_EQ(scene.outputs().sensors(1).name(), "low");
  EXPECT_EQ(scene.outputs().sensors(1).position_mm(2), 2.0);
  EXPECT_EQ(scene.outputs().sensors(1).radius_mm(), 1.5);
  EXPECT_EQ(scene.outputs().sensor_interval_s(), 2e-6);
  EXPECT_EQ(scene.outputs().filter_cutoff_hz(), 5000.0);
  EXPECT_EQ(scene.outputs().filter_order(), 4);

  v1::Scene again;
  ASSERT_TRUE(ParseYaml(ToJson(scene), &again, &error)) << error.ToString();
  EXPECT_EQ(scene.SerializeAsString(), again.SerializeAsString());
  // The lower-case spellings of the new enum values, as of the old ones.
  ASSERT_TRUE(ParseYaml(
      "analysis: {type: dynamic_relaxation}\ncontacts: [{shape: cylinder_flat}]\n", &scene, &error))
      << error.ToString();
  EXPECT_EQ(scene.analysis().type(), v1::Analysis::DYNAMIC_RELAXATION);
  EXPECT_EQ(scene.contacts(0).shape(), v1::Contact::CYLINDER_FLAT);
  // A misspelt key names its path.
  EXPECT_FALSE(ParseYaml("analysis: {explicit_dynamics: {time_step: 0.5}}\n", &scene, &error));
  EXPECT_EQ(error.field, "analysis.explicit_dynamics.time_step");
}

TEST(YamlCodecTest, FluidLevelZeroIsGiven) {
  v1::Scene scene;
  ParseError error;
  ASSERT_TRUE(ParseYaml("gravity: {fluid_level_mm: 0}\n", &scene, &error)) << error.ToString();
  EXPECT_TRUE(scene.gravity().has_fluid_level_mm());
  ASSERT_TRUE(ParseYaml("gravity: {fluid_density_kg_per_m3: 1007}\n", &scene, &error));
  EXPECT_FALSE(scene.gravity().has_fluid_level_mm());
}

TEST(YamlCodecTest, TwoRelaxationFormsAreRefused) {
  v1::Scene scene;
  ParseError error;
  EXPECT_FALSE(ParseYaml(
      "material:\n  viscoelastic:\n    prony: {g: [0.5], tau_s: [1]}\n    exponential: {}\n",
      &scene, &error));
  EXPECT_EQ(error.field, "material.viscoelastic.exponential");
}

}  // namespace
}  // namespace pba::codec
