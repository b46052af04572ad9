#include "mesh/collapse.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "mesh/quality.h"
#include "mesh/region_faces.h"

namespace pba {
namespace {

using Vec3 = Eigen::Vector3d;
using Tet = std::array<int, 4>;

constexpr double kMm = 1e-3;

// An n x n x n grid of 1 mm cubes, each split into the six tetrahedra of
// the Kuhn triangulation (which conform across cubes), positively oriented;
// `region` gives each tetrahedron's region from its centroid [mm]. Its
// region-derived face sets are built.
struct Grid {
  int n = 4;
  Mesh mesh;
  int Node(int i, int j, int k) const { return (k * (n + 1) + j) * (n + 1) + i; }
};

template <typename RegionOf>
Grid MakeGrid(int n, const std::vector<std::string>& names, RegionOf region) {
  Grid g;
  g.n = n;
  g.mesh.nodes.resize((n + 1) * (n + 1) * (n + 1), 3);
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) g.mesh.nodes.row(g.Node(i, j, k)) = kMm * Vec3(i, j, k);
    }
  }
  const std::array<std::array<int, 3>, 6> orders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        for (const auto& order : orders) {
          std::array<int, 3> at{i, j, k};
          Tet t{};
          t[0] = g.Node(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[order[s]];
            t[s + 1] = g.Node(at[0], at[1], at[2]);
          }
          const Vec3 x0 = g.mesh.nodes.row(t[0]);
          const Vec3 x1 = g.mesh.nodes.row(t[1]);
          const Vec3 x2 = g.mesh.nodes.row(t[2]);
          const Vec3 x3 = g.mesh.nodes.row(t[3]);
          if ((x1 - x0).dot((x2 - x0).cross(x3 - x0)) < 0) std::swap(t[2], t[3]);
          g.mesh.tets.push_back(t);
          g.mesh.element_region.push_back(region((x0 + x1 + x2 + x3) / 4 / kMm));
        }
      }
    }
  }
  g.mesh.region_names = names;
  RebuildRegionFaceSets(&g.mesh);
  return g;
}

Grid OneRegion(int n) {
  return MakeGrid(n, {"block"}, [](const Vec3&) { return 0; });
}

// Two regions split by the plane x = 2 mm.
Grid TwoRegions(int n) {
  return MakeGrid(n, {"left", "right"}, [](const Vec3& c) { return c.x() < 2 ? 0 : 1; });
}

double SignedVolume(const Mesh& mesh, int e) {
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
  return (x.row(1) - x.row(0)).dot((x.row(2) - x.row(0)).cross(x.row(3) - x.row(0))) / 6;
}

std::vector<double> RegionVolumes(const Mesh& mesh) {
  std::vector<double> v(mesh.region_names.size(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e) v[mesh.element_region[e]] += SignedVolume(mesh, e);
  return v;
}

double MinDihedralDeg(const Mesh& mesh) {
  double smallest = 180;
  for (int e = 0; e < mesh.num_elements(); ++e)
    smallest = std::min(smallest, TetDihedralRangeDegrees(TetCorners(mesh, e))[0]);
  return smallest;
}

// Moves node `from` to `share` of the way to node `to`: the edge between
// them becomes (1 - share) of its length, and the tetrahedra around it
// slivers.
void MoveTowards(int from, int to, double share, Mesh* mesh) {
  mesh->nodes.row(from) += share * (mesh->nodes.row(to) - mesh->nodes.row(from));
}

// A face set is a closed 2-manifold of Euler characteristic 2 (a sphere):
// every edge in exactly two of its triangles, used once each way.
void ExpectSphere(const FaceSet& set, const std::string& name) {
  std::map<std::pair<int, int>, int> directed;
  std::set<int> nodes;
  for (const auto& t : set.triangles) {
    for (int i = 0; i < 3; ++i) {
      ++directed[{t[i], t[(i + 1) % 3]}];
      nodes.insert(t[i]);
    }
  }
  int edges = 0;
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << name << ": edge " << edge.first << "-" << edge.second;
    const auto back = directed.find({edge.second, edge.first});
    EXPECT_TRUE(back != directed.end() && back->second == 1)
        << name << ": edge " << edge.first << "-" << edge.second << " has no twin";
    if (edge.first < edge.second) ++edges;
  }
  const int chi = static_cast<int>(nodes.size()) - edges + static_cast<int>(set.triangles.size());
  EXPECT_EQ(chi, 2) << name;
}

// Each region-derived surface's Euler characteristic (V - E + F of its
// triangles), by name.
std::map<std::string, int> EulerCharacteristics(const Mesh& mesh) {
  std::map<std::string, int> out;
  for (const auto& [name, set] : mesh.face_sets) {
    if (name.rfind("surface:", 0) != 0) continue;
    std::set<std::pair<int, int>> edges;
    for (const auto& t : set.triangles) {
      for (int i = 0; i < 3; ++i)
        edges.insert({std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])});
    }
    out[name] = static_cast<int>(set.nodes.size()) - static_cast<int>(edges.size()) +
                static_cast<int>(set.triangles.size());
  }
  return out;
}

void ExpectValid(const Mesh& mesh, bool spheres = true) {
  for (int e = 0; e < mesh.num_elements(); ++e) ASSERT_GT(SignedVolume(mesh, e), 0) << e;
  std::map<std::array<int, 3>, int> faces;
  for (const Tet& t : mesh.tets) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f{};
      int c = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != skip) f[c++] = t[i];
      }
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  }
  for (const auto& [f, count] : faces) ASSERT_LE(count, 2);
  if (!spheres) return;
  for (const auto& [name, set] : mesh.face_sets) {
    if (name == "surface" || name.rfind("surface:", 0) == 0) ExpectSphere(set, name);
  }
}

CollapseOptions Options(double max_edge_mm) {
  CollapseOptions o;
  o.max_edge_m = max_edge_mm * kMm;
  return o;
}

// A short edge inside: one node goes, the block keeps its volume exactly
// and its surface, and the slivers around the edge are gone.
TEST(CollapseTest, AShortEdgeInsideGoes) {
  Grid g = OneRegion(4);
  MoveTowards(g.Node(2, 2, 2), g.Node(3, 2, 2), 0.97, &g.mesh);
  const double before = MinDihedralDeg(g.mesh);
  ASSERT_LT(before, 5);
  const int nodes = g.mesh.num_nodes();
  const std::size_t surface = g.mesh.face_sets.at("surface").triangles.size();
  CollapseStats stats;
  ASSERT_TRUE(CollapseShortEdges(Options(0.1), &g.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 1);
  EXPECT_NEAR(stats.longest_m, 0.03 * kMm, 1e-12);
  EXPECT_EQ(stats.longest_surface_m, 0);
  EXPECT_EQ(g.mesh.num_nodes(), nodes - 1);
  EXPECT_GT(stats.removed_tetrahedra, 0);
  EXPECT_NEAR(stats.min_dihedral_before_deg, before, 1e-9);
  // No sliver left: every angle above the target (Kuhn's 45 degrees
  // become about 20 around the node that took the other's place).
  EXPECT_GT(MinDihedralDeg(g.mesh), CollapseOptions().target_min_dihedral_deg);
  EXPECT_NEAR(stats.min_dihedral_after_deg, MinDihedralDeg(g.mesh), 1e-9);
  EXPECT_NEAR(RegionVolumes(g.mesh)[0], 64 * std::pow(kMm, 3), 1e-20);
  EXPECT_EQ(g.mesh.face_sets.at("surface").triangles.size(), surface);
  ExpectValid(g.mesh);
}

// A short edge on a flat face of the outer surface: the node slides along
// it, so the volume stays exactly, the surface loses two triangles and
// stays a sphere.
TEST(CollapseTest, AShortEdgeOnTheSurfaceSlidesAlongIt) {
  Grid g = OneRegion(4);
  MoveTowards(g.Node(2, 2, 0), g.Node(3, 2, 0), 0.97, &g.mesh);
  ASSERT_LT(MinDihedralDeg(g.mesh), 5);
  const std::size_t surface = g.mesh.face_sets.at("surface").triangles.size();
  CollapseStats stats;
  ASSERT_TRUE(CollapseShortEdges(Options(0.1), &g.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 1);
  EXPECT_NEAR(stats.longest_surface_m, 0.03 * kMm, 1e-12);
  EXPECT_GT(MinDihedralDeg(g.mesh), CollapseOptions().target_min_dihedral_deg);
  EXPECT_NEAR(RegionVolumes(g.mesh)[0], 64 * std::pow(kMm, 3), 1e-20);
  EXPECT_EQ(g.mesh.face_sets.at("surface").triangles.size(), surface - 2);
  ExpectValid(g.mesh);
}

// An inside node brought near a surface node: the inside one goes, onto
// the surface node, which stays where it is (moving it inside would dent
// the surface): every surface node keeps its place.
TEST(CollapseTest, ASurfaceNodeStaysAndTheInsideOneGoes) {
  Grid g = OneRegion(4);
  const int surface_node = g.Node(2, 2, 0), inside = g.Node(2, 2, 1);
  MoveTowards(inside, surface_node, 0.97, &g.mesh);
  const Vec3 kept = g.mesh.nodes.row(surface_node);
  std::set<std::array<double, 3>> surface_points;
  for (int n : g.mesh.face_sets.at("surface").nodes)
    surface_points.insert({g.mesh.nodes(n, 0), g.mesh.nodes(n, 1), g.mesh.nodes(n, 2)});
  CollapseStats stats;
  ASSERT_TRUE(CollapseShortEdges(Options(0.1), &g.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 1);
  std::set<std::array<double, 3>> after;
  for (int n : g.mesh.face_sets.at("surface").nodes)
    after.insert({g.mesh.nodes(n, 0), g.mesh.nodes(n, 1), g.mesh.nodes(n, 2)});
  EXPECT_EQ(after, surface_points);
  EXPECT_TRUE(after.count({kept.x(), kept.y(), kept.z()}));
  EXPECT_NEAR(RegionVolumes(g.mesh)[0], 64 * std::pow(kMm, 3), 1e-20);
  ExpectValid(g.mesh);
}

// Across an interface: a node inside the left region brought near a node
// of the interface goes onto it; an interface node brought near another
// slides along the interface; a node where the interface meets the outer
// surface stays on that line. Each region keeps its volume exactly.
TEST(CollapseTest, InterfacesKeepTheirPlace) {
  Grid g = TwoRegions(4);
  MoveTowards(g.Node(1, 2, 2), g.Node(2, 2, 2), 0.97, &g.mesh);  // left inside -> interface
  MoveTowards(g.Node(2, 1, 1), g.Node(2, 1, 2), 0.97, &g.mesh);  // along the interface
  MoveTowards(g.Node(2, 2, 0), g.Node(2, 3, 0), 0.97, &g.mesh);  // along interface x surface
  ASSERT_LT(MinDihedralDeg(g.mesh), 5);
  const int nodes = g.mesh.num_nodes();
  CollapseStats stats;
  ASSERT_TRUE(CollapseShortEdges(Options(0.1), &g.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 3);
  EXPECT_EQ(g.mesh.num_nodes(), nodes - 3);
  EXPECT_GT(MinDihedralDeg(g.mesh), CollapseOptions().target_min_dihedral_deg);
  const std::vector<double> volumes = RegionVolumes(g.mesh);
  EXPECT_NEAR(volumes[0], 32 * std::pow(kMm, 3), 1e-20);
  EXPECT_NEAR(volumes[1], 32 * std::pow(kMm, 3), 1e-20);
  // The interface is still the plane x = 2 mm.
  for (int n : g.mesh.face_sets.at(InterfaceSetName("left", "right")).nodes)
    EXPECT_NEAR(g.mesh.nodes(n, 0), 2 * kMm, 1e-15) << n;
  ExpectValid(g.mesh);
}

// What never goes: an edge longer than the share of its tetrahedron's
// longest edge; an edge longer than the bound when it would move a surface
// node (a node inside may go further: its region keeps its shape); a node
// of a face set that is not region-derived (a scene's load patch).
TEST(CollapseTest, LongEdgesAndHeldNodesStay) {
  Grid g = OneRegion(4);
  MoveTowards(g.Node(2, 2, 0), g.Node(3, 2, 0), 0.97, &g.mesh);  // on the surface
  Mesh before = g.mesh;
  CollapseStats stats;
  ASSERT_TRUE(CollapseShortEdges(Options(0.02), &g.mesh, &stats).ok());  // edge 0.03 mm
  EXPECT_EQ(stats.edges, 0);
  EXPECT_TRUE(g.mesh.nodes.isApprox(before.nodes));
  EXPECT_EQ(g.mesh.tets, before.tets);

  CollapseOptions ratio = Options(0.1);
  ratio.max_edge_ratio = 0.01;  // 0.03 mm against longest edges of 1.4 to 1.7 mm
  ASSERT_TRUE(CollapseShortEdges(ratio, &g.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 0);

  Grid inside = OneRegion(4);
  MoveTowards(inside.Node(2, 2, 2), inside.Node(3, 2, 2), 0.97, &inside.mesh);
  ASSERT_TRUE(CollapseShortEdges(Options(0.02), &inside.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 1);
  EXPECT_EQ(stats.longest_surface_m, 0);
  EXPECT_NEAR(RegionVolumes(inside.mesh)[0], 64 * std::pow(kMm, 3), 1e-20);

  // Both ends on a load patch: neither may go.
  Grid held = OneRegion(4);
  const int a = held.Node(2, 2, 0), b = held.Node(3, 2, 0);
  MoveTowards(a, b, 0.97, &held.mesh);
  FaceSet load;
  for (const auto& t : held.mesh.face_sets.at("surface").triangles) {
    if (std::count(t.begin(), t.end(), a) + std::count(t.begin(), t.end(), b) > 0)
      load.triangles.push_back(t);
  }
  CollectFaceSetNodes(&load);
  held.mesh.face_sets["load"] = load;
  ASSERT_TRUE(CollapseShortEdges(Options(0.1), &held.mesh, &stats).ok());
  EXPECT_EQ(stats.edges, 0);
  EXPECT_EQ(held.mesh.face_sets.at("load").triangles, load.triangles);
}

// Many random short edges in meshes of three regions scattered cube by
// cube, collapsed with generous bounds: whatever goes, every tetrahedron
// stays positive, no face is shared by three, and the outer surface stays a
// sphere and each region's surface keeps its Euler characteristic (the link
// condition on the whole mesh and on each region). (The volume does change:
// the block's edges and corners are one patch with its faces, and are cut
// by edges this long.)
TEST(CollapseTest, ManyCollapsesKeepTheTopology) {
  std::mt19937 random(7);
  int collapsed = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<int> pick(0, 2);
    // Three boxes: a slab at x < 2 and the rest split at z = 3 (each cube
    // whole, so every region is a ball); every other trial one box.
    const bool one = trial % 2 == 0;
    Grid g = MakeGrid(5, {"a", "b", "c"}, [&](const Vec3& c) {
      return one ? 0 : c.x() < 2 ? 0 : c.z() < 3 ? 1 : 2;
    });
    const std::map<std::string, int> euler = EulerCharacteristics(g.mesh);
    std::uniform_int_distribution<int> index(0, 5);
    std::uniform_real_distribution<double> share(0.5, 0.97);
    for (int m = 0; m < 60; ++m) {
      const int i = index(random), j = index(random), k = index(random);
      const int step = pick(random);
      const int di = std::min(i + (step != 1), 5), dj = std::min(j + (step != 2), 5),
                dk = std::min(k + (step != 0), 5);
      if (di == i && dj == j && dk == k) continue;
      Mesh moved = g.mesh;
      MoveTowards(g.Node(i, j, k), g.Node(di, dj, dk), share(random), &moved);
      bool positive = true;
      for (int e = 0; e < moved.num_elements() && positive; ++e)
        positive = SignedVolume(moved, e) > 0;
      if (positive) g.mesh = std::move(moved);
    }
    CollapseOptions o = Options(2);
    o.max_edge_ratio = 1;
    o.target_min_dihedral_deg = 40;
    CollapseStats stats;
    ASSERT_TRUE(CollapseShortEdges(o, &g.mesh, &stats).ok());
    collapsed += stats.edges;
    SCOPED_TRACE("trial " + std::to_string(trial));
    ExpectValid(g.mesh, /*spheres=*/false);
    ExpectSphere(g.mesh.face_sets.at("surface"), "surface");
    EXPECT_EQ(EulerCharacteristics(g.mesh), euler);
    EXPECT_GE(stats.min_dihedral_after_deg, stats.min_dihedral_before_deg - 1e-9);
  }
  EXPECT_GT(collapsed, 100);
}

TEST(CollapseTest, BadOptionsAndMeshesAreRefused) {
  Grid g = OneRegion(2);
  CollapseOptions o = Options(0.1);
  o.max_edge_m = 0;
  Status s = CollapseShortEdges(o, &g.mesh, nullptr);
  EXPECT_EQ(s.field(), "max_edge_m");
  o = Options(0.1);
  o.max_edge_ratio = 1.5;
  EXPECT_EQ(CollapseShortEdges(o, &g.mesh, nullptr).field(), "max_edge_ratio");
  o = Options(0.1);
  o.target_min_dihedral_deg = 80;
  EXPECT_EQ(CollapseShortEdges(o, &g.mesh, nullptr).field(), "target_min_dihedral_deg");
  EXPECT_EQ(CollapseShortEdges(Options(0.1), nullptr, nullptr).field(), "mesh");
  Mesh inverted = g.mesh;
  std::swap(inverted.tets[0][0], inverted.tets[0][1]);
  const Mesh copy = inverted;
  s = CollapseShortEdges(Options(0.1), &inverted, nullptr);
  EXPECT_EQ(s.field(), "mesh.tets");
  EXPECT_EQ(inverted.tets, copy.tets);
}

}  // namespace
}  // namespace pba
