// The model builder on an atlas scene: the structures asked for become the
// mesh's regions, and the mesh note says what was kept, dropped or merged,
// at what sizes, and how well the mesh follows the plates.
#include "scene/model_builder.h"

#include <gtest/gtest.h>

#include <string>

#include "common/scene_builders.h"

namespace pba {
namespace {

SceneSpec AtlasScene(std::vector<std::string> structures) {
  SceneSpec s;
  s.name = "atlas";
  s.geometry.kind = GeometrySpec::Kind::kAtlas;
  s.geometry.atlas.voxel_size_mm = 2;
  s.geometry.atlas.structures = std::move(structures);
  s.mesh.element = ElementType::kTet4;
  s.mesh.element_size_mm = 4;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = {testing::Condition("surface", BoundaryConditionSpec::Kind::kFixed)};
  return s;
}

TEST(ModelBuilderAtlas, KeepsTheStructuresAskedForAndSaysSo) {
  Model model;
  ASSERT_TRUE(BuildModel(AtlasScene({"Putamen", "Globus pallidus lateralis"}), &model).ok());
  EXPECT_EQ(model.mesh.region_names,
            (std::vector<std::string>{"Globus pallidus lateralis", "Putamen"}));
  EXPECT_GT(model.mesh.num_elements(), 100);
  EXPECT_FALSE(model.mesh.face_sets.at("surface").triangles.empty());
  EXPECT_TRUE(model.mesh.face_sets.count("interface:Globus pallidus lateralis|Putamen"));
  const std::string& note = model.mesh_description;
  std::printf("%s\n", note.c_str());
  EXPECT_NE(note.find("synthetic atlas, 2 structures (as asked), 42 dropped"), std::string::npos)
      << note;
  EXPECT_NE(note.find("2 mm voxels, 4 mm elements, 2 mm on surfaces"), std::string::npos) << note;
  EXPECT_NE(note.find("against its plates"), std::string::npos) << note;
  // Every surface node is held.
  int prescribed = 0;
  for (int dof = 0; dof < model.dofs.num_dofs(); ++dof) prescribed += model.dofs.prescribed(dof);
  EXPECT_EQ(prescribed, 3 * static_cast<int>(model.mesh.face_sets.at("surface").nodes.size()));
}

TEST(ModelBuilderAtlas, AnUnknownStructureIsNamed) {
  Model model;
  const Status status = BuildModel(AtlasScene({"Putamen", "Claustrum"}), &model);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "geometry.atlas.structures[1]");
  EXPECT_NE(status.message().find("Claustrum"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace pba
