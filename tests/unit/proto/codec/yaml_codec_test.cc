#include "codec/yaml_codec.h"

#include <gtest/gtest.h>

#include <string>

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

}  // namespace
}  // namespace pba::codec
