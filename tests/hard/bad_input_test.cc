// Hard cases: bad input through SolveScene. Each is refused before any work
// with kInvalidArgument naming the culprit field, or, for what only the mesh
// or the atlas's files can tell, with kFailedPrecondition naming it (a patch
// holding no face, a structure the atlas lacks, a rigid-body mode the
// supports leave).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using K = BoundaryConditionSpec::Kind;
using testing::Condition;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A valid scene: a neo-Hookean 10 mm cube, bottom fixed, top pressed 10 %.
SceneSpec GoodScene() {
  SceneSpec s;
  s.name = "good";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = 5;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, 1e5};
  s.boundary_conditions = {Condition("bottom", K::kFixed),
                           Condition("top", K::kDisplacement, {0.0, 0.0, -1.0})};
  s.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  return s;
}

struct BadCase {
  std::string name;
  std::function<void(SceneSpec*)> spoil;
  Status::Code code;
  std::string field;    // expected field path (kInvalidArgument)
  std::string mention;  // text the message must contain
};
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadInputTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInputTest, IsRefusedNamingTheCulprit) {
  const BadCase& c = GetParam();
  SceneSpec scene = GoodScene();
  c.spoil(&scene);
  Solution solution;
  const Status status = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_EQ(status.code(), c.code) << status.ToString();
  EXPECT_EQ(status.field(), c.field) << status.ToString();
  EXPECT_NE(status.message().find(c.mention), std::string::npos) << status.ToString();
  std::printf("%s -> %s\n", c.name.c_str(), status.ToString().c_str());
}

const std::string kShear = "material.neo_hookean.shear_modulus_pa";
const std::string kBulk = "material.neo_hookean.bulk_modulus_pa";
constexpr auto kInvalid = Status::Code::kInvalidArgument;
// A scene that validates fails later only for what the mesh shows.
constexpr auto kMeshed = Status::Code::kFailedPrecondition;

INSTANTIATE_TEST_SUITE_P(
    Cases, BadInputTest,
    ::testing::Values(
        BadCase{"nan_shear", [](SceneSpec* s) { s->material.neo_hookean.shear_modulus_pa = kNaN; },
                kInvalid, kShear, "finite"},
        BadCase{"negative_shear",
                [](SceneSpec* s) { s->material.neo_hookean.shear_modulus_pa = -1000; }, kInvalid,
                kShear, "-1000"},
        BadCase{"zero_shear", [](SceneSpec* s) { s->material.neo_hookean.shear_modulus_pa = 0; },
                kInvalid, kShear, "0"},
        BadCase{"nan_bulk", [](SceneSpec* s) { s->material.neo_hookean.bulk_modulus_pa = kNaN; },
                kInvalid, kBulk, "finite"},
        BadCase{"negative_bulk",
                [](SceneSpec* s) { s->material.neo_hookean.bulk_modulus_pa = -1e5; }, kInvalid,
                kBulk, "-100000"},
        BadCase{"zero_bulk", [](SceneSpec* s) { s->material.neo_hookean.bulk_modulus_pa = 0; },
                kInvalid, kBulk, "0"},
        BadCase{"infinite_bulk",
                [](SceneSpec* s) {
                  s->material.neo_hookean.bulk_modulus_pa = std::numeric_limits<double>::infinity();
                },
                kInvalid, kBulk, "finite"},
        BadCase{"nan_youngs_modulus",
                [](SceneSpec* s) {
                  s->analysis.type = AnalysisSpec::Type::kLinearStatic;
                  s->material.kind = MaterialSpec::Kind::kLinearElastic;
                  s->material.linear_elastic = {kNaN, 0.45};
                },
                kInvalid, "material.linear_elastic.youngs_modulus_pa", "nan"},
        BadCase{"poissons_ratio_one_half",
                [](SceneSpec* s) {
                  s->analysis.type = AnalysisSpec::Type::kLinearStatic;
                  s->material.kind = MaterialSpec::Kind::kLinearElastic;
                  s->material.linear_elastic = {3000, 0.5};
                },
                kInvalid, "material.linear_elastic.poissons_ratio", "hyperelastic"},
        BadCase{"nan_element_size", [](SceneSpec* s) { s->mesh.element_size_mm = kNaN; }, kInvalid,
                "mesh.element_size_mm", "nan"},
        BadCase{"negative_element_size", [](SceneSpec* s) { s->mesh.element_size_mm = -1; },
                kInvalid, "mesh.element_size_mm", "-1"},
        BadCase{"absurdly_small_element_size", [](SceneSpec* s) { s->mesh.element_size_mm = 1e-4; },
                kInvalid, "mesh.element_size_mm", "more than the limit"},
        BadCase{"nan_box_size", [](SceneSpec* s) { s->geometry.box.size_mm[1] = kNaN; }, kInvalid,
                "geometry.box.size_mm", "nan"},
        BadCase{"unknown_set", [](SceneSpec* s) { s->boundary_conditions[1].set = "lid"; },
                kInvalid, "boundary_conditions[1].set", "'lid'"},
        BadCase{"empty_set", [](SceneSpec* s) { s->boundary_conditions[0].set = ""; }, kInvalid,
                "boundary_conditions[0].set", "unknown face set ''"},
        BadCase{"unknown_reaction_set",
                [](SceneSpec* s) {
                  s->outputs.reaction_sets = {"top", "roof"};
                },
                kInvalid, "outputs.reaction_sets[1]", "'roof'"},
        BadCase{"nan_displacement",
                [](SceneSpec* s) { s->boundary_conditions[1].displacement_mm[2] = kNaN; }, kInvalid,
                "boundary_conditions[1].displacement.z_mm", "finite"},
        BadCase{"nan_pressure",
                [](SceneSpec* s) {
                  BoundaryConditionSpec p = Condition("top", K::kPressure);
                  p.pressure_pa = kNaN;
                  s->boundary_conditions[1] = p;
                },
                kInvalid, "boundary_conditions[1].pressure.pressure_pa", "nan"},
        // Under-constrained: only z held (rollers under the bottom, pressed
        // top), then only a pressure and no support at all.
        BadCase{"only_z_held",
                [](SceneSpec* s) {
                  s->boundary_conditions = {
                      Condition("bottom", K::kSymmetry),
                      Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -1.0})};
                },
                kInvalid, "boundary_conditions", "direction x, y"},
        BadCase{"only_pressure",
                [](SceneSpec* s) {
                  BoundaryConditionSpec p = Condition("top", K::kPressure);
                  p.pressure_pa = 100;
                  s->boundary_conditions = {p};
                },
                kInvalid, "boundary_conditions", "direction x, y, z"},
        // A patch smaller than the elements it should hold: only the mesh can
        // tell, and the message says what radius would do.
        BadCase{"patch_smaller_than_an_element",
                [](SceneSpec* s) {
                  s->geometry.patches = {PatchSpec::Ball("pad", "top", {5, 5, 10}, 2)};
                  s->boundary_conditions[1].set = "pad";
                },
                kMeshed, "geometry.patches[0].radius_mm", "at least 5"},
        // An atlas structure the atlas does not have: only building the
        // atlas can tell.
        BadCase{"atlas_structure_unknown",
                [](SceneSpec* s) {
                  s->geometry.kind = GeometrySpec::Kind::kAtlas;
                  s->geometry.atlas.voxel_size_mm = 3;
                  s->geometry.atlas.structures = {"Amygdala"};
                  s->boundary_conditions = {Condition("surface", K::kFixed)};
                },
                kMeshed, "geometry.atlas.structures[0]", "Amygdala"},
        BadCase{"atlas_label_volume_missing",
                [](SceneSpec* s) {
                  s->geometry.kind = GeometrySpec::Kind::kAtlas;
                  s->geometry.atlas.source = "no-such-dir/labels.nii.gz";
                  s->boundary_conditions = {Condition("surface", K::kFixed)};
                },
                Status::Code::kIo, "", "no-such-dir/labels.nii.gz"},
        BadCase{"no_conditions", [](SceneSpec* s) { s->boundary_conditions.clear(); }, kInvalid,
                "boundary_conditions", "free to move"},
        // Every direction is held somewhere, yet the body can turn about
        // the y axis through the edge x = 0, z = 0: x held on the bottom,
        // z on x_min and y on y_min all leave that rotation alone.
        BadCase{"free_rotation",
                [](SceneSpec* s) {
                  s->boundary_conditions = {
                      Condition("bottom", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
                      Condition("x_min", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
                      Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt})};
                },
                Status::Code::kFailedPrecondition, "", "rotation about y"}),
    [](const auto& info) { return info.param.name; });

// An element size of 0 is the documented default (a twentieth of the
// largest dimension), not an error.
TEST(BadInput, ZeroElementSizeMeansTheDefault) {
  SceneSpec scene = GoodScene();
  scene.mesh.element_size_mm = 0;
  scene.analysis.type = AnalysisSpec::Type::kLinearStatic;
  scene.material.kind = MaterialSpec::Kind::kLinearElastic;
  scene.material.linear_elastic = {3000, 0.45};
  Solution solution;
  const Status status = SolveScene(scene, SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_GT(solution.summary.elements, 0);
  bool noted = false;
  for (const std::string& note : solution.summary.notes) {
    noted |= note.find("element size 0.5 mm") != std::string::npos;
  }
  EXPECT_TRUE(noted);
}

}  // namespace
}  // namespace pba
