// The element-shape table (mesh/element_shape.h) and Mesh::shape(),
// ElementNodes and ElementCorners on 4-node, 10-node and brick meshes; and
// that the writers name each shape as the table does: the mesh export's
// .xdmf, .vtu, .msh and .inp, and the CalculiX deck of a scene.
#include "mesh/element_shape.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/finite_strain_checks.h"
#include "common/subprocess.h"
#include "io/mesh_export.h"
#include "mesh/mesh.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {
namespace fs = std::filesystem;
using testing::TempDir;

// A 4 x 4 x 6 mm box of 2 mm elements of `shape`.
Mesh Box(ElementShape shape) {
  const Mesh mesh = testing::BoxMesh(
      4, 4, 6, 2, shape == ElementShape::kHex8 ? ElementType::kHex8 : ElementType::kDefault);
  return shape == ElementShape::kTet10 ? MakeQuadratic(mesh) : mesh;
}

std::string ReadText(const fs::path& file) {
  std::stringstream text;
  text << std::ifstream(file).rdbuf();
  return text.str();
}

const ElementShape kAllShapes[] = {ElementShape::kTet4, ElementShape::kTet10, ElementShape::kHex8};

TEST(ElementShape, TableRowsAreInEnumOrderWithTheFormatsNames) {
  ASSERT_EQ(ElementShapes().size(), 3u);
  for (const ElementShape shape : kAllShapes) {
    EXPECT_EQ(ShapeInfo(shape).shape, shape);
    EXPECT_EQ(&ElementShapes()[static_cast<int>(shape)], &ShapeInfo(shape));
    EXPECT_LE(ShapeInfo(shape).nodes, kMaxElementNodes);
    EXPECT_LE(ShapeInfo(shape).corners, ShapeInfo(shape).nodes);
  }
  const ElementShapeInfo& tet4 = ShapeInfo(ElementShape::kTet4);
  const ElementShapeInfo& tet10 = ShapeInfo(ElementShape::kTet10);
  const ElementShapeInfo& hex8 = ShapeInfo(ElementShape::kHex8);
  EXPECT_STREQ(tet4.name, "TET4");
  EXPECT_STREQ(tet10.name, "TET10");
  EXPECT_STREQ(hex8.name, "HEX8");
  EXPECT_EQ(tet4.nodes, 4);
  EXPECT_EQ(tet10.nodes, 10);
  EXPECT_EQ(hex8.nodes, 8);
  EXPECT_EQ(tet4.corners, 4);
  EXPECT_EQ(tet10.corners, 4);
  EXPECT_EQ(hex8.corners, 8);
  // vtkCellType.h: VTK_TETRA, VTK_QUADRATIC_TETRA, VTK_HEXAHEDRON.
  EXPECT_EQ(tet4.vtk_cell_type, 10);
  EXPECT_EQ(tet10.vtk_cell_type, 24);
  EXPECT_EQ(hex8.vtk_cell_type, 12);
  EXPECT_STREQ(tet4.xdmf_topology, "Tetrahedron");
  EXPECT_STREQ(tet10.xdmf_topology, "Tetrahedron_10");
  EXPECT_STREQ(hex8.xdmf_topology, "Hexahedron");
  EXPECT_EQ(tet4.gmsh_type, 4);
  EXPECT_EQ(tet10.gmsh_type, 11);
  EXPECT_EQ(hex8.gmsh_type, 5);
  EXPECT_STREQ(tet4.abaqus_type, "C3D4");
  EXPECT_STREQ(tet10.abaqus_type, "C3D10");
  EXPECT_STREQ(hex8.abaqus_type, "C3D8");
  EXPECT_EQ(tet4.boundary_face, BoundaryFace::kTri3);
  EXPECT_EQ(tet10.boundary_face, BoundaryFace::kTri6);
  EXPECT_EQ(hex8.boundary_face, BoundaryFace::kQuad4);
}

TEST(ElementShape, MeshShapeFollowsItsArrays) {
  EXPECT_EQ(Mesh().shape(), ElementShape::kTet4);  // no elements
  for (const ElementShape shape : kAllShapes) {
    const Mesh mesh = Box(shape);
    ASSERT_GT(mesh.num_elements(), 0);
    EXPECT_EQ(mesh.shape(), shape);
    EXPECT_EQ(mesh.quadratic(), shape == ElementShape::kTet10);
    EXPECT_EQ(mesh.hexahedral(), shape == ElementShape::kHex8);
  }
}

// Element e's nodes as the mesh's arrays hold them, corners then mid-edge
// nodes.
std::vector<int> FromArrays(const Mesh& mesh, int e) {
  if (!mesh.hexes.empty()) return {mesh.hexes[e].begin(), mesh.hexes[e].end()};
  std::vector<int> nodes(mesh.tets[e].begin(), mesh.tets[e].end());
  if (!mesh.midside.empty())
    nodes.insert(nodes.end(), mesh.midside[e].begin(), mesh.midside[e].end());
  return nodes;
}

TEST(ElementShape, ElementNodesAreTheArraysInAbaqusOrder) {
  for (const ElementShape shape : kAllShapes) {
    const Mesh mesh = Box(shape);
    const int n = mesh.num_elements();
    for (const int e : {0, n / 2, n - 1}) {
      const NodeList nodes = mesh.ElementNodes(e);
      const std::vector<int> expected = FromArrays(mesh, e);
      ASSERT_EQ(nodes.size(), ShapeInfo(shape).nodes);
      EXPECT_EQ(std::vector<int>(nodes.begin(), nodes.end()), expected) << "element " << e;
      for (int k = 0; k < nodes.size(); ++k) EXPECT_EQ(nodes[k], expected[k]);
      const NodeList corners = mesh.ElementCorners(e);
      ASSERT_EQ(corners.size(), ShapeInfo(shape).corners);
      EXPECT_EQ(std::vector<int>(corners.begin(), corners.end()),
                std::vector<int>(expected.begin(), expected.begin() + corners.size()));
    }
  }
}

TEST(ElementShape, MeshExportNamesEachShapeAsTheTable) {
  for (const ElementShape shape : kAllShapes) {
    const ElementShapeInfo& info = ShapeInfo(shape);
    SCOPED_TRACE(info.name);
    const Mesh mesh = Box(shape);
    TempDir dir;
    ASSERT_FALSE(dir.path().empty());
    for (const char* file : {"m.xdmf", "m.vtu", "m.msh", "m.inp"}) {
      ASSERT_TRUE(ExportMesh(mesh, dir.path() / file).ok()) << file;
    }
    const std::string ne = std::to_string(mesh.num_elements());
    EXPECT_NE(ReadText(dir.path() / "m.xdmf")
                  .find(std::string("<Topology TopologyType=\"") + info.xdmf_topology +
                        "\" NumberOfElements=\"" + ne + "\""),
              std::string::npos);
    EXPECT_NE(
        ReadText(dir.path() / "m.vtu")
            .find("Name=\"types\" format=\"ascii\">\n" + std::to_string(info.vtk_cell_type) + " "),
        std::string::npos);
    // One block (one region): dimension 3, entity 1, the element type.
    EXPECT_NE(ReadText(dir.path() / "m.msh")
                  .find("\n3 1 " + std::to_string(info.gmsh_type) + " " + ne + "\n"),
              std::string::npos);
    std::string first = "1";
    for (int node : mesh.ElementNodes(0)) first += ", " + std::to_string(node + 1);
    EXPECT_NE(ReadText(dir.path() / "m.inp")
                  .find(std::string("*ELEMENT, TYPE=") + info.abaqus_type + ", ELSET=EALL\n" +
                        first + "\n"),
              std::string::npos);
  }
}

// The CalculiX deck of a pressed box: its element type and first element
// from the table and ElementNodes, and pressure on element faces (P labels
// of the triangles' or the bricks' faces).
TEST(ElementShape, AbaqusDeckNamesEachShapeAsTheTable) {
  const std::pair<ElementType, ElementShape> cases[] = {
      {ElementType::kTet4, ElementShape::kTet4},
      {ElementType::kTet10, ElementShape::kTet10},
      {ElementType::kHex8Full, ElementShape::kHex8}};
  for (const auto& [element, shape] : cases) {
    const ElementShapeInfo& info = ShapeInfo(shape);
    SCOPED_TRACE(info.name);
    SceneSpec scene;
    scene.name = "pressed box";
    scene.geometry.kind = GeometrySpec::Kind::kBox;
    scene.geometry.box.size_mm = {4, 4, 6};
    scene.mesh.element = element;
    scene.mesh.element_size_mm = 2;
    scene.material.kind = MaterialSpec::Kind::kLinearElastic;
    scene.material.linear_elastic = {3000, 0.45};
    scene.analysis.type = AnalysisSpec::Type::kLinearStatic;
    BoundaryConditionSpec bottom, top;
    bottom.set = "bottom";
    bottom.kind = BoundaryConditionSpec::Kind::kFixed;
    top.set = "top";
    top.kind = BoundaryConditionSpec::Kind::kPressure;
    top.pressure_pa = 100;
    scene.boundary_conditions = {bottom, top};
    Model model;
    ASSERT_TRUE(BuildModel(scene, &model).ok());
    ASSERT_EQ(model.mesh.shape(), shape);

    TempDir dir;
    ASSERT_FALSE(dir.path().empty());
    ASSERT_TRUE(ExportAbaqusInput(scene, dir.path() / "deck.inp").ok());
    const std::string deck = ReadText(dir.path() / "deck.inp");
    std::string first = "1";
    for (int node : model.mesh.ElementNodes(0)) first += ", " + std::to_string(node + 1);
    EXPECT_NE(deck.find(std::string("*ELEMENT, TYPE=") + info.abaqus_type + ", ELSET=EALL\n" +
                        first + "\n"),
              std::string::npos)
        << deck.substr(0, 800);
    const std::size_t dload = deck.find("*DLOAD\n");
    ASSERT_NE(dload, std::string::npos);
    // "<element>, P<face>, <pressure>": the top's faces found as element
    // faces.
    const std::size_t line_end = deck.find('\n', dload + 7);
    const std::string line = deck.substr(dload + 7, line_end - dload - 7);
    EXPECT_NE(line.find(", P"), std::string::npos) << line;
  }
}

}  // namespace
}  // namespace pba
