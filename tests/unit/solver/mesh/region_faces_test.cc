#include "mesh/region_faces.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <set>
#include <string>

#include "atlas/label_mesher.h"
#include "mesh/quality.h"

namespace pba {
namespace {

using Triangle = std::array<int, 3>;

// A triangle up to rotation (orientation kept): smallest index first.
Triangle Canonical(Triangle t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

std::set<Triangle> Oriented(const FaceSet& set) {
  std::set<Triangle> out;
  for (const Triangle& t : set.triangles) out.insert(Canonical(t));
  return out;
}

int TwoSpheres(const Eigen::Vector3d& x) {
  const double r = x.norm();
  return r < 10 ? 2 : r < 20 ? 1 : 0;
}

// Rebuilt from the regions, the sets are those the mesher made: the same
// triangles, the same way round.
TEST(RegionFacesTest, RebuildGivesTheMeshersSets) {
  LabelMeshOptions o;
  o.box_min_mm = Eigen::Vector3d::Constant(-25);
  o.box_max_mm = Eigen::Vector3d::Constant(25);
  o.cell_size_mm = 4;
  o.facet_size_mm = 3;
  Mesh meshed;
  ASSERT_TRUE(MeshLabels(TwoSpheres, {"shell", "core"}, o, &meshed).ok());
  Mesh rebuilt = meshed;
  rebuilt.face_sets["kept"] = meshed.face_sets.at("surface");  // not region-derived
  RebuildRegionFaceSets(&rebuilt);
  ASSERT_EQ(rebuilt.face_sets.size(), meshed.face_sets.size() + 1);
  for (const auto& [name, set] : meshed.face_sets) {
    ASSERT_TRUE(rebuilt.face_sets.count(name)) << name;
    EXPECT_EQ(Oriented(rebuilt.face_sets.at(name)), Oriented(set)) << name;
    EXPECT_EQ(rebuilt.face_sets.at(name).nodes, set.nodes) << name;
  }
  EXPECT_EQ(rebuilt.face_sets.at("kept").triangles, meshed.face_sets.at("surface").triangles);
}

// The nearly flat quadrilateral 1-2-3-4 (node 4 0.02 above the plane of
// the others) split two ways: above, along 2-4, into the faces of two
// tetrahedra of region a reaching up to node 0; below, along 1-3, into the
// faces of two tetrahedra of region b reaching down to node 5. Between the
// two splits the flat tetrahedron (1, 2, 3, 4), in region a, has its two
// lower faces on the interface with b.
Mesh SliverAgainstAnInterface() {
  Mesh mesh;
  mesh.nodes.resize(6, 3);
  mesh.nodes << 0, 0, 1,  // 0: apex above
      -1, -1, 0,          // 1
      1, -1, 0,           // 2
      1, 1, 0,            // 3
      -1, 1, 0.02,        // 4
      0, 0, -1;           // 5: apex below
  const auto positive = [&](std::array<int, 4> t) {
    const Eigen::Vector3d p0 = mesh.nodes.row(t[0]).transpose();
    const double v = (mesh.nodes.row(t[1]).transpose() - p0)
                         .cross(mesh.nodes.row(t[2]).transpose() - p0)
                         .dot(mesh.nodes.row(t[3]).transpose() - p0);
    if (v < 0) std::swap(t[2], t[3]);
    return t;
  };
  mesh.tets = {positive({0, 1, 2, 4}), positive({0, 2, 3, 4}), positive({1, 2, 3, 4}),
               positive({5, 1, 2, 3}), positive({5, 1, 3, 4})};
  mesh.region_names = {"a", "b"};
  mesh.element_region = {0, 0, 0, 1, 1};
  RebuildRegionFaceSets(&mesh);
  return mesh;
}

TEST(RegionFacesTest, ASliverWithTwoFacesOnAnInterfaceCrossesIt) {
  Mesh mesh = SliverAgainstAnInterface();
  const double angle = TetDihedralRangeDegrees(TetCorners(mesh, 2))[0];
  ASSERT_LT(angle, 5);
  ASSERT_EQ(mesh.face_sets.at("interface:a|b").triangles.size(), 2u);
  const RelabelStats stats = RelabelInterfaceSlivers(10, &mesh);
  EXPECT_EQ(stats.tetrahedra, 1);
  EXPECT_EQ(mesh.element_region[2], 1);
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, 2);
  const double volume =
      (x.row(1) - x.row(0)).cross(x.row(2) - x.row(0)).dot(x.row(3) - x.row(0)) / 6;
  EXPECT_NEAR(stats.volume_m3, volume, 1e-15);
  // The interface now runs over the sliver's other two faces.
  const FaceSet& between = mesh.face_sets.at("interface:a|b");
  EXPECT_EQ(between.triangles.size(), 2u);
  std::set<Triangle> expected;
  for (const std::array<int, 3>& f : {std::array<int, 3>{1, 2, 4}, std::array<int, 3>{2, 3, 4}}) {
    Triangle s = f;
    std::sort(s.begin(), s.end());
    expected.insert(s);
  }
  std::set<Triangle> got;
  for (Triangle t : between.triangles) {
    std::sort(t.begin(), t.end());
    got.insert(t);
  }
  EXPECT_EQ(got, expected);
  // A well-shaped tetrahedron and a target below its angles: nothing moves.
  Mesh again = SliverAgainstAnInterface();
  EXPECT_EQ(RelabelInterfaceSlivers(angle / 2, &again).tetrahedra, 0);
}

TEST(RegionFacesTest, TheLastTetrahedronOfARegionStays) {
  Mesh mesh = SliverAgainstAnInterface();
  mesh.region_names = {"a", "b", "c"};
  mesh.element_region = {0, 0, 2, 1, 1};  // the sliver alone in c
  RebuildRegionFaceSets(&mesh);
  EXPECT_EQ(RelabelInterfaceSlivers(10, &mesh).tetrahedra, 0);
  EXPECT_EQ(mesh.element_region[2], 2);
}

// The sliver of SliverAgainstAnInterface with region b gone: two of its
// faces are on the outer boundary, and it is taken out, nothing else.
TEST(RegionFacesTest, ASliverOnTheOuterSurfaceIsPeeled) {
  Mesh mesh = SliverAgainstAnInterface();
  mesh.nodes.conservativeResize(5, 3);  // node 5 was only region b's
  mesh.tets.resize(3);
  mesh.element_region = {0, 0, 0};
  mesh.region_names = {"a"};
  RebuildRegionFaceSets(&mesh);
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, 2);
  const double volume =
      (x.row(1) - x.row(0)).cross(x.row(2) - x.row(0)).dot(x.row(3) - x.row(0)) / 6;
  const std::array<int, 4> first = mesh.tets[0], second = mesh.tets[1];
  // A target below its angle: it stays.
  Mesh kept = mesh;
  EXPECT_EQ(PeelBoundarySlivers(TetDihedralRangeDegrees(x)[0] / 2, &kept).tetrahedra, 0);
  EXPECT_EQ(kept.tets.size(), 3u);

  const RemovedTetrahedra peeled = PeelBoundarySlivers(10, &mesh);
  EXPECT_EQ(peeled.tetrahedra, 1);
  EXPECT_NEAR(peeled.volume_m3, volume, 1e-15);
  EXPECT_EQ(peeled.regions, std::vector<std::string>{"a"});
  ASSERT_EQ(mesh.tets.size(), 2u);
  EXPECT_EQ(mesh.tets[0], first);  // every node is still used: none renumbered
  EXPECT_EQ(mesh.tets[1], second);
  EXPECT_EQ(mesh.num_nodes(), 5);
  // The surface is now the two tetrahedra's faces but the one they share.
  EXPECT_EQ(mesh.face_sets.at("surface").triangles.size(), 6u);
  for (const auto& [name, set] : mesh.face_sets)
    EXPECT_EQ(name.find("interface:"), std::string::npos);
}

TEST(RegionFacesTest, PeelingKeepsASliverInsideOrTheLastOfItsRegion) {
  // Inside: its faces are against a and b, none outside.
  Mesh inside = SliverAgainstAnInterface();
  EXPECT_EQ(PeelBoundarySlivers(10, &inside).tetrahedra, 0);
  // Alone in its region c, with faces outside.
  Mesh alone = SliverAgainstAnInterface();
  alone.nodes.conservativeResize(5, 3);
  alone.tets.resize(3);
  alone.region_names = {"a", "c"};
  alone.element_region = {0, 0, 1};
  RebuildRegionFaceSets(&alone);
  EXPECT_EQ(PeelBoundarySlivers(10, &alone).tetrahedra, 0);
  EXPECT_EQ(alone.tets.size(), 3u);
}

// Two unit-cube corner tetrahedra sharing a face (region a), a small
// tetrahedron touching them at one node only (region a too: a fragment),
// and one more small one elsewhere that is all of region c. The fragment
// of a is taken out with its two nodes of its own; c's stays.
TEST(RegionFacesTest, MeshFragmentsAreDroppedUnlessTheyAreAllOfARegion) {
  Mesh mesh;
  mesh.nodes.resize(12, 3);
  mesh.nodes << 0, 0, 0,  // 0
      1, 0, 0,            // 1
      0, 1, 0,            // 2
      0, 0, 1,            // 3
      1, 1, 1,            // 4
      1.1, 1, 1,          // 5: fragment of a, with node 4
      1, 1.1, 1,          // 6
      1, 1, 1.1,          // 7
      5, 5, 5,            // 8: region c
      5.1, 5, 5,          // 9
      5, 5.1, 5,          // 10
      5, 5, 5.1;          // 11
  mesh.tets = {{0, 1, 2, 3}, {1, 4, 2, 3}, {4, 5, 6, 7}, {8, 9, 10, 11}};
  for (int e = 0; e < 4; ++e) {
    ASSERT_GT((mesh.nodes.row(mesh.tets[e][1]) - mesh.nodes.row(mesh.tets[e][0]))
                  .cross(mesh.nodes.row(mesh.tets[e][2]) - mesh.nodes.row(mesh.tets[e][0]))
                  .dot(mesh.nodes.row(mesh.tets[e][3]) - mesh.nodes.row(mesh.tets[e][0])),
              0)
        << "element " << e;
  }
  mesh.region_names = {"a", "c"};
  mesh.element_region = {0, 0, 0, 1};
  RebuildRegionFaceSets(&mesh);
  // A face set of the user's: one triangle on kept nodes, one on the
  // fragment's.
  FaceSet load;
  load.triangles = {{0, 2, 1}, {5, 6, 7}};
  CollectFaceSetNodes(&load);
  mesh.face_sets["load"] = load;

  int pieces = -1;
  const RemovedTetrahedra dropped = DropMeshFragments(1e-3, &mesh, &pieces);
  EXPECT_EQ(pieces, 1);
  EXPECT_EQ(dropped.tetrahedra, 1);
  EXPECT_NEAR(dropped.volume_m3, 0.1 * 0.1 * 0.1 / 6, 1e-15);
  EXPECT_EQ(dropped.regions, std::vector<std::string>{"a"});
  ASSERT_EQ(mesh.num_nodes(), 9);  // 5, 6 and 7 gone, 8..11 now 5..8
  const std::vector<std::array<int, 4>> expected = {{0, 1, 2, 3}, {1, 4, 2, 3}, {5, 6, 7, 8}};
  EXPECT_EQ(mesh.tets, expected);
  EXPECT_EQ(mesh.element_region, (std::vector<int>{0, 0, 1}));
  EXPECT_EQ(mesh.nodes.row(5), Eigen::RowVector3d(5, 5, 5));
  EXPECT_EQ(mesh.face_sets.at("load").triangles, (std::vector<Triangle>{{0, 2, 1}}));
  EXPECT_EQ(mesh.face_sets.at("surface").triangles.size(), 10u);  // 6 of a, 4 of c
  EXPECT_EQ(mesh.face_sets.at("surface:a").triangles.size(), 6u);
  // Nothing small enough: nothing taken.
  EXPECT_EQ(DropMeshFragments(1e-6, &mesh, &pieces).tetrahedra, 0);
  EXPECT_EQ(pieces, 0);
}

}  // namespace
}  // namespace pba
