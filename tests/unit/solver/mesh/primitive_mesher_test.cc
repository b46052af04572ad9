#include "mesh/primitive_mesher.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "fem/tet4.h"

namespace pba {
namespace {

double TotalVolume(const Mesh& mesh, double* min_volume) {
  double total = 0;
  *min_volume = INFINITY;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double v = ComputeTet4Geometry(TetCorners(mesh, e)).volume;
    total += v;
    *min_volume = std::min(*min_volume, v);
  }
  return total;
}

// Conforming: every interior triangle is shared by exactly two elements, and
// the faces used once are exactly the boundary face sets.
void ExpectConforming(const Mesh& mesh) {
  std::map<std::array<int, 3>, int> count;
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (const auto& t : mesh.tets) {
    for (const auto& f : kFaces) {
      std::array<int, 3> key = {t[f[0]], t[f[1]], t[f[2]]};
      std::sort(key.begin(), key.end());
      ++count[key];
    }
  }
  std::set<std::array<int, 3>> boundary;
  for (const auto& [name, set] : mesh.face_sets) {
    for (auto tri : set.triangles) {
      std::sort(tri.begin(), tri.end());
      boundary.insert(tri);
    }
  }
  std::size_t once = 0;
  for (const auto& [face, n] : count) {
    ASSERT_LE(n, 2);
    if (n == 1) {
      ++once;
      EXPECT_TRUE(boundary.count(face)) << "a boundary face belongs to no set";
    }
  }
  EXPECT_EQ(once, boundary.size());
}

TEST(PrimitiveMesherTest, BoxVolumeIsExactAndMeshConforming) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec options;
  options.element_size_mm = 5;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  EXPECT_EQ(mesh.num_elements(), 6 * 2 * 4 * 6);
  EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
  double min_volume;
  EXPECT_NEAR(TotalVolume(mesh, &min_volume), 10e-3 * 20e-3 * 30e-3, 1e-15);
  EXPECT_GT(min_volume, 0);
  ExpectConforming(mesh);
  // Face set areas [m^2].
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("bottom")), 200e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("top")), 200e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("x_min")), 600e-6, 1e-15);
  EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("y_max")), 300e-6, 1e-15);
  for (int node : mesh.face_sets.at("top").nodes) EXPECT_NEAR(mesh.nodes(node, 2), 30e-3, 1e-15);
}

// Tetrahedra of `g` at element size h [mm]: as many as estimated, none
// inverted, and a volume error against `exact` [m^3] below 0.4 of the
// coarser mesh's (`previous_error`, updated): like h^2 or faster.
Mesh MeshWithConvergingVolume(const GeometrySpec& g, double h, double exact,
                              double* previous_error) {
  MeshSpec options;
  options.element_size_mm = h;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
  double min_volume;
  const double error = std::abs(TotalVolume(mesh, &min_volume) - exact) / exact;
  EXPECT_GT(min_volume, 0) << "h = " << h;
  EXPECT_LT(error, 0.4 * *previous_error) << "h = " << h;
  *previous_error = error;
  return mesh;
}

TEST(PrimitiveMesherTest, CylinderVolumeConvergesAndMeshIsConforming) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  g.cylinder = {10, 20};
  const double exact = std::numbers::pi * 10e-3 * 10e-3 * 20e-3;
  double previous_error = INFINITY;
  for (double h : {4.0, 2.0, 1.0}) {
    // A polygon inscribed in the circle: the error falls like h^2.
    const Mesh mesh = MeshWithConvergingVolume(g, h, exact, &previous_error);
    if (h == 2.0) ExpectConforming(mesh);
    for (int node : mesh.face_sets.at("side").nodes) {
      EXPECT_NEAR(mesh.nodes.row(node).head<2>().norm(), 10e-3, 1e-12);
    }
  }
  EXPECT_LT(previous_error, 0.01);
}

// Sums HexVolume over the bricks; `min_jacobian` is the smallest det J at a
// brick's corners, where a badly shaped trilinear brick turns first.
double HexTotalVolume(const Mesh& mesh, double* min_volume, double* min_jacobian) {
  static constexpr int kCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                        {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  double total = 0;
  *min_volume = INFINITY;
  *min_jacobian = INFINITY;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double v = HexVolume(mesh, e);
    total += v;
    *min_volume = std::min(*min_volume, v);
    const Eigen::Matrix<double, 8, 3> x = HexCorners(mesh, e);
    for (const auto& at : kCorner) {
      Eigen::Matrix<double, 8, 3> dn;
      for (int a = 0; a < 8; ++a) {
        double f[3];
        for (int j = 0; j < 3; ++j) f[j] = 1 + at[j] * kCorner[a][j];
        dn.row(a) << kCorner[a][0] * f[1] * f[2] / 8, kCorner[a][1] * f[0] * f[2] / 8,
            kCorner[a][2] * f[0] * f[1] / 8;
      }
      *min_jacobian = std::min(*min_jacobian, (x.transpose() * dn).determinant());
    }
  }
  return total;
}

// As ExpectConforming, for bricks and quads.
void ExpectHexConforming(const Mesh& mesh) {
  EXPECT_TRUE(mesh.tets.empty());
  std::map<std::array<int, 4>, int> count;
  for (const auto& h : mesh.hexes) {
    for (const auto& f : kHex8Faces) {
      std::array<int, 4> key = {h[f[0]], h[f[1]], h[f[2]], h[f[3]]};
      std::sort(key.begin(), key.end());
      ++count[key];
    }
  }
  std::set<std::array<int, 4>> boundary;
  for (const auto& [name, set] : mesh.face_sets) {
    EXPECT_TRUE(set.triangles.empty()) << name;
    for (auto quad : set.quads) {
      std::sort(quad.begin(), quad.end());
      boundary.insert(quad);
    }
  }
  std::size_t once = 0;
  for (const auto& [face, n] : count) {
    ASSERT_LE(n, 2);
    if (n == 1) {
      ++once;
      EXPECT_TRUE(boundary.count(face)) << "a boundary face belongs to no set";
    }
  }
  EXPECT_EQ(once, boundary.size());
}

// The outward normal of a set's quad (anticlockwise seen from outside), by
// its diagonals, unit length.
Eigen::Vector3d QuadNormal(const Mesh& mesh, const std::array<int, 4>& q) {
  const auto x = [&](int k) { return Eigen::Vector3d(mesh.nodes.row(q[k]).transpose()); };
  return (x(2) - x(0)).cross(x(3) - x(1)).normalized();
}

TEST(PrimitiveMesherTest, HexBoxIsExactConformingAndFacesOut) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec options;
  options.element = ElementType::kHex8;
  options.element_size_mm = 5;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  ASSERT_TRUE(mesh.hexahedral());
  EXPECT_EQ(mesh.num_nodes(), 3 * 5 * 7);
  EXPECT_EQ(mesh.num_elements(), 2 * 4 * 6);
  EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
  EXPECT_NE(stats.description.find("hexahedra"), std::string::npos) << stats.description;
  double min_volume, min_jacobian;
  EXPECT_NEAR(HexTotalVolume(mesh, &min_volume, &min_jacobian), 10e-3 * 20e-3 * 30e-3, 1e-15);
  EXPECT_NEAR(min_volume, 125e-9, 1e-18);  // every brick a 5 mm cube
  EXPECT_GT(min_jacobian, 0);
  ExpectHexConforming(mesh);
  // Per set: area [m^2], quad count, outward normal, and the Abaqus face
  // label (0-based) of the bricks behind it. The bricks are the section's
  // anticlockwise quads extruded along +z, so natural xi, eta, zeta run
  // along x, y, z.
  struct Expected {
    const char* name;
    double area;
    std::size_t quads;
    Eigen::Vector3d normal;
    int face;
  };
  const Expected expected[] = {{"bottom", 200e-6, 8, -Eigen::Vector3d::UnitZ(), 0},
                               {"top", 200e-6, 8, Eigen::Vector3d::UnitZ(), 1},
                               {"y_min", 300e-6, 12, -Eigen::Vector3d::UnitY(), 2},
                               {"x_max", 600e-6, 24, Eigen::Vector3d::UnitX(), 3},
                               {"y_max", 300e-6, 12, Eigen::Vector3d::UnitY(), 4},
                               {"x_min", 600e-6, 24, -Eigen::Vector3d::UnitX(), 5}};
  for (const Expected& e : expected) {
    const FaceSet& set = mesh.face_sets.at(e.name);
    EXPECT_NEAR(FaceSetArea(mesh, set), e.area, 1e-15) << e.name;
    EXPECT_EQ(set.quads.size(), e.quads) << e.name;
    const std::vector<std::array<int, 2>> owners = QuadFaceElements(mesh, set);
    for (std::size_t i = 0; i < set.quads.size(); ++i) {
      EXPECT_LT((QuadNormal(mesh, set.quads[i]) - e.normal).norm(), 1e-12) << e.name;
      ASSERT_GE(owners[i][0], 0) << e.name;
      EXPECT_EQ(owners[i][1], e.face) << e.name;
      // The brick's face, reversed, is the quad up to where it starts.
      const auto& h = mesh.hexes[owners[i][0]];
      const int* f = kHex8Faces[owners[i][1]];
      const std::array<int, 4> reversed = {h[f[0]], h[f[3]], h[f[2]], h[f[1]]};
      const int start = static_cast<int>(
          std::find(reversed.begin(), reversed.end(), set.quads[i][0]) - reversed.begin());
      ASSERT_LT(start, 4) << e.name;
      for (int k = 0; k < 4; ++k) EXPECT_EQ(reversed[(start + k) % 4], set.quads[i][k]) << e.name;
    }
  }
  // Each set's nodes: those of its quads, here 3 x 5 on the bottom.
  EXPECT_EQ(mesh.face_sets.at("bottom").nodes.size(), 15u);
  for (int node : mesh.face_sets.at("top").nodes) EXPECT_NEAR(mesh.nodes(node, 2), 30e-3, 1e-15);
}

TEST(PrimitiveMesherTest, HexCylinderVolumeConvergesAndBricksArePositive) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  g.cylinder = {10, 20};
  const double exact = std::numbers::pi * 10e-3 * 10e-3 * 20e-3;
  double previous_error = INFINITY;
  for (double h : {4.0, 2.0, 1.0}) {
    MeshSpec options;
    options.element = ElementType::kHex8;
    options.element_size_mm = h;
    MeshStats stats;
    const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
    EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
    double min_volume, min_jacobian;
    const double error = std::abs(HexTotalVolume(mesh, &min_volume, &min_jacobian) - exact) / exact;
    EXPECT_GT(min_volume, 0) << "h = " << h;
    EXPECT_GT(min_jacobian, 0) << "h = " << h;
    // The same inscribed polygon as the tetrahedra's: error like h^2.
    EXPECT_LT(error, 0.4 * previous_error) << "h = " << h;
    previous_error = error;
    if (h == 2.0) ExpectHexConforming(mesh);
    for (int node : mesh.face_sets.at("side").nodes) {
      EXPECT_NEAR(mesh.nodes.row(node).head<2>().norm(), 10e-3, 1e-12);
    }
    // The side's area, 2 pi R H less the chords' deficit.
    const double side = 2 * std::numbers::pi * 10e-3 * 20e-3;
    EXPECT_NEAR(FaceSetArea(mesh, mesh.face_sets.at("side")), side, 0.02 * side) << "h = " << h;
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(PrimitiveMesherTest, HalfCylinderIsTheLowerHalfWithAFlatCut) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kCylinder;
  g.cylinder.radius_mm = 10;
  g.cylinder.height_mm = 20;
  g.cylinder.half = true;
  const double exact = 0.5 * std::numbers::pi * 10e-3 * 10e-3 * 20e-3;
  for (ElementType element : {ElementType::kTet4, ElementType::kHex8}) {
    MeshSpec options;
    options.element = element;
    options.element_size_mm = 1.5;  // an odd central division, made even
    MeshStats stats;
    const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
    double min_volume, min_jacobian, volume;
    if (element == ElementType::kHex8) {
      volume = HexTotalVolume(mesh, &min_volume, &min_jacobian);
      ExpectHexConforming(mesh);
    } else {
      volume = TotalVolume(mesh, &min_volume);
      ExpectConforming(mesh);
    }
    EXPECT_GT(min_volume, 0);
    EXPECT_NEAR(volume, exact, 0.01 * exact);
    for (int node = 0; node < mesh.num_nodes(); ++node) {
      EXPECT_LE(mesh.nodes(node, 1), 1e-12) << "node " << node << " above the cut";
    }
    // The cut is the rectangle 2 R x H in the plane y = 0.
    const FaceSet& cut = mesh.face_sets.at("cut");
    EXPECT_NEAR(FaceSetArea(mesh, cut), 2 * 10e-3 * 20e-3, 1e-12);
    for (int node : cut.nodes) EXPECT_NEAR(mesh.nodes(node, 1), 0, 1e-15);
    EXPECT_EQ(PlaneNormalAxis(g, "cut"), 1);
    EXPECT_NEAR(mesh.num_elements(), EstimateElementCount(g, options),
                0.2 * EstimateElementCount(g, options));
  }
}

TEST(PrimitiveMesherTest, HexShellVolumeIsCloseAndBricksArePositive) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kSphericalShell;
  g.spherical_shell.inner_radius_mm = 10;
  g.spherical_shell.outer_radius_mm = 20;
  const double exact = std::numbers::pi * (20e-3 * 20e-3 * 20e-3 - 10e-3 * 10e-3 * 10e-3) / 6;
  double previous_error = INFINITY;
  for (double h : {5.0, 2.5, 1.25}) {
    MeshSpec options;
    options.element = ElementType::kHex8;
    options.element_size_mm = h;
    MeshStats stats;
    const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
    EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
    double min_volume, min_jacobian;
    const double error = std::abs(HexTotalVolume(mesh, &min_volume, &min_jacobian) - exact) / exact;
    EXPECT_GT(min_volume, 0) << "h = " << h;
    EXPECT_GT(min_jacobian, 0) << "h = " << h;
    // Faceted spheres and cut-plane arcs: about 3e-2, 1.1e-2, 2.7e-3, like h^2
    // (3, 5 and 10 cells along a patch edge).
    EXPECT_LT(error, 0.4 * previous_error) << "h = " << h;
    previous_error = error;
    ExpectHexConforming(mesh);
    for (int node : mesh.face_sets.at("inner").nodes) {
      EXPECT_NEAR(mesh.nodes.row(node).norm(), 10e-3, 1e-12);
    }
    for (const char* name : {"inner", "outer", "x0", "y0", "z0"}) {
      EXPECT_FALSE(mesh.face_sets.at(name).quads.empty()) << name;
    }
  }
  EXPECT_LT(previous_error, 0.01);
}

// The smallest dihedral angle of the tetrahedra [degrees].
double MinDihedralDegrees(const Mesh& mesh) {
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  double smallest = 180;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
    for (const auto& edge : kEdges) {
      int others[2], k = 0;
      for (int v = 0; v < 4; ++v) {
        if (v != edge[0] && v != edge[1]) others[k++] = v;
      }
      const Eigen::Vector3d axis = (x.row(edge[1]) - x.row(edge[0])).normalized();
      Eigen::Vector3d a = x.row(others[0]) - x.row(edge[0]);
      Eigen::Vector3d b = x.row(others[1]) - x.row(edge[0]);
      a -= a.dot(axis) * axis;
      b -= b.dot(axis) * axis;
      const double angle = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
      smallest = std::min(smallest, angle * 180 / std::numbers::pi);
    }
  }
  return smallest;
}

// An ellipsoid of a brain's proportions: tetrahedra cut from an O-grid's
// bricks, conforming, none flat, surface nodes on the ellipsoid, the volume
// converging like h^2 to 4 pi a b c / 3.
TEST(PrimitiveMesherTest, EllipsoidVolumeConvergesAndMeshIsConforming) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kEllipsoid;
  g.ellipsoid.semi_axes_mm = {70, 60, 50};
  const double exact = 4.0 / 3 * std::numbers::pi * 70e-3 * 60e-3 * 50e-3;
  double previous_error = INFINITY;
  for (double h : {20.0, 10.0, 5.0}) {
    const Mesh mesh = MeshWithConvergingVolume(g, h, exact, &previous_error);
    // Cells at the cube's corners are the most skewed; no sliver.
    const double dihedral = MinDihedralDegrees(mesh);
    std::printf("ellipsoid, %g mm: smallest dihedral angle %.1f degrees\n", h, dihedral);
    EXPECT_GT(dihedral, 12) << "h = " << h;
    if (h == 10.0) ExpectConforming(mesh);
    ASSERT_EQ(mesh.face_sets.size(), 1u);
    for (int node : mesh.face_sets.at("surface").nodes) {
      const Eigen::Vector3d x = mesh.nodes.row(node).transpose();
      EXPECT_NEAR(x.cwiseQuotient(Eigen::Vector3d(70e-3, 60e-3, 50e-3)).norm(), 1, 1e-12);
    }
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(PrimitiveMesherTest, HexEllipsoidIsConformingAndBricksArePositive) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kEllipsoid;
  g.ellipsoid.semi_axes_mm = {70, 60, 50};
  const double exact = 4.0 / 3 * std::numbers::pi * 70e-3 * 60e-3 * 50e-3;
  MeshSpec options;
  options.element = ElementType::kHex8;
  options.element_size_mm = 10;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  EXPECT_EQ(mesh.num_elements(), EstimateElementCount(g, options));
  double min_volume, min_jacobian;
  const double volume = HexTotalVolume(mesh, &min_volume, &min_jacobian);
  EXPECT_NEAR(volume, exact, 0.02 * exact);
  EXPECT_GT(min_jacobian, 0);
  ExpectHexConforming(mesh);
  // Every surface quad faces out: its normal points away from the centre.
  for (const auto& q : mesh.face_sets.at("surface").quads) {
    EXPECT_GT(QuadNormal(mesh, q).dot(Eigen::Vector3d(mesh.nodes.row(q[0]).transpose())), 0);
  }
}

// A patch holds the faces whose nodes all lie in its ball, with their
// mid-edge nodes on a quadratic mesh.
TEST(PrimitiveMesherTest, FacesWithinKeepsTheFacesInsideTheBall) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 10};
  MeshSpec options;
  options.element_size_mm = 1;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  const Eigen::Vector3d centre(5e-3, 5e-3, 10e-3);
  const FaceSet patch = FacesWithin(mesh, mesh.face_sets.at("top"), centre, 3e-3);
  ASSERT_FALSE(patch.triangles.empty());
  for (const auto& t : patch.triangles) {
    for (int v : t) EXPECT_LE((mesh.nodes.row(v).transpose() - centre).norm(), 3e-3);
  }
  // A disk of radius 3 mm less a rim of at most one cell.
  const double area = FaceSetArea(mesh, patch);
  EXPECT_LT(area, std::numbers::pi * 9e-6);
  EXPECT_GT(area, std::numbers::pi * 4e-6);
  EXPECT_TRUE(FacesWithin(mesh, mesh.face_sets.at("bottom"), centre, 3e-3).triangles.empty());
}

TEST(PrimitiveMesherTest, DefaultElementSizeIsATwentiethOfTheLargestDimension) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 40};
  EXPECT_DOUBLE_EQ(EffectiveElementSize(g, MeshSpec()), 2.0);
}

}  // namespace
}  // namespace pba
