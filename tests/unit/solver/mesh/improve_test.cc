#include "mesh/improve.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "atlas/label_mesher.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"
#include "mesh/quality.h"

namespace pba {
namespace {

using Vec3 = Eigen::Vector3d;
using Tet = std::array<int, 4>;
using Triangle = std::array<int, 3>;

constexpr double kDegrees = 180 / std::numbers::pi;
// The faces opposite corners 0..3, anticlockwise seen from outside.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

Tet SortedTet(Tet t) {
  std::sort(t.begin(), t.end());
  return t;
}

Triangle SortedTriangle(Triangle t) {
  std::sort(t.begin(), t.end());
  return t;
}

std::set<Tet> SortedTets(const Mesh& mesh) {
  std::set<Tet> out;
  for (const Tet& t : mesh.tets) out.insert(SortedTet(t));
  return out;
}

double SignedVolume(const Mesh& mesh, int e) {
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
  const Vec3 e1 = (x.row(1) - x.row(0)).transpose();
  const Vec3 e2 = (x.row(2) - x.row(0)).transpose();
  const Vec3 e3 = (x.row(3) - x.row(0)).transpose();
  return e1.dot(e2.cross(e3)) / 6;
}

double MinDihedralDeg(const Mesh& mesh) {
  double smallest = 180;
  for (int e = 0; e < mesh.num_elements(); ++e)
    smallest = std::min(smallest, TetDihedralRangeDegrees(TetCorners(mesh, e))[0]);
  return smallest;
}

// A mesh of the given corners [mm] and tetrahedra, with one face set,
// "surface", of its boundary triangles (anticlockwise seen from outside).
Mesh MakeMesh(const std::vector<Vec3>& points_mm, const std::vector<Tet>& tets) {
  Mesh mesh;
  mesh.nodes.resize(static_cast<int>(points_mm.size()), 3);
  for (std::size_t i = 0; i < points_mm.size(); ++i)
    mesh.nodes.row(static_cast<int>(i)) = 1e-3 * points_mm[i].transpose();
  mesh.tets = tets;
  std::map<Triangle, std::vector<Triangle>> faces;  // sorted -> as listed by each tet
  for (const Tet& t : tets) {
    for (const auto& f : kTetFaces) {
      const Triangle face{t[f[0]], t[f[1]], t[f[2]]};
      faces[SortedTriangle(face)].push_back(face);
    }
  }
  FaceSet surface;
  for (const auto& [key, listed] : faces) {
    if (listed.size() == 1) surface.triangles.push_back(listed.front());
  }
  CollectFaceSetNodes(&surface);
  mesh.face_sets["surface"] = surface;
  return mesh;
}

// The faces of the mesh's tetrahedra, sorted, with their elements.
std::map<Triangle, std::vector<int>> FaceOwners(const Mesh& mesh) {
  std::map<Triangle, std::vector<int>> owners;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    for (const auto& f : kTetFaces) {
      const Tet& t = mesh.tets[e];
      owners[SortedTriangle({t[f[0]], t[f[1]], t[f[2]]})].push_back(e);
    }
  }
  return owners;
}

int RegionOf(const Mesh& mesh, int e) {
  return mesh.element_region.empty() ? 0 : mesh.element_region[e];
}

// What ImproveTetMesh promises, `after` against `before`: the same nodes
// and node count but for the inserted ones (appended, each in elements of
// one region only, on no face set and no boundary face), only free nodes
// moved (in no face set triangle, on no
// boundary face, all their tetrahedra in one region); face sets and region
// names identical; every tetrahedron positively oriented; each region's
// volume kept to 1e-12; conforming, with the same boundary faces and the same
// faces between regions; the smallest angle not lower.
void ExpectInvariants(const Mesh& before, const Mesh& after, const ImproveStats& stats) {
  ASSERT_EQ(after.num_nodes(), before.num_nodes() + stats.inserted_nodes);
  ASSERT_EQ(after.face_sets.size(), before.face_sets.size());
  for (const auto& [name, set] : before.face_sets) {
    const FaceSet& now = after.face_sets.at(name);
    EXPECT_EQ(now.triangles, set.triangles) << name;
    EXPECT_EQ(now.nodes, set.nodes) << name;
  }
  EXPECT_EQ(after.region_names, before.region_names);
  ASSERT_EQ(after.element_region.size(), before.element_region.empty() ? 0 : after.tets.size());
  EXPECT_FALSE(after.quadratic());

  // Free nodes of `before`.
  const int n = before.num_nodes();
  std::vector<bool> held(n, false);
  std::vector<int> region_of_node(n, -1);
  for (const auto& [name, set] : before.face_sets) {
    for (const Triangle& t : set.triangles) {
      for (int node : t) held[node] = true;
    }
  }
  const auto owners_before = FaceOwners(before);
  for (const auto& [face, elements] : owners_before) {
    if (elements.size() == 1) {
      for (int node : face) held[node] = true;
    }
  }
  for (int e = 0; e < before.num_elements(); ++e) {
    for (int node : before.tets[e]) {
      if (region_of_node[node] >= 0 && region_of_node[node] != RegionOf(before, e))
        held[node] = true;
      region_of_node[node] = RegionOf(before, e);
    }
  }
  int moved = 0;
  for (int node = 0; node < n; ++node) {
    if (after.nodes.row(node) == before.nodes.row(node)) continue;
    ++moved;
    EXPECT_FALSE(held[node]) << "node " << node << " is held but moved";
  }
  EXPECT_LE(moved, stats.smoothed_nodes);

  // Every node in an element; an inserted one inside one region.
  std::vector<std::set<int>> regions_at(after.num_nodes());
  for (int e = 0; e < after.num_elements(); ++e) {
    for (int node : after.tets[e]) regions_at[node].insert(RegionOf(after, e));
  }
  for (int node = 0; node < after.num_nodes(); ++node) {
    EXPECT_FALSE(regions_at[node].empty()) << "node " << node << " is in no element";
    if (node >= n) {
      EXPECT_EQ(regions_at[node].size(), 1u) << "inserted node " << node;
    }
  }
  for (const auto& [name, set] : after.face_sets) {
    for (int node : set.nodes) EXPECT_LT(node, n) << name;
  }

  // Orientation and region volumes.
  std::map<int, double> volume_before, volume_after;
  for (int e = 0; e < before.num_elements(); ++e)
    volume_before[RegionOf(before, e)] += SignedVolume(before, e);
  for (int e = 0; e < after.num_elements(); ++e) {
    const double v = SignedVolume(after, e);
    EXPECT_GT(v, 0) << "element " << e;
    volume_after[RegionOf(after, e)] += v;
  }
  ASSERT_EQ(volume_after.size(), volume_before.size());
  for (const auto& [region, volume] : volume_before)
    EXPECT_NEAR(volume_after[region], volume, 1e-12 * volume) << "region " << region;

  // Conformity; boundary and region interfaces unchanged.
  const auto owners_after = FaceOwners(after);
  const auto boundary_and_interfaces = [](const Mesh& mesh,
                                          const std::map<Triangle, std::vector<int>>& owners) {
    std::set<Triangle> boundary, interfaces;
    for (const auto& [face, elements] : owners) {
      EXPECT_LE(elements.size(), 2u);
      if (elements.size() == 1) boundary.insert(face);
      if (elements.size() == 2 && RegionOf(mesh, elements[0]) != RegionOf(mesh, elements[1]))
        interfaces.insert(face);
    }
    return std::pair{boundary, interfaces};
  };
  const auto [boundary_before, interfaces_before] = boundary_and_interfaces(before, owners_before);
  const auto [boundary_after, interfaces_after] = boundary_and_interfaces(after, owners_after);
  EXPECT_EQ(boundary_after, boundary_before);  // so no inserted node is on the boundary
  EXPECT_EQ(interfaces_after, interfaces_before);
  // Every face set triangle is still a face of a tetrahedron.
  for (const auto& [name, set] : after.face_sets) {
    for (const Triangle& t : set.triangles)
      EXPECT_TRUE(owners_after.count(SortedTriangle(t))) << name;
  }

  const double min_before = MinDihedralDeg(before), min_after = MinDihedralDeg(after);
  EXPECT_GE(min_after, min_before);
  EXPECT_NEAR(stats.min_dihedral_before_deg, min_before, 1e-9);
  EXPECT_NEAR(stats.min_dihedral_after_deg, min_after, 1e-9);
}

// Two tetrahedra on the equilateral triangle (p, q, r) of unit side in z = 0,
// with apices a and b on its axis at z = -h and +h: flat for small h, their
// smallest angle arctan(h / rho) along the triangle's edges, rho = sqrt 3 / 6
// its inradius. The three tetrahedra around the edge (a, b) have
// 2 arctan(h / rho) along the triangle's edges instead (the apices' angles
// add), so for small h the 2-3 flip doubles the smallest angle; for large h
// the three are the worse (the 3-2 flip is then the cure).
constexpr int kP = 0, kQ = 1, kR = 2, kA = 3, kB = 4;
const double kInradius = std::sqrt(3.0) / 6;

std::vector<Vec3> Bipyramid(double h) {
  const Vec3 centre(0.5, kInradius, 0);
  return {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, std::sqrt(3.0) / 2, 0), centre - Vec3(0, 0, h),
          centre + Vec3(0, 0, h)};
}
const std::vector<Tet> kTwo = {{kP, kQ, kR, kB}, {kP, kR, kQ, kA}};
const std::vector<Tet> kThree = {{kA, kB, kP, kQ}, {kA, kB, kQ, kR}, {kA, kB, kR, kP}};

TEST(ImproveTest, TwoThreeFlipCuresTwoFlatTetrahedra) {
  const double h = 0.05;
  const Mesh before = MakeMesh(Bipyramid(h), kTwo);
  EXPECT_NEAR(MinDihedralDeg(before), std::atan(h / kInradius) * kDegrees, 1e-9);  // 9.83
  Mesh mesh = before;
  ImproveOptions options;
  options.target_min_dihedral_deg = 30;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.flips_23, 1);
  EXPECT_EQ(stats.flips_32 + stats.flips_44 + stats.edge_removals, 0);
  EXPECT_EQ(SortedTets(mesh), SortedTets(MakeMesh(Bipyramid(h), kThree)));
  for (int e = 0; e < mesh.num_elements(); ++e) {
    EXPECT_NEAR(TetDihedralRangeDegrees(TetCorners(mesh, e))[0],
                2 * std::atan(h / kInradius) * kDegrees, 1e-9);  // 19.65
  }
  EXPECT_EQ(stats.below_target_before, 2);
  EXPECT_EQ(stats.below_target_after, 3);  // better, not yet at the target
  ExpectInvariants(before, mesh, stats);
}

TEST(ImproveTest, ThreeTwoFlipCuresThreeNeedles) {
  const double h = 0.8;
  const Mesh before = MakeMesh(Bipyramid(h), kThree);
  EXPECT_NEAR(MinDihedralDeg(before), 35.45, 0.01);
  Mesh mesh = before;
  ImproveOptions options;
  options.target_min_dihedral_deg = 50;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.flips_32, 1);
  EXPECT_EQ(stats.flips_23, 0);
  EXPECT_EQ(SortedTets(mesh), SortedTets(MakeMesh(Bipyramid(h), kTwo)));
  for (int e = 0; e < mesh.num_elements(); ++e) {
    EXPECT_NEAR(TetDihedralRangeDegrees(TetCorners(mesh, e))[0],
                std::atan(h / kInradius) * kDegrees, 1e-9);  // 70.16
  }
  EXPECT_EQ(stats.below_target_after, 0);
  ExpectInvariants(before, mesh, stats);
}

// Four tetrahedra around the edge from (0, 0, -1) to (0, 0, 1), one a sliver
// (9.76 degrees): the 4-4 flip to the diagonal (r1, r3) gives 40.15 degrees
// (the best of the two triangulations of the ring, computed apart); the 2-3
// flips across the faces around the edge would give at most 6.1.
TEST(ImproveTest, FourFourFlipRemovesASliverOnARingOfFour) {
  const std::vector<Vec3> points = {Vec3(0.96, -0.28, -0.15), Vec3(-0.06, 0.19, 0.17),
                                    Vec3(-0.99, 0.12, 0.14),  Vec3(-0.19, -0.98, -0.02),
                                    Vec3(0, 0, -1),           Vec3(0, 0, 1)};
  const int a = 4, b = 5;
  const Mesh before = MakeMesh(points, {{a, b, 0, 1}, {a, b, 1, 2}, {a, b, 2, 3}, {a, b, 3, 0}});
  EXPECT_NEAR(MinDihedralDeg(before), 9.755, 0.001);
  Mesh mesh = before;
  ImproveOptions options;
  options.target_min_dihedral_deg = 12;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.flips_44, 1);
  EXPECT_EQ(stats.flips_23 + stats.flips_32 + stats.edge_removals, 0);
  EXPECT_EQ(SortedTets(mesh),
            (std::set<Tet>{{1, 2, 3, a}, {1, 2, 3, b}, {0, 1, 3, a}, {0, 1, 3, b}}));
  EXPECT_NEAR(stats.min_dihedral_after_deg, 40.14722237, 1e-6);
  ExpectInvariants(before, mesh, stats);
}

// The flips above, refused: the shared face is in a face set, or the
// tetrahedra lie in two regions.
TEST(ImproveTest, FlipsNeverCrossAFaceSetOrARegionBoundary) {
  ImproveOptions options;
  options.target_min_dihedral_deg = 50;
  const auto unchanged = [&](const Mesh& before) {
    Mesh mesh = before;
    ImproveStats stats;
    ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
    EXPECT_EQ(stats.flips_23 + stats.flips_32 + stats.flips_44 + stats.edge_removals, 0);
    EXPECT_EQ(mesh.tets, before.tets);
    EXPECT_EQ(mesh.element_region, before.element_region);
    EXPECT_TRUE(mesh.nodes == before.nodes);
    EXPECT_EQ(stats.below_target_after, stats.below_target_before);
  };
  // 2-3: the shared triangle (p, q, r) in a face set.
  Mesh two = MakeMesh(Bipyramid(0.05), kTwo);
  two.face_sets["membrane"].triangles = {{kP, kQ, kR}};
  CollectFaceSetNodes(&two.face_sets["membrane"]);
  unchanged(two);
  // 2-3: the two tetrahedra in two regions.
  two = MakeMesh(Bipyramid(0.05), kTwo);
  two.region_names = {"above", "below"};
  two.element_region = {0, 1};
  unchanged(two);
  // 3-2: a face around the edge (a, b) in a face set.
  Mesh three = MakeMesh(Bipyramid(0.8), kThree);
  three.face_sets["membrane"].triangles = {{kA, kB, kQ}};
  CollectFaceSetNodes(&three.face_sets["membrane"]);
  unchanged(three);
  // 3-2: the ring in two regions.
  three = MakeMesh(Bipyramid(0.8), kThree);
  three.region_names = {"one", "two"};
  three.element_region = {0, 0, 1};
  unchanged(three);
  // Both allowed when the regions agree (the flips above still happen).
  three.element_region = {1, 1, 1};
  Mesh mesh = three;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.flips_32, 1);
  EXPECT_EQ(mesh.element_region, (std::vector<int>{1, 1}));
}

TEST(ImproveTest, RefusesWhatItCannotImprove) {
  const Mesh linear = MakeMesh(Bipyramid(0.05), kTwo);
  const auto field_of = [](const ImproveOptions& o, Mesh mesh) {
    const Mesh before = mesh;
    const Status s = ImproveTetMesh(o, &mesh, nullptr);
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << s.ToString();
    EXPECT_EQ(mesh.tets, before.tets) << "a refused mesh is untouched";
    return s.field();
  };
  const ImproveOptions defaults;
  EXPECT_EQ(field_of(defaults, MakeQuadratic(linear)), "mesh");
  Mesh hexahedral;
  hexahedral.nodes.resize(8, 3);
  hexahedral.hexes = {{0, 1, 2, 3, 4, 5, 6, 7}};
  EXPECT_EQ(field_of(defaults, hexahedral), "mesh");
  EXPECT_EQ(ImproveTetMesh(defaults, nullptr, nullptr).field(), "mesh");

  Mesh inverted = linear;
  std::swap(inverted.tets[1][0], inverted.tets[1][1]);
  EXPECT_EQ(field_of(defaults, inverted), "mesh.tets");
  Mesh out_of_range = linear;
  out_of_range.tets[0][2] = 99;
  EXPECT_EQ(field_of(defaults, out_of_range), "mesh.tets");
  // A third tetrahedron on the face (p, q, r): not conforming.
  Mesh three_on_a_face = MakeMesh(Bipyramid(0.05), {{kP, kQ, kR, kB}, {kP, kR, kQ, kA}});
  three_on_a_face.nodes.conservativeResize(6, 3);
  three_on_a_face.nodes.row(5) << 0.5e-3, 0.3e-3, 0.2e-3;
  three_on_a_face.tets.push_back({kP, kQ, kR, 5});
  EXPECT_EQ(field_of(defaults, three_on_a_face), "mesh.tets");
  Mesh regions = linear;
  regions.element_region = {0};
  EXPECT_EQ(field_of(defaults, regions), "mesh.element_region");

  ImproveOptions o;
  o.target_min_dihedral_deg = 71;
  EXPECT_EQ(field_of(o, linear), "target_min_dihedral_deg");
  o = ImproveOptions();
  o.max_passes = -1;
  EXPECT_EQ(field_of(o, linear), "max_passes");
  o = ImproveOptions();
  o.max_ring_size = 2;
  EXPECT_EQ(field_of(o, linear), "max_ring_size");
}

// An octahedron (poles N and S, equator e0..e3 alternately 0.05 mm above
// and below z = 0) cut into a sliver on the equator, two tetrahedra from N
// onto its upper faces and two from S onto its lower ones: every node on the
// boundary, so no node can move. A node inserted at the centre, joined to
// the eight faces, lifts the smallest angle from the sliver's 8.1 degrees
// to over 50.
Mesh HeldSliver() {
  const double d = 0.05;
  const std::vector<Vec3> points = {Vec3(1, 0, d),   Vec3(0, 1, -d), Vec3(-1, 0, d),
                                    Vec3(0, -1, -d), Vec3(0, 0, 1),  Vec3(0, 0, -1)};
  std::vector<Tet> tets = {{0, 1, 2, 3}, {4, 0, 2, 1}, {4, 0, 2, 3}, {5, 1, 3, 0}, {5, 1, 3, 2}};
  for (Tet& t : tets) {
    const Mesh one = MakeMesh(points, {t});
    if (SignedVolume(one, 0) < 0) std::swap(t[0], t[1]);
  }
  return MakeMesh(points, tets);
}

TEST(ImproveTest, NodeInsertionFreesASliverWhoseCornersAreAllHeld) {
  const Mesh before = HeldSliver();
  const double sliver = MinDihedralDeg(before);
  EXPECT_NEAR(sliver, 8.07, 0.01);
  ImproveOptions options;
  options.target_min_dihedral_deg = 30;
  options.smooth = false;
  options.flip = false;  // insertion alone
  Mesh mesh = before;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.inserted_nodes, 1);
  EXPECT_EQ(mesh.num_elements(), 8);
  EXPECT_GT(stats.min_dihedral_after_deg, 50);
  EXPECT_LT(mesh.nodes.row(6).norm(), 0.1e-3);  // near the centre [m]
  ExpectInvariants(before, mesh, stats);

  // Without it, nothing lifts the sliver here but flips; without either,
  // nothing at all.
  options.insert = false;
  mesh = before;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.inserted_nodes, 0);
  EXPECT_EQ(mesh.tets, before.tets);

  // The sliver alone in its region: no cavity of it can grow, and a node
  // inside it alone splits its angles: nothing is inserted.
  Mesh apart = before;
  apart.region_names = {"sliver", "rest"};
  apart.element_region = {0, 1, 1, 1, 1};
  options = ImproveOptions();
  options.target_min_dihedral_deg = 30;
  mesh = apart;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(stats.inserted_nodes, 0);
  EXPECT_EQ(mesh.num_nodes(), apart.num_nodes());
  EXPECT_NEAR(stats.min_dihedral_after_deg, sliver, 1e-9);
  ExpectInvariants(apart, mesh, stats);
}

// A structured box (10 mm, 1 mm cells, six tetrahedra each) whose interior
// nodes are shaken by up to 0.3 mm, split into two regions along x = 5 mm:
// slivers everywhere, interior nodes free, the box faces and the region
// interface (no face set) held.
Mesh ShakenBox() {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 10};
  MeshSpec spec;
  spec.element_size_mm = 1;
  MeshStats mesh_stats;
  Mesh before = BuildPrimitiveMesh(g, spec, &mesh_stats);
  std::vector<bool> on_face(before.num_nodes(), false);
  for (const auto& [name, set] : before.face_sets) {
    for (int node : set.nodes) on_face[node] = true;
  }
  // A deterministic shake: a linear congruential generator.
  std::uint64_t state = 12345;
  const auto uniform = [&state]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 9007199254740992.0 * 2 - 1;  // [-1, 1)
  };
  for (int node = 0; node < before.num_nodes(); ++node) {
    const Eigen::RowVector3d shake(uniform(), uniform(), uniform());
    if (!on_face[node]) before.nodes.row(node) += 0.3e-3 * shake;
  }
  before.region_names = {"left", "right"};
  for (int e = 0; e < before.num_elements(); ++e) {
    EXPECT_GT(SignedVolume(before, e), 0) << "the shake inverted element " << e;
    before.element_region.push_back(TetCorners(before, e).col(0).mean() < 5e-3 ? 0 : 1);
  }
  return before;
}

TEST(ImproveTest, ShakenBoxGetsBetterAndKeepsItsShape) {
  const Mesh before = ShakenBox();
  Mesh mesh = before;
  ImproveOptions options;
  options.target_min_dihedral_deg = 25;
  ImproveStats stats;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ExpectInvariants(before, mesh, stats);
  EXPECT_GT(stats.min_dihedral_after_deg, stats.min_dihedral_before_deg + 1);
  EXPECT_LT(stats.below_target_after, stats.below_target_before / 2);
  EXPECT_GT(stats.smoothed_nodes, 0);
  EXPECT_GT(stats.flips_32 + stats.flips_44 + stats.edge_removals, 0);
  EXPECT_GT(stats.smoothed_flips, 0)
      << "flips that needed their new corners moved (and trials undone)";
  std::printf(
      "shaken box: %d -> %d tetrahedra; smallest angle %.2f -> %.2f deg; below 25 deg %d -> "
      "%d; 2-3 %d, 3-2 %d, 4-4 %d, larger rings %d (%d of the flips with smoothing), "
      "node moves %d, passes %d; %.3f s\n",
      before.num_elements(), mesh.num_elements(), stats.min_dihedral_before_deg,
      stats.min_dihedral_after_deg, stats.below_target_before, stats.below_target_after,
      stats.flips_23, stats.flips_32, stats.flips_44, stats.edge_removals, stats.smoothed_flips,
      stats.smoothed_nodes, stats.passes, seconds);
}

// The largest aspect ratio, and how many tetrahedra are above `bound`.
std::pair<double, int> AspectRatios(const Mesh& mesh, double bound) {
  double largest = 0;
  int above = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double a = TetAspectRatio(TetCorners(mesh, e));
    largest = std::max(largest, a);
    above += a > bound;
  }
  return {largest, above};
}

// With an aspect-ratio target the same box ends with far fewer tetrahedra
// above it than with the angle alone, and the same invariants hold
// (ExpectInvariants: geometry, face sets, held nodes, the smallest angle
// not lower).
TEST(ImproveTest, AnAspectRatioTargetLiftsWhatTheAngleAloneLeaves) {
  const Mesh before = ShakenBox();
  ImproveOptions angle_only;
  angle_only.target_min_dihedral_deg = 15;
  ImproveOptions both = angle_only;
  both.target_aspect_ratio = 3;
  Mesh by_angle = before, by_both = before;
  ImproveStats angle_stats, both_stats;
  ASSERT_TRUE(ImproveTetMesh(angle_only, &by_angle, &angle_stats).ok());
  ASSERT_TRUE(ImproveTetMesh(both, &by_both, &both_stats).ok());
  ExpectInvariants(before, by_angle, angle_stats);
  ExpectInvariants(before, by_both, both_stats);
  const auto [largest_before, above_before] = AspectRatios(before, 3);
  const auto [largest_angle, above_angle] = AspectRatios(by_angle, 3);
  const auto [largest_both, above_both] = AspectRatios(by_both, 3);
  EXPECT_NEAR(both_stats.max_aspect_ratio_before, largest_before, 1e-9 * largest_before);
  EXPECT_NEAR(both_stats.max_aspect_ratio_after, largest_both, 1e-9 * largest_both);
  EXPECT_LT(largest_both, largest_before);
  EXPECT_LT(above_both, above_angle / 2);
  EXPECT_LE(largest_both, largest_angle);
  std::printf(
      "shaken box: aspect ratio > 3 in %d tetrahedra, %d after the angle alone, %d with the "
      "aspect ratio; largest %.2f, %.2f, %.2f\n",
      above_before, above_angle, above_both, largest_before, largest_angle, largest_both);
  // A bad target is refused.
  ImproveOptions bad = both;
  bad.target_aspect_ratio = 1.2;
  Mesh untouched = before;
  const Status s = ImproveTetMesh(bad, &untouched, nullptr);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << s.ToString();
  EXPECT_EQ(s.field(), "target_aspect_ratio");
}

// Two nested spheres from the labelled mesher (as label_mesher_test.cc):
// without CGAL's sliver removal the mesh has slivers everywhere, many with
// corners on the surface or the interface.
int TwoSpheres(const Eigen::Vector3d& x) {
  const double r = x.norm();
  return r < 10 ? 2 : r < 20 ? 1 : 0;
}

LabelMeshOptions SphereOptions(bool remove_slivers) {
  LabelMeshOptions o;
  o.box_min_mm = Eigen::Vector3d::Constant(-25);
  o.box_max_mm = Eigen::Vector3d::Constant(25);
  o.cell_size_mm = 3;
  o.facet_size_mm = 2;
  o.facet_distance_mm = 0.2;
  o.perturb = remove_slivers;
  o.exude = remove_slivers;
  return o;
}

TEST(ImproveTest, NestedSpheresWithoutSliverRemoval) {
  Mesh before;
  ASSERT_TRUE(MeshLabels(TwoSpheres, {"shell", "core"}, SphereOptions(false), &before).ok());
  ASSERT_EQ(before.face_sets.size(), 4u);  // surface, interface, each region's surface
  for (const double target : {10.0, 20.0}) {
    for (const bool smooth : {true, false}) {
      SCOPED_TRACE("target " + std::to_string(target) + (smooth ? "" : ", no smoothing"));
      Mesh mesh = before;
      ImproveOptions options;
      options.target_min_dihedral_deg = target;
      options.smooth = smooth;
      ImproveStats stats;
      const auto start = std::chrono::steady_clock::now();
      ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      ExpectInvariants(before, mesh, stats);
      EXPECT_GT(stats.min_dihedral_after_deg, stats.min_dihedral_before_deg);
      EXPECT_LT(stats.below_target_after, stats.below_target_before / 2);
      std::printf(
          "nested spheres, no sliver removal, target %g%s: %d -> %d tetrahedra; smallest angle "
          "%.2f -> %.2f deg; below target %d -> %d; 2-3 %d, 3-2 %d, 4-4 %d, larger rings %d "
          "(%d of the flips with smoothing), node moves %d, passes %d; %.3f s\n",
          target, smooth ? "" : " (flips only)", before.num_elements(), mesh.num_elements(),
          stats.min_dihedral_before_deg, stats.min_dihedral_after_deg, stats.below_target_before,
          stats.below_target_after, stats.flips_23, stats.flips_32, stats.flips_44,
          stats.edge_removals, stats.smoothed_flips, stats.smoothed_nodes, stats.passes, seconds);
    }
  }
}

// After CGAL's perturbation and exudation: what is left is improved or kept,
// never made worse.
TEST(ImproveTest, NestedSpheresAfterSliverRemoval) {
  Mesh before;
  ASSERT_TRUE(MeshLabels(TwoSpheres, {"shell", "core"}, SphereOptions(true), &before).ok());
  Mesh mesh = before;
  ImproveOptions options;
  options.target_min_dihedral_deg = 15;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  ExpectInvariants(before, mesh, stats);
  EXPECT_LE(stats.below_target_after, stats.below_target_before);
  std::printf(
      "nested spheres after exudation: smallest angle %.2f -> %.2f deg; below 15 deg %d -> %d\n",
      stats.min_dihedral_before_deg, stats.min_dihedral_after_deg, stats.below_target_before,
      stats.below_target_after);
}

// Improving an improved mesh again changes nothing once no tetrahedron is
// below the target, and max_passes = 0 only measures.
TEST(ImproveTest, GoodMeshIsLeftAlone) {
  const Mesh before = MakeMesh(Bipyramid(0.8), kTwo);  // 70.16 degrees
  Mesh mesh = before;
  ImproveStats stats;
  ASSERT_TRUE(ImproveTetMesh(ImproveOptions(), &mesh, &stats).ok());
  EXPECT_EQ(mesh.tets, before.tets);
  EXPECT_EQ(stats.passes, 0);
  EXPECT_EQ(stats.below_target_before, 0);

  const Mesh flat = MakeMesh(Bipyramid(0.05), kTwo);
  mesh = flat;
  ImproveOptions options;
  options.max_passes = 0;
  ASSERT_TRUE(ImproveTetMesh(options, &mesh, &stats).ok());
  EXPECT_EQ(mesh.tets, flat.tets);
  EXPECT_EQ(stats.below_target_before, 2);
  EXPECT_EQ(stats.below_target_after, 2);
  EXPECT_NEAR(stats.min_dihedral_after_deg, stats.min_dihedral_before_deg, 0);
}

}  // namespace
}  // namespace pba
