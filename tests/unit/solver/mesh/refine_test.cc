#include "mesh/refine.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <set>

#include "fem/tet4.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"
#include "mesh/quality.h"

namespace pba {
namespace {

Mesh Box(double h) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec options;
  options.element_size_mm = h;
  MeshStats stats;
  return BuildPrimitiveMesh(g, options, &stats);
}

// The box with its inner nodes moved by up to a fifth of `h` along each
// axis (a fixed pseudo-random sequence): no two edges of the same length,
// elements of many shapes.
Mesh JitteredBox(double h) {
  Mesh mesh = Box(h);
  std::vector<char> on_boundary(mesh.num_nodes(), 0);
  for (const auto& [name, set] : mesh.face_sets)
    for (int n : set.nodes) on_boundary[n] = 1;
  uint32_t state = 12345;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / (1u << 24) - 0.5;  // -0.5..0.5
  };
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    for (int c = 0; c < 3; ++c) {
      const double shift = 0.4 * h * 1e-3 * next();
      if (!on_boundary[n]) mesh.nodes(n, c) += shift;
    }
  }
  return mesh;
}

double Volume(const Mesh& mesh, int e) { return ComputeTet4Geometry(TetCorners(mesh, e)).volume; }

// Every element positive; every interior face shared by two elements, each
// seeing it the other way round (no hanging node: a face of a refined
// element that met a whole neighbour would be seen once); the faces seen
// once are exactly the face sets' triangles, oriented as the element's face
// seen from outside.
void ExpectConforming(const Mesh& mesh) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<int, 3>, std::vector<std::array<int, 3>>> seen;  // sorted -> oriented
  for (int e = 0; e < mesh.num_elements(); ++e) {
    ASSERT_GT(Volume(mesh, e), 0) << "element " << e;
    const auto& t = mesh.tets[e];
    for (const auto& f : kFaces) {
      std::array<int, 3> face = {t[f[0]], t[f[1]], t[f[2]]};
      std::array<int, 3> key = face;
      std::sort(key.begin(), key.end());
      seen[key].push_back(face);
    }
  }
  // A cyclic rotation of a triangle is the same oriented face.
  const auto same = [](std::array<int, 3> a, std::array<int, 3> b) {
    for (int r = 0; r < 3; ++r) {
      if (a == b) return true;
      std::rotate(b.begin(), b.begin() + 1, b.end());
    }
    return false;
  };
  std::set<std::array<int, 3>> boundary;
  for (const auto& [name, set] : mesh.face_sets) {
    for (const auto& tri : set.triangles) {
      std::array<int, 3> key = tri;
      std::sort(key.begin(), key.end());
      const auto it = seen.find(key);
      ASSERT_NE(it, seen.end()) << name << ": a triangle that is no element's face";
      ASSERT_EQ(it->second.size(), 1u) << name << ": a triangle inside the body";
      EXPECT_TRUE(same(tri, it->second[0])) << name << ": a triangle turned inwards";
      boundary.insert(key);
    }
  }
  std::size_t once = 0;
  for (const auto& [key, faces] : seen) {
    ASSERT_LE(faces.size(), 2u);
    if (faces.size() == 2) {
      std::array<int, 3> reversed = faces[1];
      std::swap(reversed[1], reversed[2]);
      EXPECT_TRUE(same(faces[0], reversed)) << "two elements on the same side of a face";
    } else {
      ++once;
      EXPECT_TRUE(boundary.count(key)) << "a face of one element belongs to no set";
    }
  }
  EXPECT_EQ(once, boundary.size());
}

// Whether element e of `mesh` holds point x (within rounding).
bool Holds(const Mesh& mesh, int e, const Eigen::Vector3d& x) {
  const auto corners = TetCorners(mesh, e);
  const Eigen::Matrix3d edges = (corners.bottomRows<3>().rowwise() - corners.row(0)).transpose();
  const Eigen::Vector3d local = edges.inverse() * (x - corners.row(0).transpose());
  return (local.array() >= -1e-12).all() && local.sum() <= 1 + 1e-12;
}

double TotalVolume(const Mesh& mesh) {
  double total = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) total += Volume(mesh, e);
  return total;
}

double SmallestDihedral(const Mesh& mesh) {
  double smallest = 180;
  for (int e = 0; e < mesh.num_elements(); ++e)
    smallest = std::min(smallest, TetDihedralRangeDegrees(TetCorners(mesh, e))[0]);
  return smallest;
}

TEST(RefineTest, OneMarkedElementIsHalvedAndTheMeshStaysConforming) {
  const Mesh coarse = Box(5);
  std::vector<char> marked(coarse.num_elements(), 0);
  const int chosen = coarse.num_elements() / 2;
  marked[chosen] = 1;
  Mesh fine;
  RefineReport report;
  ASSERT_TRUE(RefineTets(coarse, marked, &fine, &report).ok());
  EXPECT_EQ(report.marked, 1);
  EXPECT_GE(report.cut_edges, 1);
  EXPECT_EQ(report.elements, fine.num_elements());
  EXPECT_GT(fine.num_elements(), coarse.num_elements());
  // The longest-edge closure spreads the cut only a little.
  EXPECT_LT(fine.num_elements(), coarse.num_elements() + 40);
  EXPECT_EQ(fine.num_nodes(), coarse.num_nodes() + report.cut_edges);
  // The coarse nodes keep their indices and places.
  EXPECT_EQ(fine.nodes.topRows(coarse.num_nodes()), coarse.nodes);
  EXPECT_NEAR(TotalVolume(fine), TotalVolume(coarse), 1e-18);
  ExpectConforming(fine);
  // The marked element's corners are all still corners, and no element of
  // the refined mesh is as large as it was.
  const double chosen_volume = Volume(coarse, chosen);
  const Eigen::Vector3d centroid = TetCorners(coarse, chosen).colwise().mean().transpose();
  for (int e = 0; e < fine.num_elements(); ++e) {
    // The element of the fine mesh holding the coarse element's centroid.
    if (!Holds(fine, e, centroid)) continue;
    EXPECT_LE(Volume(fine, e), 0.5 * chosen_volume * (1 + 1e-12));
  }
  for (const auto& [name, set] : coarse.face_sets) {
    EXPECT_NEAR(FaceSetArea(fine, fine.face_sets.at(name)), FaceSetArea(coarse, set), 1e-18)
        << name;
  }
}

TEST(RefineTest, RegionsKeepTheirVolumesAndFaceSetsTheirNodesOnThePlane) {
  Mesh coarse = Box(5);
  coarse.region_names = {"left", "right"};
  std::vector<double> region_volume(2, 0);
  for (int e = 0; e < coarse.num_elements(); ++e) {
    const double x = TetCorners(coarse, e).col(0).mean();
    coarse.element_region.push_back(x < 5e-3 ? 0 : 1);
    region_volume[coarse.element_region.back()] += Volume(coarse, e);
  }
  // Every third element, twice over.
  Mesh mesh = coarse;
  for (int round = 0; round < 2; ++round) {
    std::vector<char> marked(mesh.num_elements(), 0);
    for (int e = 0; e < mesh.num_elements(); e += 3) marked[e] = 1;
    Mesh fine;
    ASSERT_TRUE(RefineTets(mesh, marked, &fine).ok());
    mesh = std::move(fine);
  }
  ASSERT_EQ(mesh.element_region.size(), mesh.tets.size());
  std::vector<double> refined(2, 0);
  for (int e = 0; e < mesh.num_elements(); ++e) refined[mesh.element_region[e]] += Volume(mesh, e);
  EXPECT_NEAR(refined[0], region_volume[0], 1e-18);
  EXPECT_NEAR(refined[1], region_volume[1], 1e-18);
  ExpectConforming(mesh);
  for (int node : mesh.face_sets.at("top").nodes) EXPECT_NEAR(mesh.nodes(node, 2), 30e-3, 1e-15);
  for (const auto& tri : mesh.face_sets.at("top").triangles) {
    const Eigen::Vector3d a = mesh.nodes.row(tri[0]), b = mesh.nodes.row(tri[1]),
                          c = mesh.nodes.row(tri[2]);
    EXPECT_GT((b - a).cross(c - a).z(), 0) << "the top's normal points out, +z";
  }
}

// Uniform refinement four times over (every element at least halved each
// time) of a mesh of irregular elements: conforming every time, and the
// smallest dihedral angle stays within a fixed factor of the coarse
// mesh's.
TEST(RefineTest, RepeatedRefinementKeepsTheShapes) {
  Mesh mesh = JitteredBox(5);
  const double coarse_angle = SmallestDihedral(mesh);
  const double coarse_volume = TotalVolume(mesh);
  const int coarse_elements = mesh.num_elements();
  for (int round = 0; round < 4; ++round) {
    Mesh fine;
    ASSERT_TRUE(RefineTets(mesh, std::vector<char>(mesh.num_elements(), 1), &fine).ok());
    EXPECT_GE(fine.num_elements(), 2 * mesh.num_elements());
    mesh = std::move(fine);
    ExpectConforming(mesh);
    EXPECT_GE(SmallestDihedral(mesh), 0.5 * coarse_angle) << "round " << round;
  }
  EXPECT_GE(mesh.num_elements(), 16 * coarse_elements);
  EXPECT_NEAR(TotalVolume(mesh), coarse_volume, 1e-12 * coarse_volume);
}

// Local refinement, repeated where the elements are already finest (a
// corner of the box), as an adaptive solve does: conforming, and the
// refinement stays near the corner.
TEST(RefineTest, RefinementTowardsACornerStaysLocal) {
  Mesh mesh = JitteredBox(5);
  const double coarse_angle = SmallestDihedral(mesh);
  double coarse_smallest = INFINITY, coarse_largest = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    coarse_smallest = std::min(coarse_smallest, Volume(mesh, e));
    coarse_largest = std::max(coarse_largest, Volume(mesh, e));
  }
  const int coarse_elements = mesh.num_elements();
  for (int round = 0; round < 6; ++round) {
    std::vector<char> marked(mesh.num_elements(), 0);
    for (int e = 0; e < mesh.num_elements(); ++e)
      marked[e] = TetCorners(mesh, e).rowwise().norm().minCoeff() < 3e-3;
    Mesh fine;
    ASSERT_TRUE(RefineTets(mesh, marked, &fine).ok());
    mesh = std::move(fine);
  }
  ExpectConforming(mesh);
  EXPECT_GE(SmallestDihedral(mesh), 0.5 * coarse_angle);
  EXPECT_GE(mesh.num_elements(), 2 * coarse_elements);
  // Elements beyond 15 mm of the corner are the coarse ones, elements
  // at the corner at least 2^6 times smaller (halved at least once a round).
  int far_fine = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double distance = TetCorners(mesh, e).rowwise().norm().minCoeff();
    if (distance > 15e-3 && Volume(mesh, e) < 0.9 * coarse_smallest) ++far_fine;
    if (distance < 1e-9) {
      EXPECT_LE(Volume(mesh, e), coarse_largest / 64);
    }
  }
  EXPECT_EQ(far_fine, 0);
}

// Three bisections of the marked elements halve their edges: every element
// inside a marked coarse one has at most an eighth of its volume, and the
// parents RefineTets reports hold their children.
TEST(RefineTest, ThreeBisectionsHalveTheMarkedElements) {
  const Mesh coarse = JitteredBox(5);
  std::vector<char> marked(coarse.num_elements(), 0);
  for (int e = 0; e < coarse.num_elements(); e += 5) marked[e] = 1;
  Mesh once;
  std::vector<int> parent;
  ASSERT_TRUE(RefineTets(coarse, marked, &once, nullptr, &parent).ok());
  ASSERT_EQ(parent.size(), once.tets.size());
  std::vector<double> children(coarse.num_elements(), 0);
  for (int f = 0; f < once.num_elements(); ++f) children[parent[f]] += Volume(once, f);
  for (int e = 0; e < coarse.num_elements(); ++e)
    EXPECT_NEAR(children[e], Volume(coarse, e), 1e-12 * Volume(coarse, e));

  Mesh fine;
  RefineReport report;
  ASSERT_TRUE(RefineTetsRepeatedly(coarse, marked, 3, &fine, &report).ok());
  ExpectConforming(fine);
  EXPECT_EQ(report.marked, (coarse.num_elements() + 4) / 5);
  EXPECT_EQ(report.elements, fine.num_elements());
  EXPECT_GE(fine.num_elements(), coarse.num_elements() + 7 * report.marked);
  for (int e = 0; e < coarse.num_elements(); ++e) {
    if (!marked[e]) continue;
    const Eigen::Vector3d centroid = TetCorners(coarse, e).colwise().mean().transpose();
    for (int f = 0; f < fine.num_elements(); ++f) {
      if (!Holds(fine, f, centroid)) continue;
      EXPECT_LE(Volume(fine, f), Volume(coarse, e) / 8 * (1 + 1e-9));
    }
  }
}

// A bound on the elements stops the passes once one passes it.
TEST(RefineTest, RepeatedRefinementStopsPastItsBound) {
  const Mesh coarse = JitteredBox(5);
  const std::vector<char> all(coarse.num_elements(), 1);
  Mesh fine;
  RefineReport whole, bounded;
  ASSERT_TRUE(RefineTetsRepeatedly(coarse, all, 3, &fine, &whole).ok());
  const int64_t bound = coarse.num_elements() + 1;
  ASSERT_TRUE(RefineTetsRepeatedly(coarse, all, 3, &fine, &bounded, bound).ok());
  EXPECT_GT(bounded.elements, bound);
  EXPECT_LT(bounded.elements, whole.elements);
  ASSERT_TRUE(RefineTetsRepeatedly(coarse, all, 3, &fine, &bounded, whole.elements).ok());
  EXPECT_EQ(bounded.elements, whole.elements);
}

TEST(RefineTest, SameInputSameMesh) {
  const Mesh coarse = JitteredBox(5);
  std::vector<char> marked(coarse.num_elements(), 0);
  for (int e = 0; e < coarse.num_elements(); e += 7) marked[e] = 1;
  Mesh a, b;
  ASSERT_TRUE(RefineTets(coarse, marked, &a).ok());
  ASSERT_TRUE(RefineTets(coarse, marked, &b).ok());
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.nodes, b.nodes);
}

TEST(RefineTest, NothingMarkedChangesNothing) {
  const Mesh coarse = Box(5);
  Mesh fine;
  RefineReport report;
  ASSERT_TRUE(RefineTets(coarse, std::vector<char>(coarse.num_elements(), 0), &fine, &report).ok());
  EXPECT_EQ(fine.tets, coarse.tets);
  EXPECT_EQ(fine.nodes, coarse.nodes);
  EXPECT_EQ(report.cut_edges, 0);
}

TEST(RefineTest, RefusesWhatItCannotRefine) {
  const Mesh coarse = Box(5);
  Mesh fine;
  const Status wrong = RefineTets(coarse, std::vector<char>(3, 1), &fine);
  EXPECT_EQ(wrong.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(wrong.field(), "marked");
  const Mesh quadratic = MakeQuadratic(coarse, {});
  const Status shape = RefineTets(quadratic, std::vector<char>(quadratic.num_elements(), 1), &fine);
  EXPECT_EQ(shape.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(shape.field(), "mesh");
}

TEST(RefineTest, MarkLargestShareTakesTheFewestThatCarryTheFraction) {
  EXPECT_EQ(MarkLargestShare({0.1, 0.5, 0.3, 0.1}, 0.5), (std::vector<char>{0, 1, 0, 0}));
  EXPECT_EQ(MarkLargestShare({0.1, 0.5, 0.3, 0.1}, 0.6), (std::vector<char>{0, 1, 1, 0}));
  // Ties, to rounding, are taken together.
  EXPECT_EQ(MarkLargestShare({0.25, 0.25, 0.25, 0.25}, 0.5), (std::vector<char>{1, 1, 1, 1}));
  EXPECT_EQ(MarkLargestShare({0.2, 0.3 * (1 + 1e-12), 0.3, 0.2}, 0.3),
            (std::vector<char>{0, 1, 1, 0}));
  EXPECT_EQ(MarkLargestShare({0.2, 0.3 * (1 + 1e-3), 0.3, 0.2}, 0.3),
            (std::vector<char>{0, 1, 0, 0}));
  EXPECT_EQ(MarkLargestShare({0.2, 0.8}, 1.0), (std::vector<char>{1, 1}));
  EXPECT_EQ(MarkLargestShare({0, 0}, 0.5), (std::vector<char>{0, 0}));
}

}  // namespace
}  // namespace pba
