// The model builder on an atlas scene: the structures asked for become the
// mesh's regions, and the mesh note says what was kept, dropped or merged,
// at what sizes, and how well the mesh follows the plates.
#include "scene/model_builder.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "atlas/contours.h"
#include "atlas/plates.h"
#include "atlas/structure_set.h"
#include "common/scene_builders.h"
#include "mesh/mesh.h"
#include "mesh/quadratic.h"
#include "mesh/quality.h"
#include "pba/solve.h"

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

// Face sets from the atlas's geometry as condition targets: a structure's
// whole surface, an interface named in either order (the normal from the
// first structure into the second), a half-space of the outer surface.
TEST(ModelBuilderAtlas, StructureSurfacesInterfacesAndHalfSpacesAreTargets) {
  SceneSpec s = AtlasScene({"Putamen", "Globus pallidus lateralis"});
  s.geometry.patches = {PatchSpec::HalfSpace("low", "surface", {0, 0, -2}, {0, 0, -1})};
  s.boundary_conditions = {
      testing::Condition("low", BoundaryConditionSpec::Kind::kFixed),
      testing::Condition("surface:Putamen", BoundaryConditionSpec::Kind::kFixed),
      testing::Condition("interface:Putamen|Globus pallidus lateralis",
                         BoundaryConditionSpec::Kind::kFixed)};
  Model model;
  const Status status = BuildModel(s, &model);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const Mesh& mesh = model.mesh;
  // Every node of the low patch lies at or below z = -2 mm, and it holds
  // every surface face that does.
  const FaceSet& low = mesh.face_sets.at("low");
  ASSERT_FALSE(low.triangles.empty());
  // (A node within a nanometre of the plane counts as on it.)
  const double plane = -2e-3 + 1e-9;
  for (int n : low.nodes) EXPECT_LE(mesh.nodes(n, 2), plane);
  int below = 0;
  for (const auto& t : mesh.face_sets.at("surface").triangles) {
    below += mesh.nodes(t[0], 2) <= plane && mesh.nodes(t[1], 2) <= plane &&
             mesh.nodes(t[2], 2) <= plane;
  }
  EXPECT_EQ(static_cast<int>(low.triangles.size()), below);
  // The reversed interface: the same triangles, turned over.
  const FaceSet& forward = mesh.face_sets.at("interface:Globus pallidus lateralis|Putamen");
  const FaceSet& reversed = mesh.face_sets.at("interface:Putamen|Globus pallidus lateralis");
  ASSERT_EQ(forward.triangles.size(), reversed.triangles.size());
  for (std::size_t t = 0; t < forward.triangles.size(); ++t) {
    const auto& f = forward.triangles[t];
    EXPECT_EQ(reversed.triangles[t], (std::array<int, 3>{f[0], f[2], f[1]}));
  }
  EXPECT_EQ(forward.nodes, reversed.nodes);
  // The putamen's surface: its outer part and its interface with the
  // pallidus, so its area is theirs.
  const double putamen = FaceSetArea(mesh, mesh.face_sets.at("surface:Putamen"));
  const double pallidus = FaceSetArea(mesh, mesh.face_sets.at("surface:Globus pallidus lateralis"));
  const double outer = FaceSetArea(mesh, mesh.face_sets.at("surface"));
  const double between = FaceSetArea(mesh, forward);
  EXPECT_NEAR(putamen + pallidus, outer + 2 * between, 1e-9 * outer);
}

TEST(ModelBuilderAtlas, AnInterfaceBetweenStructuresThatDoNotTouchIsNamed) {
  SceneSpec s = AtlasScene({"Putamen", "Thalamus: pulvinar"});
  s.boundary_conditions.push_back(testing::Condition("interface:Putamen|Thalamus: pulvinar",
                                                     BoundaryConditionSpec::Kind::kFixed));
  Model model;
  const Status status = BuildModel(s, &model);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "boundary_conditions[1].set");
  EXPECT_NE(status.message().find("do not touch"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("'surface:Putamen'"), std::string::npos) << status.message();
}

// Model only what a scene needs: the thalamus (a group: its eleven
// nuclei) and the putamen alone, at the whole brain's element size, take
// at least five times fewer elements than the whole brain.
TEST(ModelBuilderAtlas, ThalamusAndPutamenTakeFiveTimesFewerElementsThanTheBrain) {
  SceneSpec part = AtlasScene({"Thalamus", "Putamen"});
  SceneSpec whole = AtlasScene({});
  part.mesh.element_size_mm = whole.mesh.element_size_mm = 6;
  Model model_part, model_whole;
  ASSERT_TRUE(BuildModel(part, &model_part).ok());
  ASSERT_TRUE(BuildModel(whole, &model_whole).ok());
  EXPECT_EQ(model_part.mesh.region_names.size(), 12u);
  EXPECT_TRUE(model_part.mesh.face_sets.count("surface:Thalamus: pulvinar"));
  const int part_elements = model_part.mesh.num_elements();
  const int whole_elements = model_whole.mesh.num_elements();
  std::printf("thalamus and putamen: %d elements; whole brain: %d (%.1fx)\n", part_elements,
              whole_elements, static_cast<double>(whole_elements) / part_elements);
  EXPECT_GE(whole_elements, 5 * part_elements);
}

// 10-node tetrahedra on the atlas: the mid-edge nodes of the surfaces and
// interfaces go onto the loft's smooth surfaces (over a third of them off their
// edges' midpoints), a patch cut before the upgrade shares them, every
// element stays within the Jacobian ratio bound, and the model solves.
TEST(ModelBuilderAtlas, TenNodeAtlasHasItsMidEdgeNodesOnTheLoftsSurfaces) {
  SceneSpec s = AtlasScene({"Putamen", "Globus pallidus lateralis"});
  s.mesh.element = ElementType::kTet10;
  s.geometry.patches = {PatchSpec::HalfSpace("low", "surface", {0, 0, -2}, {0, 0, -1})};
  BoundaryConditionSpec push =
      testing::Condition("surface:Putamen", BoundaryConditionSpec::Kind::kPressure);
  push.pressure_pa = 100;
  s.boundary_conditions = {testing::Condition("low", BoundaryConditionSpec::Kind::kFixed), push};
  Model model;
  const Status status = BuildModel(s, &model);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const Mesh& mesh = model.mesh;
  ASSERT_TRUE(mesh.quadratic());
  const std::string& note = model.mesh_description;
  std::printf("%s\n", note.c_str());
  EXPECT_NE(note.find("moved onto the loft's smooth surfaces"), std::string::npos) << note;
  // Mid-edge nodes of the outer surface off the middle of their edges.
  const FaceSet& surface = mesh.face_sets.at("surface");
  int off = 0, total = 0;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = mesh.nodes.row(surface.triangles[t][k]).transpose();
      const Eigen::Vector3d b = mesh.nodes.row(surface.triangles[t][(k + 1) % 3]).transpose();
      const Eigen::Vector3d m = mesh.nodes.row(surface.triangle_midside[t][k]).transpose();
      off += (m - 0.5 * (a + b)).norm() > 1e-3 * (b - a).norm();
      ++total;
    }
  }
  EXPECT_GT(3 * off, total) << off << " of " << total;
  // The patch's mid-edge nodes are the surface's own.
  const FaceSet& low = mesh.face_sets.at("low");
  ASSERT_FALSE(low.triangles.empty());
  std::map<std::array<int, 2>, int> surface_midside;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = surface.triangles[t][k], b = surface.triangles[t][(k + 1) % 3];
      surface_midside[{std::min(a, b), std::max(a, b)}] = surface.triangle_midside[t][k];
    }
  }
  for (std::size_t t = 0; t < low.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = low.triangles[t][k], b = low.triangles[t][(k + 1) % 3];
      EXPECT_EQ(low.triangle_midside[t][k], surface_midside.at({std::min(a, b), std::max(a, b)}));
    }
  }
  double worst = 1;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    worst = std::max(worst, Tet10MaxJacobianRatio(Tet10Coordinates(mesh, e)));
  }
  EXPECT_GT(worst, 1.01);
  EXPECT_LE(worst, 40);
  Solution solution;
  const Status solved = SolveScene(s, SolveOptions(), &solution);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  EXPECT_GT(solution.summary.max_displacement_mm, 0);
}

// The atlas mesh cache: a second build of the same scene takes the first's
// mesh from the cache, identical to the bit, patches and sets added after
// it as on a build; a 10-node scene is meshed as before and not cached.
TEST(ModelBuilderAtlas, ASecondBuildTakesTheSameMeshFromTheCache) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("pba_model_builder_cache_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  SceneSpec s = AtlasScene({"Putamen", "Globus pallidus lateralis"});
  s.geometry.patches = {PatchSpec::HalfSpace("low", "surface", {0, 0, -2}, {0, 0, -1})};
  s.boundary_conditions = {testing::Condition("low", BoundaryConditionSpec::Kind::kFixed),
                           testing::Condition("interface:Putamen|Globus pallidus lateralis",
                                              BoundaryConditionSpec::Kind::kFixed)};
  BuildModelOptions options;
  options.atlas_cache_dir = dir / "atlas";  // created by the first build
  const auto timed = [&](Model* model) {
    const auto start = std::chrono::steady_clock::now();
    const Status status = BuildModel(s, model, options);
    EXPECT_TRUE(status.ok()) << status.ToString();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  Model built, cached;
  const double built_s = timed(&built);
  const double cached_s = timed(&cached);
  std::printf("built in %.3f s, from the cache in %.3f s\n%s\n%s\n", built_s, cached_s,
              built.mesh_description.c_str(), cached.mesh_description.c_str());
  const std::string& first = built.mesh_description;
  const std::size_t built_note = first.find("; atlas mesh (built, cached as ");
  ASSERT_NE(built_note, std::string::npos) << first;
  const std::string key = first.substr(built_note + 31, 12);
  EXPECT_EQ(cached.mesh_description,
            first.substr(0, built_note) + "; atlas mesh from the cache (key " + key + ")");
  EXPECT_TRUE(fs::exists(options.atlas_cache_dir));

  const Mesh& a = built.mesh;
  const Mesh& b = cached.mesh;
  ASSERT_EQ(a.nodes.rows(), b.nodes.rows());
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(double)), 0);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.element_region, b.element_region);
  EXPECT_EQ(a.region_names, b.region_names);
  ASSERT_EQ(a.face_sets.size(), b.face_sets.size());
  for (const auto& [name, set] : a.face_sets) {
    ASSERT_TRUE(b.face_sets.count(name)) << name;
    EXPECT_EQ(set.triangles, b.face_sets.at(name).triangles) << name;
    EXPECT_EQ(set.nodes, b.face_sets.at(name).nodes) << name;
  }
  // The patch and the reversed interface exist on both paths.
  EXPECT_FALSE(b.face_sets.at("low").triangles.empty());
  EXPECT_TRUE(b.face_sets.count("interface:Putamen|Globus pallidus lateralis"));
  EXPECT_EQ(built.dofs.num_free(), cached.dofs.num_free());

  // 10-node: built as without a cache (the loft is needed), nothing stored.
  s.mesh.element = ElementType::kTet10;
  Model quadratic;
  ASSERT_TRUE(BuildModel(s, &quadratic, options).ok());
  EXPECT_EQ(quadratic.mesh_description.find("atlas mesh"), std::string::npos)
      << quadratic.mesh_description;
  EXPECT_EQ(
      std::distance(fs::directory_iterator(options.atlas_cache_dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(ModelBuilderAtlas, AnUnknownStructureIsNamed) {
  Model model;
  const Status status = BuildModel(AtlasScene({"Putamen", "Claustrum"}), &model);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "geometry.atlas.structures[1]");
  EXPECT_NE(status.message().find("Claustrum"), std::string::npos) << status.message();
}

// A scene's atlas source may be a structure set: composed (here from
// contours into plates, with an overlap noted) and meshed.
TEST(ModelBuilderAtlas, AStructureSetIsAnAtlasSource) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "model_builder_structure_set";
  fs::remove_all(dir);
  fs::create_directories(dir);
  StructureSet set;
  const auto add = [&](const std::string& name, double x0, double x1, uint8_t r) {
    Contours c;
    for (double z : {0.0, 4.0, 8.0, 12.0}) {
      c.plates.push_back({z, {{{x0, -8}, {x1, -8}, {x1, 8}, {x0, 8}}}});
    }
    std::ofstream(dir / (name + ".json")) << FormatContoursJson(c);
    StructureEntry e;
    e.name = name;
    e.file = name + ".json";
    e.r = r;
    e.g = e.b = 90;
    set.structures.push_back(e);
  };
  add("Right", -1, 16, 200);
  add("Left", -16, 0, 100);
  ASSERT_TRUE(WriteStructureSet(set, dir).ok());
  SceneSpec s = AtlasScene({});
  s.geometry.atlas.source = dir.string();
  Model model;
  const Status built = BuildModel(s, &model);
  ASSERT_TRUE(built.ok()) << built.ToString();
  EXPECT_EQ(model.mesh.region_names, (std::vector<std::string>{"Left", "Right"}));
  const std::string& note = model.mesh_description;
  EXPECT_NE(note.find("user atlas, 2 structures"), std::string::npos) << note;
  EXPECT_NE(note.find("Left and Right overlap on"), std::string::npos) << note;
  fs::remove_all(dir);
}

// The names a scene may use before its atlas is built are those the atlas
// has after its label steps and derived structures: a merge takes its
// parts, a drop its structures, an overlay adds what it lays.
TEST(ModelBuilderAtlas, KnownStructuresAreThoseTheStepsLeave) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "model_builder_known_structures";
  fs::remove_all(dir);
  fs::create_directories(dir / "set");
  std::ofstream(dir / "table.csv") << "label,name,r,g,b\n1,A,10,0,0\n2,B,20,0,0\n3,C,30,0,0\n"
                                      "4,G: x,40,0,0\n5,G: y,50,0,0\n";
  std::ofstream(dir / "over.csv") << "label,name,r,g,b\n1,T1,10,0,0\n2,T2,20,0,0\n";
  AtlasSpec a;
  a.source = (dir / "atlas.nii.gz").string();  // not read: the names come from the table
  a.colour_table = (dir / "table.csv").string();
  a.label_steps_json =
      "[{\"drop\": [\"A\"]}, {\"merge\": {\"structures\": [\"G\", \"B\"], \"name\": \"M\"}}, "
      "{\"rename\": {\"from\": \"C\", \"to\": \"Z\"}}, {\"fill\": {\"name\": \"W\"}}, "
      "{\"overlay\": {\"volume\": \"" +
      (dir / "over.nii.gz").string() + "\", \"table\": \"" + (dir / "over.csv").string() +
      "\", \"structures\": [\"T2\"]}}]";
  EXPECT_EQ(KnownAtlasStructures(a), (std::vector<std::string>{"Z", "M", "W", "T2"}));

  // A structure set with a derived merge.
  StructureSet set;
  uint8_t colour = 0;
  for (const char* name : {"Left", "Right", "Both"}) {
    StructureEntry e;
    e.name = name;
    e.file = std::string(name) + (e.name == "Both" ? ".yaml" : ".nii.gz");
    e.format = e.name == "Both" ? StructureFormat::kDerived : StructureFormat::kNifti;
    e.r = colour += 40;
    std::ofstream(dir / "set" / e.file) << (e.name == "Both" ? "merge: [Left]" : "mask");
    set.structures.push_back(e);
  }
  ASSERT_TRUE(WriteStructureSet(set, dir / "set").ok());
  AtlasSpec s;
  s.source = (dir / "set").string();
  EXPECT_EQ(KnownAtlasStructures(s), (std::vector<std::string>{"Right", "Both"}));
  // A recipe reading what is not there: none known (the build says why).
  std::ofstream(dir / "set" / "Both.yaml") << "merge: [Nowhere]";
  EXPECT_TRUE(KnownAtlasStructures(s).empty());

  // A plate directory: its colour table's names.
  LabelVolume volume({6, 6, 6}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  volume.set(2, 2, 2, 1);
  volume.set(3, 3, 3, 2);
  ColourTable table;
  ASSERT_TRUE(ColourTable::FromEntries({{1, "P", 10, 0, 0}, {2, "Q", 20, 0, 0}}, &table).ok());
  PlateOptions plates;
  plates.z_mm = {2, 3};
  ASSERT_TRUE(WritePlates(volume, table, plates, dir / "plates").ok());
  AtlasSpec p;
  p.source = (dir / "plates").string();
  EXPECT_EQ(KnownAtlasStructures(p), (std::vector<std::string>{"P", "Q"}));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pba

namespace pba {
namespace {

// An inverted patch is its set less the ball: a plate's face with a hole.
TEST(ModelBuilderPatches, InvertedBallIsTheSetLessTheBall) {
  SceneSpec s;
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 10};
  s.mesh.element_size_mm = 1;
  PatchSpec hole = PatchSpec::Ball("hole", "top", {5, 5, 10}, 2);
  PatchSpec plate = hole;
  plate.name = "plate";
  plate.invert = true;
  s.geometry.patches = {hole, plate};
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {1000, 0.3};
  s.boundary_conditions = {testing::Condition("bottom", BoundaryConditionSpec::Kind::kFixed)};
  Model model;
  const Status status = BuildModel(s, &model);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const Mesh& mesh = model.mesh;
  const FaceSet& top = mesh.face_sets.at("top");
  const FaceSet& in = mesh.face_sets.at("hole");
  const FaceSet& out = mesh.face_sets.at("plate");
  EXPECT_EQ(in.triangles.size() + out.triangles.size(), top.triangles.size());
  EXPECT_NEAR(FaceSetArea(mesh, in) + FaceSetArea(mesh, out), FaceSetArea(mesh, top), 1e-15);
  // Every plate face has a corner outside the hole.
  for (const auto& t : out.triangles) {
    bool outside = false;
    for (int n : t)
      outside |= (mesh.nodes.row(n).transpose() - Eigen::Vector3d(5e-3, 5e-3, 10e-3)).norm() > 2e-3;
    EXPECT_TRUE(outside);
  }
}

}  // namespace
}  // namespace pba
