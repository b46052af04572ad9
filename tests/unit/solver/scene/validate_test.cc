#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "pba/scene.h"

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
