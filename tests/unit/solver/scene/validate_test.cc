#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>

#include "pba/scene.h"
#include "scene/unsolved.h"

namespace pba {
namespace {

SceneSpec GoodScene() {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 20};
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  BoundaryConditionSpec bottom;
  bottom.set = "bottom";
  bottom.kind = BoundaryConditionSpec::Kind::kFixed;
  BoundaryConditionSpec top;
  top.set = "top";
  top.kind = BoundaryConditionSpec::Kind::kDisplacement;
  top.displacement_mm[2] = -1.0;
  s.boundary_conditions = {bottom, top};
  return s;
}

struct Case {
  const char* label;
  std::function<void(SceneSpec*)> spoil;
  const char* field;
  const char* message_part;
};

class ValidateSceneTest : public ::testing::TestWithParam<Case> {};

TEST(ValidateSceneGoodTest, GoodSceneIsAccepted) { EXPECT_TRUE(ValidateScene(GoodScene()).ok()); }

TEST_P(ValidateSceneTest, NamesTheField) {
  SceneSpec scene = GoodScene();
  GetParam().spoil(&scene);
  const Status status = ValidateScene(scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), GetParam().field);
  EXPECT_NE(status.message().find(GetParam().message_part), std::string::npos) << status.message();
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ValidateSceneTest,
    ::testing::Values(
        Case{"no_geometry", [](SceneSpec* s) { s->geometry.kind = GeometrySpec::Kind::kNone; },
             "geometry", "no shape"},
        Case{"zero_box_edge", [](SceneSpec* s) { s->geometry.box.size_mm[1] = 0; },
             "geometry.box.size_mm", "positive"},
        Case{"nan_box_edge", [](SceneSpec* s) { s->geometry.box.size_mm[0] = NAN; },
             "geometry.box.size_mm", "positive"},
        Case{"negative_radius",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kCylinder;
               s->geometry.cylinder = {-1, 10};
             },
             "geometry.cylinder.radius_mm", "positive"},
        Case{"zero_height",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kCylinder;
               s->geometry.cylinder = {5, 0};
             },
             "geometry.cylinder.height_mm", "positive"},
        Case{"tet10_md_in_a_linear_analysis",
             [](SceneSpec* s) { s->mesh.element = ElementType::kTet10Md; }, "mesh.element",
             "TET10_MD (10-node tetrahedron with mean dilatation) is implemented for "
             "NONLINEAR_STATIC; a linear analysis uses TET10 or HEX8"},
        Case{"atlas_negative_voxel",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->geometry.atlas.voxel_size_mm = -1;
             },
             "geometry.atlas.voxel_size_mm", "positive"},
        Case{"atlas_roi_without_size",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->geometry.atlas.roi_radius_mm = 10;
             },
             "geometry.atlas.roi_element_size_mm", "region of interest"},
        Case{"atlas_surface_of_unknown_structure",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->boundary_conditions[0].set = "surface:Putamn";
             },
             "boundary_conditions[0].set", "no structure \"Putamn\""},
        Case{"atlas_interface_without_bar",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->boundary_conditions[0].set = "interface:Putamen";
             },
             "boundary_conditions[0].set", "interface:<structure>|<structure>"},
        Case{"atlas_interface_with_itself",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->boundary_conditions[0].set = "interface:Putamen|Putamen";
             },
             "boundary_conditions[0].set", "same structure twice"},
        Case{"atlas_set_of_a_structure_not_kept",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->geometry.atlas.structures = {"Putamen"};
               s->geometry.patches = {
                   PatchSpec::HalfSpace("low", "surface:Nucleus caudatus", {0, 0, 0}, {0, 0, -1})};
             },
             "geometry.patches[0].set", "not among geometry.atlas.structures"},
        Case{"atlas_surrounding_tissue_without_merge",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->geometry.atlas.structures = {"Putamen"};
               for (auto& bc : s->boundary_conditions) bc.set = "surface";
               s->outputs.reaction_sets = {"interface:Putamen|Surrounding tissue"};
             },
             "outputs.reaction_sets[0]", "merge_rest"},
        Case{"atlas_empty_structure",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->geometry.atlas.structures = {"Putamen", ""};
             },
             "geometry.atlas.structures[1]", "empty"},
        Case{"atlas_of_bricks",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kAtlas;
               s->mesh.element = ElementType::kHex8;
             },
             "mesh.element", "tetrahedra"},
        Case{"negative_size", [](SceneSpec* s) { s->mesh.element_size_mm = -1; },
             "mesh.element_size_mm", "positive"},
        Case{"too_many_elements", [](SceneSpec* s) { s->mesh.element_size_mm = 0.01; },
             "mesh.element_size_mm", "more than the limit"},
        Case{"no_material", [](SceneSpec* s) { s->material.kind = MaterialSpec::Kind::kNone; },
             "material", "no material"},
        Case{"negative_e", [](SceneSpec* s) { s->material.linear_elastic.youngs_modulus_pa = -5; },
             "material.linear_elastic.youngs_modulus_pa", "positive"},
        Case{"nu_half", [](SceneSpec* s) { s->material.linear_elastic.poissons_ratio = 0.5; },
             "material.linear_elastic.poissons_ratio", "hyperelastic"},
        Case{"nu_too_low", [](SceneSpec* s) { s->material.linear_elastic.poissons_ratio = -1; },
             "material.linear_elastic.poissons_ratio", "(-1, 0.5)"},
        Case{"orthotropic_nu12",
             [](SceneSpec* s) {
               s->material.kind = MaterialSpec::Kind::kOrthotropicElastic;
               s->material.orthotropic_elastic = {6000, 3000, 1500, 1.5, 0.35, 0.4, 1500, 900, 600};
             },
             "material.orthotropic_elastic.nu12", "sqrt(E1 / E2)"},
        Case{"orthotropic_nonlinear",
             [](SceneSpec* s) {
               s->material.kind = MaterialSpec::Kind::kOrthotropicElastic;
               s->material.orthotropic_elastic = {6000, 3000, 1500, 0.3, 0.35, 0.4, 1500, 900, 600};
               s->analysis.type = AnalysisSpec::Type::kNonlinearStatic;
             },
             "material", "LINEAR_STATIC only"},
        Case{"no_conditions", [](SceneSpec* s) { s->boundary_conditions.clear(); },
             "boundary_conditions", "free to move"},
        Case{"unknown_set", [](SceneSpec* s) { s->boundary_conditions[1].set = "lid"; },
             "boundary_conditions[1].set", "x_min"},
        Case{"cylinder_set_on_box", [](SceneSpec* s) { s->boundary_conditions[0].set = "side"; },
             "boundary_conditions[0].set", "unknown face set"},
        Case{"no_kind",
             [](SceneSpec* s) {
               s->boundary_conditions[1].kind = BoundaryConditionSpec::Kind::kNone;
             },
             "boundary_conditions[1]", "no condition"},
        Case{"no_component",
             [](SceneSpec* s) { s->boundary_conditions[1].displacement_mm[2].reset(); },
             "boundary_conditions[1].displacement", "no component"},
        Case{"infinite_component",
             [](SceneSpec* s) { s->boundary_conditions[1].displacement_mm[2] = INFINITY; },
             "boundary_conditions[1].displacement.z_mm", "finite"},
        Case{"direction_free",
             [](SceneSpec* s) {
               s->boundary_conditions[0].kind = BoundaryConditionSpec::Kind::kDisplacement;
               s->boundary_conditions[0].displacement_mm = {0.0, std::nullopt, 0.0};
             },
             "boundary_conditions", "direction y"},
        Case{"zero_semi_axis",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kEllipsoid;
               s->geometry.ellipsoid.semi_axes_mm = {70, 0, 50};
             },
             "geometry.ellipsoid.semi_axes_mm[1]", "positive"},
        Case{"patch_without_name",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("", "top", {5, 5, 20}, 3)};
             },
             "geometry.patches[0].name", "needs a name"},
        Case{"patch_named_like_a_set",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("top", "top", {5, 5, 20}, 3)};
             },
             "geometry.patches[0].name", "already a face set"},
        Case{"patch_named_twice",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("pad", "top", {5, 5, 20}, 3),
                                      PatchSpec::Ball("pad", "top", {5, 5, 20}, 4)};
             },
             "geometry.patches[1].name", "already a face set"},
        Case{"patch_of_unknown_set",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("pad", "lid", {5, 5, 20}, 3)};
             },
             "geometry.patches[0].set", "x_min"},
        Case{"patch_of_a_patch",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("pad", "top", {5, 5, 20}, 3),
                                      PatchSpec::Ball("dot", "pad", {5, 5, 20}, 1)};
             },
             "geometry.patches[1].set", "unknown face set 'pad'"},
        Case{"patch_centre_nan",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("pad", "top", {5, NAN, 20}, 3)};
             },
             "geometry.patches[0].centre_mm[1]", "finite"},
        Case{"patch_with_neither_ball_nor_half_space",
             [](SceneSpec* s) {
               PatchSpec p;
               p.name = "pad";
               p.set = "top";
               s->geometry.patches = {p};
             },
             "geometry.patches[0]", "a ball (centre_mm, radius_mm), a half-space"},
        Case{"patch_plane_normal_zero",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::HalfSpace("pad", "top", {0, 0, 5}, {0, 0, 0})};
             },
             "geometry.patches[0].plane_normal", "not be zero"},
        Case{"patch_plane_point_infinite",
             [](SceneSpec* s) {
               s->geometry.patches = {
                   PatchSpec::HalfSpace("pad", "top", {0, INFINITY, 5}, {0, 0, 1})};
             },
             "geometry.patches[0].plane_point_mm[1]", "finite"},
        Case{"patch_radius_zero",
             [](SceneSpec* s) {
               s->geometry.patches = {PatchSpec::Ball("pad", "top", {5, 5, 20}, 0)};
             },
             "geometry.patches[0].radius_mm", "positive"},
        Case{"symmetry_on_curved_patch",
             [](SceneSpec* s) {
               s->geometry.kind = GeometrySpec::Kind::kCylinder;
               s->geometry.cylinder = {5, 20};
               s->geometry.patches = {PatchSpec::Ball("pad", "side", {5, 0, 10}, 3)};
               s->boundary_conditions[1].set = "pad";
               s->boundary_conditions[1].kind = BoundaryConditionSpec::Kind::kSymmetry;
             },
             "boundary_conditions[1].symmetry", "curved"},
        Case{"bad_reaction_set",
             [](SceneSpec* s) {
               s->outputs.reaction_sets = {"top", "roof"};
             },
             "outputs.reaction_sets[1]", "roof"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

// A quasi-static scene on the synthetic atlas with every new field: a
// viscoelastic scene material, a tissue table, a region material, a growing
// inclusion, a punch, buoyancy, a time curve and structure displacements.
SceneSpec QuasiStaticScene() {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kAtlas;
  s.geometry.atlas.structures = {"Putamen", "Globus pallidus lateralis"};
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, 1e6};
  s.material.density_kg_per_m3 = 1040;
  s.material.viscoelastic.form = ViscoelasticSpec::Form::kProny;
  s.material.viscoelastic.g = {0.5, 0.2};
  s.material.viscoelastic.tau_s = {0.5, 5};
  s.material_library = "rat-brain-prony";

  RegionMaterialSpec putamen;
  putamen.structures = {"Putamen"};
  putamen.material.kind = MaterialSpec::Kind::kOgden;
  putamen.material.ogden.terms = {{842, -4.7}};
  putamen.material.ogden.bulk_modulus_pa = 8.42e8;
  putamen.material.viscoelastic.form = ViscoelasticSpec::Form::kExponential;
  putamen.material.viscoelastic.long_term_ratio = 0.3;
  putamen.material.viscoelastic.beta_per_s = 2;
  s.region_materials = {putamen};

  InclusionSpec tumour;
  tumour.name = "tumour";
  tumour.centre_mm = {0, 0, 2};
  tumour.radius_mm = 3;
  tumour.material.kind = MaterialSpec::Kind::kNeoHookean;
  tumour.material.neo_hookean = {3000, 3e6};
  tumour.material.viscoelastic.form = ViscoelasticSpec::Form::kModuli;
  tumour.material.viscoelastic.long_term_modulus_pa = 300;
  tumour.material.viscoelastic.moduli_pa = {500, 200};
  tumour.material.viscoelastic.tau_s = {0.1, 10};
  tumour.growth_strain = 0.1;
  s.inclusions = {tumour};

  BoundaryConditionSpec held;
  held.set = "surface";
  held.kind = BoundaryConditionSpec::Kind::kFixed;
  s.boundary_conditions = {held};

  ContactSpec punch;
  punch.name = "punch";
  punch.set = "surface:Putamen";
  punch.shape = ContactSpec::Shape::kFlatPunch;
  punch.position_mm = {0, 0, 20};
  punch.radius_mm = 3;
  punch.motion_mm = {0, 0, -2};
  punch.friction = 0.1;
  s.contacts = {punch};

  s.gravity.enabled = true;
  s.gravity.acceleration_m_per_s2 = {0, 0, -9.81};
  s.gravity.fluid_density_kg_per_m3 = 1007;
  s.gravity.fluid_level_mm = 10;

  s.analysis.type = AnalysisSpec::Type::kQuasiStatic;
  s.analysis.time.end_time_s = 10;
  s.analysis.time.initial_step_s = 0.5;
  s.analysis.time.min_step_s = 0.01;
  s.analysis.time.max_step_s = 2;
  s.analysis.time.curve = {{0, 0}, {5, 1}, {10, 1}};
  s.outputs.structure_displacements = {"Putamen", "tumour", "*"};
  return s;
}

// The quasi-static scene on a box: no atlas, so no tissue table, region
// materials or structures; the punch presses on top.
void ToBox(SceneSpec* s) {
  const SceneSpec box = GoodScene();
  s->geometry = box.geometry;
  s->boundary_conditions = box.boundary_conditions;
  s->material_library.clear();
  s->region_materials.clear();
  s->contacts[0].set = "top";
  s->outputs.structure_displacements.clear();
}

// Back to a linear static analysis (hyperelastic materials enter with their
// initial moduli): no time, no contacts, no growth.
void ToLinearStatic(SceneSpec* s) {
  s->analysis.type = AnalysisSpec::Type::kLinearStatic;
  s->analysis.time = TimeSpec();
  s->contacts.clear();
  s->inclusions[0].growth_strain = 0;
}

MaterialSpec Linear() {
  MaterialSpec m;
  m.kind = MaterialSpec::Kind::kLinearElastic;
  m.linear_elastic = {3000, 0.45};
  return m;
}

// A scene on an atlas other than the synthetic one (a snapshot, a label
// volume with its table) names that atlas's structures: checked against
// the names known before meshing, refused naming the nearest ones.
TEST(ValidateAtlasNamesTest, StructuresAreCheckedAgainstTheAtlasUsed) {
  SceneSpec s = QuasiStaticScene();
  s.material_library.clear();  // its tissues name the synthetic atlas's structures
  s.geometry.atlas.structures = {"Putamen_L", "Precentral"};
  s.region_materials[0].structures = {"Putamen_L"};
  s.contacts[0].set = "surface:Precentral_R";
  s.outputs.structure_displacements = {"Putamen_L", "Precentral", "tumour", "*"};
  // Unknown names with the synthetic atlas: refused as today.
  Status status = ValidateScene(s);
  EXPECT_NE(status.message().find("the synthetic atlas has no structure"), std::string::npos)
      << status.ToString();
  // A snapshot's names (the source left empty: the server stages it).
  s.geometry.atlas.known_structures = {"Putamen_L", "Putamen_R", "Precentral: left",
                                       "Precentral_R"};
  status = ValidateScene(s);
  EXPECT_NE(status.field(), "region_materials[0].structures[0]") << status.ToString();
  EXPECT_EQ(status.message().find("has no structure"), std::string::npos) << status.ToString();
  // surface:Precentral_R is not kept by geometry.atlas.structures.
  s.geometry.atlas.structures.push_back("Precentral_R");
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();

  s.region_materials[0].structures = {"Putamen_X"};
  status = ValidateScene(s);
  EXPECT_EQ(status.field(), "region_materials[0].structures[0]");
  EXPECT_NE(status.message().find("not among geometry.atlas.structures"), std::string::npos)
      << status.ToString();
  s.geometry.atlas.structures.clear();
  status = ValidateScene(s);
  EXPECT_EQ(status.field(), "region_materials[0].structures[0]");
  EXPECT_NE(status.message().find("the atlas (4 structures) has no structure \"Putamen_X\"; "
                                  "nearest names: \"Putamen_L\", \"Putamen_R\""),
            std::string::npos)
      << status.ToString();
  s.region_materials[0].structures = {"Putamen_L"};
  s.geometry.atlas.structures = {"Caudate_L"};
  status = ValidateScene(s);
  EXPECT_EQ(status.field(), "geometry.atlas.structures[0]");
  EXPECT_NE(status.message().find("has no structure \"Caudate_L\""), std::string::npos);

  // A label volume whose names are not known before meshing: not checked.
  s.geometry.atlas.structures.clear();
  s.geometry.atlas.known_structures.clear();
  s.geometry.atlas.source = "atlas.nii.gz";
  s.region_materials[0].structures = {"Anything"};
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
}

TEST(ValidateQuasiStaticGoodTest, EveryNewFieldIsAccepted) {
  const SceneSpec s = QuasiStaticScene();
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
}

TEST(ValidateQuasiStaticGoodTest, VariantsThatStayValid) {
  SceneSpec s = QuasiStaticScene();
  s.mesh.element = ElementType::kTet4Anp;  // a finite-strain element
  s.contacts[0].axis = {1, 1, -5};         // any length
  s.contacts[0].shape = ContactSpec::Shape::kPlane;
  s.contacts[0].radius_mm = 0;          // a plane has none
  s.analysis.time = {10, 0, 0, 0, {}};  // defaults and a ramp
  s.gravity.fluid_level_mm.reset();     // the fluid covers everything
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();

  s = QuasiStaticScene();
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;  // contacts and growth too
  s.analysis.time = TimeSpec();
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();

  s = QuasiStaticScene();
  ToBox(&s);
  s.outputs.structure_displacements = {"tumour", "*"};  // inclusions are structures
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
}

class ValidateQuasiStaticTest : public ::testing::TestWithParam<Case> {};

TEST_P(ValidateQuasiStaticTest, NamesTheField) {
  SceneSpec scene = QuasiStaticScene();
  GetParam().spoil(&scene);
  const Status status = ValidateScene(scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), GetParam().field) << status.ToString();
  EXPECT_NE(status.message().find(GetParam().message_part), std::string::npos) << status.message();
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ValidateQuasiStaticTest,
    ::testing::Values(
        // Viscoelasticity.
        Case{"viscoelastic_on_a_linear_model",
             [](SceneSpec* s) {
               ToLinearStatic(s);
               ToBox(s);
               ViscoelasticSpec v = s->material.viscoelastic;
               s->material = Linear();
               s->material.viscoelastic = v;
               s->inclusions.clear();
             },
             "material.viscoelastic", "only for hyperelastic models"},
        Case{"prony_negative_g", [](SceneSpec* s) { s->material.viscoelastic.g[1] = -0.1; },
             "material.viscoelastic.prony.g[1]", ">= 0"},
        Case{"prony_infinite_g", [](SceneSpec* s) { s->material.viscoelastic.g[0] = INFINITY; },
             "material.viscoelastic.prony.g[0]", "finite"},
        Case{"prony_sum_of_one",
             [](SceneSpec* s) {
               s->material.viscoelastic.g = {0.6, 0.4};
             },
             "material.viscoelastic.prony.g", "sum to less than 1"},
        Case{"prony_zero_tau", [](SceneSpec* s) { s->material.viscoelastic.tau_s[0] = 0; },
             "material.viscoelastic.prony.tau_s[0]", "> 0"},
        Case{"prony_sizes_differ", [](SceneSpec* s) { s->material.viscoelastic.tau_s = {0.5}; },
             "material.viscoelastic.prony.tau_s", "one relaxation time per g"},
        Case{"prony_no_terms",
             [](SceneSpec* s) {
               s->material.viscoelastic.g.clear();
               s->material.viscoelastic.tau_s.clear();
             },
             "material.viscoelastic.prony.g", "1 to 10"},
        Case{"prony_eleven_terms",
             [](SceneSpec* s) {
               s->material.viscoelastic.g.assign(11, 0.01);
               s->material.viscoelastic.tau_s.assign(11, 1);
             },
             "material.viscoelastic.prony.g", "1 to 10"},
        Case{"exponential_ratio_zero",
             [](SceneSpec* s) { s->region_materials[0].material.viscoelastic.long_term_ratio = 0; },
             "region_materials[0].material.viscoelastic.exponential.long_term_ratio", "(0, 1]"},
        Case{"exponential_ratio_above_one",
             [](SceneSpec* s) {
               s->region_materials[0].material.viscoelastic.long_term_ratio = 1.5;
             },
             "region_materials[0].material.viscoelastic.exponential.long_term_ratio", "(0, 1]"},
        Case{"exponential_beta_zero",
             [](SceneSpec* s) { s->region_materials[0].material.viscoelastic.beta_per_s = 0; },
             "region_materials[0].material.viscoelastic.exponential.beta_per_s", "> 0"},
        Case{"moduli_long_term_zero",
             [](SceneSpec* s) { s->inclusions[0].material.viscoelastic.long_term_modulus_pa = 0; },
             "inclusions[0].material.viscoelastic.moduli.long_term_modulus_pa", "> 0"},
        Case{"moduli_negative",
             [](SceneSpec* s) { s->inclusions[0].material.viscoelastic.moduli_pa[1] = -5; },
             "inclusions[0].material.viscoelastic.moduli.moduli_pa[1]", ">= 0"},
        Case{"moduli_sizes_differ",
             [](SceneSpec* s) { s->inclusions[0].material.viscoelastic.tau_s = {0.1}; },
             "inclusions[0].material.viscoelastic.moduli.tau_s", "one relaxation time"},
        // Region materials and the tissue table.
        Case{"material_library_without_atlas",
             [](SceneSpec* s) {
               ToBox(s);
               s->material_library = "rat-brain-prony";
             },
             "material_library", "geometry.atlas"},
        Case{"material_library_unknown",
             [](SceneSpec* s) { s->material_library = "no-such-tissue"; }, "material_library",
             "rat-brain-prony, brain-ogden-qlv"},
        Case{"region_materials_without_atlas",
             [](SceneSpec* s) {
               const auto regions = s->region_materials;
               ToBox(s);
               s->region_materials = regions;
             },
             "region_materials", "atlas"},
        Case{"region_without_structures",
             [](SceneSpec* s) { s->region_materials[0].structures.clear(); },
             "region_materials[0].structures", "lists no structure"},
        Case{"region_structure_empty",
             [](SceneSpec* s) { s->region_materials[0].structures = {""}; },
             "region_materials[0].structures[0]", "is empty"},
        Case{"region_structure_twice",
             [](SceneSpec* s) {
               s->region_materials.push_back(s->region_materials[0]);
               s->region_materials[1].structures = {"Globus pallidus lateralis", "Putamen"};
             },
             "region_materials[1].structures[1]",
             "already has a material (in region_materials[0])"},
        Case{"region_structure_not_kept",
             [](SceneSpec* s) { s->region_materials[0].structures = {"Caudate nucleus"}; },
             "region_materials[0].structures[0]", "not among geometry.atlas.structures"},
        Case{"region_material_invalid",
             [](SceneSpec* s) { s->region_materials[0].material.ogden.bulk_modulus_pa = 0; },
             "region_materials[0].material.ogden.bulk_modulus_pa", "> 0"},
        Case{"region_material_other_family",
             [](SceneSpec* s) { s->region_materials[0].material = Linear(); },
             "region_materials[0].material", "family"},
        // Inclusions.
        Case{"inclusion_without_name", [](SceneSpec* s) { s->inclusions[0].name.clear(); },
             "inclusions[0].name", "needs a name"},
        Case{"inclusion_named_twice",
             [](SceneSpec* s) { s->inclusions.push_back(s->inclusions[0]); }, "inclusions[1].name",
             "already the name of inclusions[0]"},
        Case{"inclusion_named_like_a_set", [](SceneSpec* s) { s->inclusions[0].name = "surface"; },
             "inclusions[0].name", "face set"},
        Case{"inclusion_named_like_a_structure",
             [](SceneSpec* s) { s->inclusions[0].name = "Putamen"; }, "inclusions[0].name",
             "atlas structure"},
        Case{"inclusion_centre_nan", [](SceneSpec* s) { s->inclusions[0].centre_mm[1] = NAN; },
             "inclusions[0].centre_mm[1]", "finite"},
        Case{"inclusion_radius_zero", [](SceneSpec* s) { s->inclusions[0].radius_mm = 0; },
             "inclusions[0].radius_mm", "positive"},
        Case{"inclusion_material_invalid",
             [](SceneSpec* s) { s->inclusions[0].material.neo_hookean.shear_modulus_pa = -1; },
             "inclusions[0].material.neo_hookean.shear_modulus_pa", "> 0"},
        Case{"inclusion_material_other_family",
             [](SceneSpec* s) { s->inclusions[0].material = Linear(); }, "inclusions[0].material",
             "family"},
        Case{"inclusion_density_negative",
             [](SceneSpec* s) { s->inclusions[0].material.density_kg_per_m3 = -1; },
             "inclusions[0].material.density_kg_per_m3", "non-negative"},
        Case{"inclusion_shrinks_to_nothing",
             [](SceneSpec* s) { s->inclusions[0].growth_strain = -1; },
             "inclusions[0].growth_strain", "above -1"},
        Case{"inclusion_growth_nan", [](SceneSpec* s) { s->inclusions[0].growth_strain = NAN; },
             "inclusions[0].growth_strain", "finite"},
        Case{"inclusion_growth_in_a_linear_analysis",
             [](SceneSpec* s) {
               ToLinearStatic(s);
               s->inclusions[0].growth_strain = 0.2;
             },
             "inclusions[0].growth_strain", "NONLINEAR_STATIC or QUASI_STATIC"},
        // Contacts.
        Case{"contact_without_name", [](SceneSpec* s) { s->contacts[0].name.clear(); },
             "contacts[0].name", "needs a name"},
        Case{"contact_named_twice", [](SceneSpec* s) { s->contacts.push_back(s->contacts[0]); },
             "contacts[1].name", "already the name of contacts[0]"},
        Case{"contact_unknown_set", [](SceneSpec* s) { s->contacts[0].set = "top"; },
             "contacts[0].set", "unknown face set 'top'"},
        Case{"contact_without_shape",
             [](SceneSpec* s) { s->contacts[0].shape = ContactSpec::Shape::kNone; },
             "contacts[0].shape", "no shape"},
        Case{"punch_radius_zero", [](SceneSpec* s) { s->contacts[0].radius_mm = 0; },
             "contacts[0].radius_mm", "positive radius"},
        Case{"sphere_radius_negative",
             [](SceneSpec* s) {
               s->contacts[0].shape = ContactSpec::Shape::kSphere;
               s->contacts[0].radius_mm = -2;
             },
             "contacts[0].radius_mm", "positive radius"},
        Case{"contact_axis_zero",
             [](SceneSpec* s) {
               s->contacts[0].axis = {0, 0, 0};
             },
             "contacts[0].axis", "must not be zero"},
        Case{"contact_axis_infinite", [](SceneSpec* s) { s->contacts[0].axis[2] = -INFINITY; },
             "contacts[0].axis[2]", "finite"},
        Case{"contact_friction_too_high", [](SceneSpec* s) { s->contacts[0].friction = 0.6; },
             "contacts[0].friction", "[0, 0.5]"},
        Case{"contact_friction_negative", [](SceneSpec* s) { s->contacts[0].friction = -0.1; },
             "contacts[0].friction", "[0, 0.5]"},
        Case{"contact_penalty_negative", [](SceneSpec* s) { s->contacts[0].penalty_factor = -1; },
             "contacts[0].penalty_factor", "non-negative"},
        Case{"contact_tolerance_negative",
             [](SceneSpec* s) { s->contacts[0].penetration_tolerance_mm = -0.1; },
             "contacts[0].penetration_tolerance_mm", "non-negative"},
        Case{"contact_in_a_linear_analysis",
             [](SceneSpec* s) {
               const auto contacts = s->contacts;
               ToLinearStatic(s);
               s->contacts = contacts;
             },
             "contacts", "NONLINEAR_STATIC, QUASI_STATIC or EXPLICIT_DYNAMIC"},
        // The quasi-static analysis and its time.
        Case{"quasi_static_linear_material",
             [](SceneSpec* s) {
               s->material = Linear();
               s->region_materials.clear();
               s->inclusions.clear();
             },
             "material", "QUASI_STATIC needs a hyperelastic material"},
        Case{"end_time_zero", [](SceneSpec* s) { s->analysis.time.end_time_s = 0; },
             "analysis.time.end_time_s", "positive end time"},
        Case{"end_time_infinite", [](SceneSpec* s) { s->analysis.time.end_time_s = INFINITY; },
             "analysis.time.end_time_s", "positive end time"},
        Case{"step_negative", [](SceneSpec* s) { s->analysis.time.initial_step_s = -1; },
             "analysis.time.initial_step_s", "non-negative"},
        Case{"min_step_nan", [](SceneSpec* s) { s->analysis.time.min_step_s = NAN; },
             "analysis.time.min_step_s", "non-negative"},
        Case{"min_step_above_initial", [](SceneSpec* s) { s->analysis.time.min_step_s = 1; },
             "analysis.time.min_step_s", "must not exceed initial_step_s (0.5 s)"},
        Case{"initial_step_above_max", [](SceneSpec* s) { s->analysis.time.initial_step_s = 3; },
             "analysis.time.initial_step_s", "must not exceed max_step_s (2 s)"},
        Case{"max_step_above_end", [](SceneSpec* s) { s->analysis.time.max_step_s = 20; },
             "analysis.time.max_step_s", "must not exceed end_time_s (10 s)"},
        // A max step of 1e-300 s ran until killed; floors at 1e-6 (max) and
        // 1e-9 (min, initial) of end_time_s (TimeOptions).
        Case{"max_step_tiny", [](SceneSpec* s) { s->analysis.time.max_step_s = 1e-300; },
             "analysis.time.max_step_s", "at least 1e-06 of end_time_s (1e-05 s)"},
        Case{"initial_step_tiny",
             [](SceneSpec* s) {
               s->analysis.time.min_step_s = 0;
               s->analysis.time.initial_step_s = 1e-300;
             },
             "analysis.time.initial_step_s", "at least 1e-09 of end_time_s (1e-08 s)"},
        Case{"min_step_tiny", [](SceneSpec* s) { s->analysis.time.min_step_s = 1e-300; },
             "analysis.time.min_step_s", "at least 1e-09 of end_time_s"},
        Case{"min_step_above_max_without_initial",
             [](SceneSpec* s) {
               s->analysis.time.initial_step_s = 0;
               s->analysis.time.min_step_s = 3;
             },
             "analysis.time.min_step_s", "must not exceed max_step_s"},
        Case{"curve_time_negative", [](SceneSpec* s) { s->analysis.time.curve[0].first = -1; },
             "analysis.time.curve[0].time_s", "non-negative"},
        Case{"curve_time_repeated", [](SceneSpec* s) { s->analysis.time.curve[2].first = 5; },
             "analysis.time.curve[2].time_s", "increase strictly"},
        Case{"curve_amplitude_nan", [](SceneSpec* s) { s->analysis.time.curve[1].second = NAN; },
             "analysis.time.curve[1].amplitude", "finite"},
        Case{
            "time_on_a_nonlinear_static_analysis",
            [](SceneSpec* s) { s->analysis.type = AnalysisSpec::Type::kNonlinearStatic; },
            "analysis.time",
            "belongs to a QUASI_STATIC or EXPLICIT_DYNAMIC analysis; this one is NONLINEAR_STATIC"},
        Case{"curve_on_a_linear_analysis",
             [](SceneSpec* s) {
               ToLinearStatic(s);
               s->analysis.time.curve = {{0, 0}, {1, 1}};
             },
             "analysis.time", "this one is LINEAR_STATIC"},
        // Buoyancy.
        Case{"fluid_density_negative",
             [](SceneSpec* s) { s->gravity.fluid_density_kg_per_m3 = -1; },
             "gravity.fluid_density_kg_per_m3", "non-negative"},
        Case{"fluid_level_infinite", [](SceneSpec* s) { s->gravity.fluid_level_mm = INFINITY; },
             "gravity.fluid_level_mm", "finite"},
        // Structure displacements.
        Case{"structure_displacement_without_atlas",
             [](SceneSpec* s) {
               ToBox(s);
               s->outputs.structure_displacements = {"tumour", "Putamen"};
             },
             "outputs.structure_displacements[1]", "only an atlas geometry"},
        Case{"structure_displacement_empty",
             [](SceneSpec* s) { s->outputs.structure_displacements = {""}; },
             "outputs.structure_displacements[0]", "is empty"},
        Case{"structure_displacement_not_kept",
             [](SceneSpec* s) { s->outputs.structure_displacements = {"Caudate nucleus"}; },
             "outputs.structure_displacements[0]", "not among geometry.atlas.structures"},
        // The rigid-body rule still holds with the new fields.
        Case{"still_free_to_slide",
             [](SceneSpec* s) {
               s->boundary_conditions[0].kind = BoundaryConditionSpec::Kind::kDisplacement;
               s->boundary_conditions[0].displacement_mm[2] = 0;
             },
             "boundary_conditions", "direction x, y"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

ProfileSpec Profile(std::string name) {
  ProfileSpec p;
  p.name = std::move(name);
  p.from_mm = {5, 5, 0};
  p.to_mm = {5, 5, 20};
  return p;
}

TEST(ValidateProfilesGoodTest, PointsDefaultAndRange) {
  SceneSpec s = GoodScene();
  s.outputs.profiles = {Profile("axis"), Profile("Radial_2-b")};
  s.outputs.profiles[1].points = 2;
  EXPECT_TRUE(ValidateScene(s).ok());
  s.outputs.profiles[1].points = 1000;
  // A line may leave the body: its points there are reported empty.
  s.outputs.profiles[0].to_mm = {5, 5, 100};
  EXPECT_TRUE(ValidateScene(s).ok());
  // Outputs only: the Abaqus export does not refuse them.
  EXPECT_TRUE(RefuseUnsupportedFields(s, "exported").ok());
}

INSTANTIATE_TEST_SUITE_P(
    Profiles, ValidateSceneTest,
    ::testing::Values(Case{"profile_name_empty",
                           [](SceneSpec* s) { s->outputs.profiles = {Profile("")}; },
                           "outputs.profiles[0].name", "is empty"},
                      Case{"profile_name_not_a_file_name",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("a"), Profile("../b")};
                           },
                           "outputs.profiles[1].name", "letters, digits"},
                      Case{"profile_name_with_a_space",
                           [](SceneSpec* s) { s->outputs.profiles = {Profile("radial line")}; },
                           "outputs.profiles[0].name", "letters, digits"},
                      Case{"profile_name_twice",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r"), Profile("q"), Profile("r")};
                           },
                           "outputs.profiles[2].name", "already named 'r'"},
                      Case{"profile_from_not_finite",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].from_mm[1] = NAN;
                           },
                           "outputs.profiles[0].from_mm", "y must be a finite number of mm"},
                      Case{"profile_to_infinite",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].to_mm[2] = INFINITY;
                           },
                           "outputs.profiles[0].to_mm", "z must be a finite number of mm"},
                      Case{"profile_ends_equal",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].to_mm = s->outputs.profiles[0].from_mm;
                           },
                           "outputs.profiles[0].to_mm", "same point as from_mm"},
                      Case{"profile_one_point",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].points = 1;
                           },
                           "outputs.profiles[0].points", "must be 2..1000"},
                      Case{"profile_too_many_points",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].points = 1001;
                           },
                           "outputs.profiles[0].points", "got 1001"},
                      Case{"profile_negative_points",
                           [](SceneSpec* s) {
                             s->outputs.profiles = {Profile("r")};
                             s->outputs.profiles[0].points = -5;
                           },
                           "outputs.profiles[0].points", "must be 2..1000"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

// Solved but not exported: the Abaqus export refuses each such field by
// name rather than write a deck without it.
TEST(RefuseUnsupportedFieldsTest, NamesTheFirstUnexportedField) {
  SceneSpec s = QuasiStaticScene();
  const auto refused = [&](const SceneSpec& scene) {
    const Status status = RefuseUnsupportedFields(scene, "exported");
    EXPECT_EQ(status.code(), Status::Code::kFailedPrecondition);
    return status.message().substr(0, status.message().find(':'));
  };
  EXPECT_EQ(refused(s), "analysis.type");
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  EXPECT_EQ(refused(s), "material_library");
  s.material_library.clear();
  EXPECT_EQ(refused(s), "region_materials");
  s.region_materials.clear();
  EXPECT_EQ(refused(s), "inclusions");
  s.inclusions.clear();
  EXPECT_EQ(refused(s), "contacts");
  s.contacts.clear();
  EXPECT_EQ(refused(s), "gravity.fluid_density_kg_per_m3");
  s.gravity.fluid_density_kg_per_m3 = 0;
  s.gravity.fluid_level_mm.reset();
  EXPECT_EQ(refused(s), "outputs.structure_displacements");
  s.outputs.structure_displacements.clear();
  EXPECT_TRUE(RefuseUnsupportedFields(s, "exported").ok());
}

TEST(FaceSetNamesTest, PerGeometry) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  EXPECT_EQ(FaceSetNames(g), (std::vector<std::string>{"bottom", "top", "side"}));
  g.kind = GeometrySpec::Kind::kBox;
  EXPECT_EQ(FaceSetNames(g).size(), 6u);
  g.kind = GeometrySpec::Kind::kEllipsoid;
  EXPECT_EQ(FaceSetNames(g), (std::vector<std::string>{"surface"}));
}

// A patch is a face set of its own: conditions and reactions may name it,
// and it is as planar as the set it is cut from.
TEST(FaceSetNamesTest, PatchesFollowTheGeometrysSets) {
  SceneSpec s = GoodScene();
  s.geometry.patches = {PatchSpec::Ball("pad", "top", {5, 5, 20}, 3)};
  EXPECT_EQ(FaceSetNames(s.geometry).back(), "pad");
  EXPECT_EQ(PlaneNormalAxis(s.geometry, "pad"), 2);
  s.boundary_conditions[1].set = "pad";
  s.outputs.reaction_sets = {"pad"};
  EXPECT_TRUE(ValidateScene(s).ok()) << ValidateScene(s).ToString();
}

}  // namespace
}  // namespace pba
