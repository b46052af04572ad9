// MakeQuadratic: one node per unique edge at its midpoint, C3D10 mid-edge
// order, face sets with their mid-edge nodes, deterministic numbering, and
// the projection hook applied to boundary mid-edge nodes only. TET10_MD
// scenes get the same quadratic mesh, exported to Abaqus as C3D10 with a
// note that the peer element is the plain one.
#include "mesh/quadratic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "mesh/primitive_mesher.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

Mesh Box(double sx_mm, double sy_mm, double sz_mm, double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {sx_mm, sy_mm, sz_mm};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

Mesh Cylinder(double radius_mm, double height_mm, double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  g.cylinder.radius_mm = radius_mm;
  g.cylinder.height_mm = height_mm;
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

std::pair<int, int> Edge(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

TEST(MakeQuadratic, AddsOneNodePerEdgeAtItsMidpoint) {
  const Mesh linear = Box(10, 8, 6, 3);
  const Mesh mesh = MakeQuadratic(linear);
  ASSERT_FALSE(linear.quadratic());
  ASSERT_TRUE(mesh.quadratic());
  std::set<std::pair<int, int>> edges;
  for (const auto& t : linear.tets) {
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) edges.insert(Edge(t[i], t[j]));
    }
  }
  const int n = linear.num_nodes();
  ASSERT_EQ(mesh.num_nodes(), n + static_cast<int>(edges.size()));
  ASSERT_EQ(mesh.num_elements(), linear.num_elements());
  ASSERT_EQ(mesh.midside.size(), mesh.tets.size());
  // Corners untouched: the linear mesh of corners stays valid.
  EXPECT_EQ(mesh.tets, linear.tets);
  EXPECT_EQ(mesh.nodes.topRows(n), linear.nodes);

  std::map<std::pair<int, int>, int> node_of_edge;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& t = mesh.tets[e];
    for (int k = 0; k < 6; ++k) {
      const int a = t[kTet10Edges[k][0]], b = t[kTet10Edges[k][1]], m = mesh.midside[e][k];
      EXPECT_GE(m, n);
      EXPECT_LT((mesh.nodes.row(m) - 0.5 * (mesh.nodes.row(a) + mesh.nodes.row(b))).norm(), 1e-15);
      // One node per edge, whichever element asks.
      const auto [it, inserted] = node_of_edge.emplace(Edge(a, b), m);
      EXPECT_EQ(it->second, m);
    }
    // The element is a straight-sided C3D10: Jacobian ratio 1.
    EXPECT_NEAR(Tet10JacobianRatio(Tet10Coordinates(mesh, e)), 1.0, 1e-9);
    const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
    for (int a = 0; a < 4; ++a) EXPECT_EQ(nodes[a], t[a]);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(nodes[4 + k], mesh.midside[e][k]);
  }
  EXPECT_EQ(node_of_edge.size(), edges.size());
  // Every new node belongs to an edge.
  std::set<int> mids;
  for (const auto& [edge, m] : node_of_edge) mids.insert(m);
  EXPECT_EQ(static_cast<int>(mids.size()), mesh.num_nodes() - n);
}

TEST(MakeQuadratic, FaceSetsCarryTheirMidEdgeNodes) {
  const Mesh linear = Box(10, 8, 6, 3);
  const Mesh mesh = MakeQuadratic(linear);
  ASSERT_EQ(mesh.face_sets.size(), linear.face_sets.size());
  const std::map<std::string, std::pair<int, double>> plane = {
      {"bottom", {2, 0.0}}, {"top", {2, 0.006}}, {"x_min", {0, 0.0}},
      {"x_max", {0, 0.01}}, {"y_min", {1, 0.0}}, {"y_max", {1, 0.008}}};
  for (const auto& [name, set] : mesh.face_sets) {
    const FaceSet& before = linear.face_sets.at(name);
    EXPECT_EQ(set.triangles, before.triangles) << name;
    ASSERT_EQ(set.triangle_midside.size(), set.triangles.size()) << name;
    std::set<int> expected(before.nodes.begin(), before.nodes.end());
    for (std::size_t i = 0; i < set.triangles.size(); ++i) {
      const auto& tri = set.triangles[i];
      for (int k = 0; k < 3; ++k) {
        const int m = set.triangle_midside[i][k];
        const int a = tri[k], b = tri[(k + 1) % 3];
        EXPECT_LT((mesh.nodes.row(m) - 0.5 * (mesh.nodes.row(a) + mesh.nodes.row(b))).norm(),
                  1e-15);
        expected.insert(m);
      }
    }
    EXPECT_EQ(set.nodes, std::vector<int>(expected.begin(), expected.end())) << name;
    EXPECT_GT(set.nodes.size(), before.nodes.size()) << name;
    const auto [axis, value] = plane.at(name);
    for (int node : set.nodes) EXPECT_NEAR(mesh.nodes(node, axis), value, 1e-12) << name;
    EXPECT_NEAR(FaceSetArea(mesh, set), FaceSetArea(linear, before), 1e-15) << name;
  }
}

TEST(MakeQuadratic, NumberingIsDeterministic) {
  const Mesh linear = Box(10, 10, 10, 5);
  const Mesh a = MakeQuadratic(linear), b = MakeQuadratic(linear);
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.midside, b.midside);
  for (const auto& [name, set] : a.face_sets) {
    EXPECT_EQ(set.nodes, b.face_sets.at(name).nodes);
    EXPECT_EQ(set.triangle_midside, b.face_sets.at(name).triangle_midside);
  }
  // Mid-edge nodes follow the corners in (smaller, larger) corner order.
  std::vector<std::pair<int, int>> order(a.num_nodes() - linear.num_nodes());
  for (int e = 0; e < a.num_elements(); ++e) {
    for (int k = 0; k < 6; ++k) {
      order[a.midside[e][k] - linear.num_nodes()] =
          Edge(a.tets[e][kTet10Edges[k][0]], a.tets[e][kTet10Edges[k][1]]);
    }
  }
  EXPECT_TRUE(std::is_sorted(order.begin(), order.end()));
}

TEST(MakeQuadratic, ProjectionMovesBoundaryMidEdgeNodesOnly) {
  const Mesh linear = Box(10, 8, 6, 3);
  const Mesh plain = MakeQuadratic(linear);
  std::map<std::string, int> count;
  const MidsideProjection record = [&](const Eigen::Vector3d& x, const std::string& set) {
    ++count[set];
    return x;
  };
  const Mesh same = MakeQuadratic(linear, record);
  EXPECT_EQ(same.nodes, plain.nodes);
  // Called once per mid-edge node of each face set, and never for corners.
  for (const auto& [name, set] : plain.face_sets) {
    const int mids = static_cast<int>(std::count_if(
        set.nodes.begin(), set.nodes.end(), [&](int v) { return v >= linear.num_nodes(); }));
    EXPECT_EQ(count[name], mids) << name;
  }

  // Push boundary mid-edge nodes outwards along their set's normal by 0.1 mm.
  const std::map<std::string, Eigen::Vector3d> normal = {
      {"bottom", -Eigen::Vector3d::UnitZ()}, {"top", Eigen::Vector3d::UnitZ()},
      {"x_min", -Eigen::Vector3d::UnitX()},  {"x_max", Eigen::Vector3d::UnitX()},
      {"y_min", -Eigen::Vector3d::UnitY()},  {"y_max", Eigen::Vector3d::UnitY()}};
  const Mesh bulged = MakeQuadratic(linear, [&](const Eigen::Vector3d& x, const std::string& set) {
    return Eigen::Vector3d(x + 1e-4 * normal.at(set));
  });
  std::set<int> boundary;
  for (const auto& [name, set] : plain.face_sets)
    boundary.insert(set.nodes.begin(), set.nodes.end());
  for (int v = 0; v < plain.num_nodes(); ++v) {
    const double moved = (bulged.nodes.row(v) - plain.nodes.row(v)).norm();
    if (v >= linear.num_nodes() && boundary.count(v)) {
      EXPECT_GT(moved, 0.9e-4) << v;
    } else {
      EXPECT_EQ(moved, 0.0) << v;
    }
  }
  // A node on the rim of two sets went out along both normals.
  int rim = 0;
  for (int v : plain.face_sets.at("top").nodes) {
    if (v < linear.num_nodes() || !std::binary_search(plain.face_sets.at("x_max").nodes.begin(),
                                                      plain.face_sets.at("x_max").nodes.end(), v)) {
      continue;
    }
    ++rim;
    EXPECT_NEAR(bulged.nodes(v, 0) - plain.nodes(v, 0), 1e-4, 1e-15);
    EXPECT_NEAR(bulged.nodes(v, 2) - plain.nodes(v, 2), 1e-4, 1e-15);
  }
  EXPECT_GT(rim, 0);
}

TEST(MakeQuadratic, CylinderSideProjectedOntoTheCircle) {
  const double r = 5, height = 4;  // mm
  const Mesh linear = Cylinder(r, height, 1.5);
  const double rm = r * 1e-3;
  const Mesh mesh = MakeQuadratic(linear, [&](const Eigen::Vector3d& x, const std::string& set) {
    if (set != "side") return x;
    Eigen::Vector3d y = x;
    y.head<2>() *= rm / x.head<2>().norm();
    return y;
  });
  for (int v : mesh.face_sets.at("side").nodes) {
    EXPECT_NEAR(mesh.nodes.row(v).head<2>().norm(), rm, 1e-15) << v;
  }
  double volume = 0, linear_volume = 0, worst_ratio = 1;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Tet10Nodes x = Tet10Coordinates(mesh, e);
    worst_ratio = std::min(worst_ratio, Tet10JacobianRatio(x));
    volume += Tet10Volume(x);
    linear_volume += ComputeTet4Geometry(TetCorners(linear, e)).volume;
  }
  EXPECT_GT(worst_ratio, 0.5);
  EXPECT_LT(worst_ratio, 1.0);
  // Curved sides recover most of the volume the polygonal section loses.
  const double exact = std::numbers::pi * rm * rm * height * 1e-3;
  EXPECT_LT(std::abs(volume - exact), 0.05 * std::abs(linear_volume - exact));
}

// Through the model builder: a 10-node ellipsoid with a patch on its crown.
// Every mid-edge node of the surface, the patch's included, lies on the
// ellipsoid; the patch carries its triangles' mid-edge nodes.
TEST(MakeQuadratic, EllipsoidAndItsPatchOnTheTrueSurface) {
  SceneSpec scene;
  scene.geometry.kind = GeometrySpec::Kind::kEllipsoid;
  scene.geometry.ellipsoid.semi_axes_mm = {40, 30, 20};
  scene.geometry.patches = {PatchSpec::Ball("crown", "surface", {0, 0, 20}, 10)};
  scene.mesh.element = ElementType::kTet10;
  scene.mesh.element_size_mm = 6;
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  const Mesh& mesh = model.mesh;
  ASSERT_TRUE(mesh.quadratic());
  const Eigen::Vector3d axes(40e-3, 30e-3, 20e-3);
  for (const char* name : {"surface", "crown"}) {
    const FaceSet& set = mesh.face_sets.at(name);
    ASSERT_FALSE(set.triangles.empty()) << name;
    ASSERT_EQ(set.triangle_midside.size(), set.triangles.size()) << name;
    for (int v : set.nodes) {
      EXPECT_NEAR(mesh.nodes.row(v).transpose().cwiseQuotient(axes).norm(), 1, 1e-12) << name;
    }
  }
  double volume = 0, worst_ratio = 1;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Tet10Nodes x = Tet10Coordinates(mesh, e);
    worst_ratio = std::min(worst_ratio, Tet10JacobianRatio(x));
    volume += Tet10Volume(x);
  }
  EXPECT_GT(worst_ratio, 0.5);
  // Quadratic faces on the ellipsoid: 8e-6 of the volume at 6 mm, where
  // the flat-faced corners alone miss percents.
  const double exact = 4.0 / 3 * std::numbers::pi * axes.prod();
  EXPECT_NEAR(volume, exact, 1e-4 * exact);
}

TEST(MakeQuadratic, Tet10MdScenesAreMeshedAndExportedAsTet10) {
  SceneSpec scene;
  scene.name = "md cube";
  scene.geometry.kind = GeometrySpec::Kind::kBox;
  scene.geometry.box.size_mm = {10, 10, 10};
  scene.mesh.element = ElementType::kTet10Md;
  scene.mesh.element_size_mm = 5;
  scene.material.kind = MaterialSpec::Kind::kNeoHookean;
  scene.material.neo_hookean = {1000, 1e6};
  scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  BoundaryConditionSpec bottom, top;
  bottom.set = "bottom";
  bottom.kind = BoundaryConditionSpec::Kind::kFixed;
  top.set = "top";
  top.kind = BoundaryConditionSpec::Kind::kDisplacement;
  top.displacement_mm = {0.0, 0.0, -1.0};
  scene.boundary_conditions = {bottom, top};
  Model model;
  ASSERT_TRUE(BuildModel(scene, &model).ok());
  EXPECT_TRUE(model.mesh.quadratic());

  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / "pba_quadratic_test_tet10_md.inp";
  ASSERT_TRUE(ExportAbaqusInput(scene, file).ok());
  std::stringstream deck;
  deck << std::ifstream(file).rdbuf();
  std::filesystem::remove(file);
  EXPECT_NE(deck.str().find("TYPE=C3D10"), std::string::npos);
  EXPECT_NE(deck.str().find("CalculiX has no\n** mean-dilatation 10-node element"),
            std::string::npos)
      << deck.str().substr(0, 600);
}

}  // namespace
}  // namespace pba
