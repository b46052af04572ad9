#include "mesh/tet_topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mesh/tet_angles.h"

namespace pba {
namespace {

using Tet = TetTopology::Tet;

// The octahedron with corners +-1 on the axes [m] and a node at its centre
// (node 6), cut into the eight tetrahedra around the centre, in regions 0
// (z > 0) and 1 (z < 0).
Mesh Octahedron() {
  Mesh mesh;
  mesh.nodes.resize(7, 3);
  mesh.nodes << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0;
  for (const int x : {0, 1}) {
    for (const int y : {2, 3}) {
      for (const int z : {4, 5}) {
        const double sign = (x == 0 ? 1 : -1) * (y == 2 ? 1 : -1) * (z == 4 ? 1 : -1);
        mesh.tets.push_back(sign > 0 ? Tet{6, x, y, z} : Tet{6, x, z, y});
        mesh.element_region.push_back(z == 4 ? 0 : 1);
      }
    }
  }
  mesh.region_names = {"upper", "lower"};
  return mesh;
}

TEST(TetTopologyTest, BuildFindsTheBoundaryAndTheNeighbours) {
  Mesh mesh = Octahedron();
  TetTopology topology(&mesh);
  std::vector<char> on_boundary;
  ASSERT_TRUE(topology.Build(&on_boundary).ok());
  EXPECT_EQ(on_boundary, (std::vector<char>{1, 1, 1, 1, 1, 1, 0}));
  EXPECT_EQ(topology.num_slots(), 8);
  EXPECT_EQ(topology.around(6).size(), 8u);
  EXPECT_EQ(topology.around(4).size(), 4u);
  EXPECT_TRUE(topology.EdgeExists(6, 0));
  EXPECT_TRUE(topology.EdgeExists(0, 2));
  EXPECT_FALSE(topology.EdgeExists(0, 1));  // opposite corners
  // The face (6, 0, 2) is shared by the elements on (0, 2, 4) and (0, 2, 5).
  const auto find = [&](Tet nodes) {
    std::sort(nodes.begin(), nodes.end());
    for (int e = 0; e < topology.num_slots(); ++e) {
      Tet t = topology.tet(e);
      std::sort(t.begin(), t.end());
      if (t == nodes) return e;
    }
    return -1;
  };
  const int above = find({0, 2, 4, 6}), below = find({0, 2, 5, 6});
  ASSERT_GE(above, 0);
  EXPECT_EQ(topology.TetAcross(above, 6, 0, 2), below);
  EXPECT_EQ(topology.TetAcross(above, 0, 2, 4), -1);  // a boundary face
  // Each element's quality: arctan(sqrt 2), the corner tetrahedron's.
  for (int e = 0; e < 8; ++e) EXPECT_NEAR(topology.quality(e), std::atan(std::sqrt(2.0)), 1e-14);
}

TEST(TetTopologyTest, UndoRestoresSlotsNodesAndQualities) {
  Mesh mesh = Octahedron();
  const Mesh original = mesh;
  TetTopology topology(&mesh);
  std::vector<char> on_boundary;
  ASSERT_TRUE(topology.Build(&on_boundary).ok());
  TetTopology::Journal journal;
  topology.Remove(3, &journal);
  topology.Remove(5, &journal);
  const long before = topology.clock();
  const int added = topology.Add({6, 0, 2, 4}, 0, 0.5, &journal);
  EXPECT_EQ(added, 5) << "the last freed slot is reused first";
  EXPECT_GT(topology.changed_at(6), before);
  const int appended = topology.Add({6, 0, 4, 3}, 0, 0.5, &journal);
  EXPECT_EQ(appended, 3);
  topology.MoveNode(6, Eigen::Vector3d(0.1, 0.2, 0.3), &journal);
  EXPECT_NE(topology.quality(0), std::atan(std::sqrt(2.0)));
  topology.Undo(journal);
  EXPECT_TRUE(mesh.nodes == original.nodes);
  for (int e = 0; e < 8; ++e) {
    EXPECT_TRUE(topology.alive(e));
    EXPECT_EQ(topology.tet(e), original.tets[e]);
    EXPECT_EQ(topology.region(e), original.element_region[e]);
    EXPECT_NEAR(topology.quality(e), std::atan(std::sqrt(2.0)), 1e-14);
  }
  EXPECT_EQ(topology.around(6).size(), 8u);

  // Removing and compacting: the survivors in order, with their regions.
  topology.Remove(2, nullptr);
  topology.Compact();
  ASSERT_EQ(mesh.tets.size(), 7u);
  EXPECT_EQ(mesh.tets[2], original.tets[3]);
  EXPECT_EQ(mesh.element_region.size(), 7u);
  EXPECT_EQ(mesh.element_region[2], original.element_region[3]);
}

TEST(TetTopologyTest, BuildRefusesBrokenMeshes) {
  Mesh mesh = Octahedron();
  std::swap(mesh.tets[4][1], mesh.tets[4][2]);
  std::vector<char> on_boundary;
  EXPECT_EQ(TetTopology(&mesh).Build(&on_boundary).field(), "mesh.tets");
  mesh = Octahedron();
  mesh.tets.push_back(mesh.tets[0]);  // the same element twice: its faces on three
  mesh.element_region.push_back(0);
  EXPECT_EQ(TetTopology(&mesh).Build(&on_boundary).field(), "mesh.tets");
  mesh = Octahedron();
  mesh.element_region.pop_back();
  EXPECT_EQ(TetTopology(&mesh).Build(&on_boundary).field(), "mesh.element_region");
}

}  // namespace
}  // namespace pba
