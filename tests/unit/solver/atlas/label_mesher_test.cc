#include "atlas/label_mesher.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "mesh/quadratic.h"
#include "mesh/quality.h"

namespace pba {
namespace {

// Two nested spheres [mm]: a core (label 2) of radius 10 inside a shell
// (label 1) of outer radius 20.
constexpr double kCoreRadius = 10, kShellRadius = 20;
const std::vector<std::string> kNames = {"shell", "core"};

int TwoSpheres(const Eigen::Vector3d& x) {
  const double r = x.norm();
  return r < kCoreRadius ? 2 : r < kShellRadius ? 1 : 0;
}

// Coarse enough for the unit suite (a few seconds), fine enough that the
// surfaces are within 0.2 mm of the spheres.
LabelMeshOptions SphereOptions(double cell_size_mm = 3) {
  LabelMeshOptions o;
  o.box_min_mm = Eigen::Vector3d::Constant(-25);
  o.box_max_mm = Eigen::Vector3d::Constant(25);
  o.cell_size_mm = cell_size_mm;
  o.facet_size_mm = 2;
  o.facet_distance_mm = 0.2;
  return o;
}

double SphereVolume(double r) { return 4.0 / 3 * std::numbers::pi * r * r * r; }

using Triangle = std::array<int, 3>;

Triangle Sorted(Triangle t) {
  std::sort(t.begin(), t.end());
  return t;
}

std::set<Triangle> SortedTriangles(const FaceSet& set) {
  std::set<Triangle> out;
  for (const Triangle& t : set.triangles) out.insert(Sorted(t));
  return out;
}

// Distances [mm] from the origin of a face set's corners and centroids.
std::array<double, 2> RadiusRange(const Mesh& mesh, const FaceSet& set) {
  std::array<double, 2> range{1e300, 0};
  for (const Triangle& t : set.triangles) {
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for (int n : t) {
      const double r = 1e3 * mesh.nodes.row(n).norm();
      range = {std::min(range[0], r), std::max(range[1], r)};
      centroid += mesh.nodes.row(n) / 3;
    }
    const double r = 1e3 * centroid.norm();
    range = {std::min(range[0], r), std::max(range[1], r)};
  }
  return range;
}

// The sphere pair: regions, volumes, orientation, conformity, face sets on
// the spheres, labels at the centroids, quality.
//
// Volume tolerance: the surface vertices lie on the spheres (to the 1e-6
// relative error bound), so each surface triangle is a chord plane of its
// sphere, at most its sagitta s inside it, and Mesh_3's facet distance
// criterion keeps s <= delta = 0.2 mm (it bounds the distance from the
// triangle's circumcentre, where the gap is largest, to the surface). Over
// a near-equilateral triangle the gap (rho^2 - d^2) / (2 r), d the distance
// from the circumcentre, averages 3 s / 4, so a ball of radius r loses at
// most 3/4 delta of its 4 pi r^2 surface area: a relative volume of
// 9 delta / (4 r), 4.5 % for the core, 2.25 % for the outer sphere. The
// shell's volume is the difference of the two, so its error is bounded by
// the sum of the two losses over its volume: 3.2 %.
TEST(LabelMesherTest, NestedSpheresGiveAConformingTwoRegionMesh) {
  const LabelMeshOptions options = SphereOptions();
  Mesh mesh;
  const auto start = std::chrono::steady_clock::now();
  const Status status = MeshLabels(TwoSpheres, kNames, options, &mesh);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(status.ok()) << status.ToString();
  ASSERT_EQ(mesh.region_names, kNames);
  ASSERT_EQ(mesh.element_region.size(), mesh.tets.size());
  EXPECT_FALSE(mesh.quadratic());

  // Regions and volumes [mm^3].
  const QualitySummary quality = Summarise(mesh);
  ASSERT_EQ(quality.regions.size(), 2u);
  const double delta = options.facet_distance_mm;
  const double loss_shell = 9 * delta / (4 * kShellRadius) * SphereVolume(kShellRadius);
  const double loss_core = 9 * delta / (4 * kCoreRadius) * SphereVolume(kCoreRadius);
  const double exact[2] = {SphereVolume(kShellRadius) - SphereVolume(kCoreRadius),
                           SphereVolume(kCoreRadius)};
  const double tolerance[2] = {(loss_shell + loss_core) / exact[0], loss_core / exact[1]};
  double error[2];
  for (int r = 0; r < 2; ++r) {
    EXPECT_GT(quality.regions[r].count, 0) << kNames[r];
    error[r] = quality.regions[r].volume * 1e9 / exact[r] - 1;
    EXPECT_LT(std::abs(error[r]), tolerance[r]) << kNames[r];
  }
  EXPECT_LT(error[1], 0) << "the core's triangles are chords: it can only lose volume";

  // Every tetrahedron positively oriented; its centroid in its own region.
  int straddling = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
    const Eigen::Vector3d a = (x.row(1) - x.row(0)).transpose();
    const Eigen::Vector3d b = (x.row(2) - x.row(0)).transpose();
    const Eigen::Vector3d c = (x.row(3) - x.row(0)).transpose();
    ASSERT_GT(a.dot(b.cross(c)), 0) << "element " << e;
    const Eigen::Vector3d centroid_mm = 1e3 * x.colwise().mean().transpose();
    if (TwoSpheres(centroid_mm) != mesh.element_region[e] + 1) ++straddling;
  }
  EXPECT_EQ(straddling, 0);

  // Conformity: each triangle of a tetrahedron belongs to one (boundary) or
  // two (interior) tetrahedra; the boundary ones are exactly "surface", the
  // interior ones between regions exactly the interface.
  std::map<Triangle, std::vector<int>> owners;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& t = mesh.tets[e];
    for (int skip = 0; skip < 4; ++skip) {
      Triangle face;
      for (int k = 0, j = 0; k < 4; ++k) {
        if (k != skip) face[j++] = t[k];
      }
      owners[Sorted(face)].push_back(e);
    }
  }
  std::set<Triangle> boundary, interface;
  for (const auto& [face, elements] : owners) {
    ASSERT_LE(elements.size(), 2u);
    if (elements.size() == 1) boundary.insert(face);
    if (elements.size() == 2 &&
        mesh.element_region[elements[0]] != mesh.element_region[elements[1]])
      interface.insert(face);
  }
  ASSERT_EQ(mesh.face_sets.size(), 4u);
  const FaceSet& surface = mesh.face_sets.at("surface");
  const FaceSet& between = mesh.face_sets.at("interface:shell|core");
  EXPECT_EQ(SortedTriangles(surface), boundary);
  EXPECT_EQ(surface.triangles.size(), boundary.size()) << "no triangle twice";
  EXPECT_EQ(SortedTriangles(between), interface);
  EXPECT_EQ(between.triangles.size(), interface.size());
  EXPECT_FALSE(surface.nodes.empty());
  // Each region's whole boundary: the core's is the interface, turned to
  // face out of the core; the shell's is the outer surface and the
  // interface.
  const FaceSet& core = mesh.face_sets.at("surface:core");
  const FaceSet& shell = mesh.face_sets.at("surface:shell");
  EXPECT_EQ(SortedTriangles(core), interface);
  std::set<Triangle> both = boundary;
  both.insert(interface.begin(), interface.end());
  EXPECT_EQ(SortedTriangles(shell), both);
  EXPECT_EQ(shell.triangles.size(), both.size());
  for (const Triangle& t : core.triangles) {
    const Eigen::Vector3d p0 = mesh.nodes.row(t[0]).transpose();
    const Eigen::Vector3d normal =
        (mesh.nodes.row(t[1]).transpose() - p0).cross(mesh.nodes.row(t[2]).transpose() - p0);
    ASSERT_GT(normal.dot(p0), 0) << "out of the core";
  }

  // Surface triangles face outwards, interface ones from the shell into the
  // core (inwards).
  for (const auto& [set, sign] : {std::pair{&surface, 1.0}, std::pair{&between, -1.0}}) {
    for (const Triangle& t : set->triangles) {
      const Eigen::Vector3d p0 = mesh.nodes.row(t[0]).transpose();
      const Eigen::Vector3d normal =
          (mesh.nodes.row(t[1]).transpose() - p0).cross(mesh.nodes.row(t[2]).transpose() - p0);
      ASSERT_GT(sign * normal.dot(p0), 0);
    }
  }

  // On the spheres: corners on them (to the bisection's accuracy, 1e-6 of
  // the box's 87 mm diagonal), centroids at most the facet distance inside
  // (plus 10 % for the criterion being measured at the circumcentre).
  const std::array<double, 2> outer = RadiusRange(mesh, surface);
  const std::array<double, 2> inner = RadiusRange(mesh, between);
  EXPECT_GT(outer[0], kShellRadius - 1.1 * delta);
  EXPECT_LT(outer[1], kShellRadius + 1e-3);
  EXPECT_GT(inner[0], kCoreRadius - 1.1 * delta);
  EXPECT_LT(inner[1], kCoreRadius + 1e-3);

  // Quality after perturbation and exudation.
  EXPECT_GT(quality.overall.min_dihedral_deg, 5);
  EXPECT_LT(quality.overall.median_aspect_ratio, 2);
  std::printf(
      "nested spheres, cell %g mm: %d tetrahedra, %d nodes, %zu surface / %zu interface "
      "triangles; volume error shell %+.2f %% (bound %.2f %%), core %+.2f %% (bound %.2f %%); "
      "dihedral %.1f-%.1f deg; aspect ratio median %.3f, max %.2f; %d straddling; %.2f s\n",
      options.cell_size_mm, mesh.num_elements(), mesh.num_nodes(), surface.triangles.size(),
      between.triangles.size(), 100 * error[0], 100 * tolerance[0], 100 * error[1],
      100 * tolerance[1], quality.overall.min_dihedral_deg, quality.overall.max_dihedral_deg,
      quality.overall.median_aspect_ratio, quality.overall.max_aspect_ratio, straddling, seconds);
}

TEST(LabelMesherTest, SameInputsGiveTheSameMesh) {
  const LabelMeshOptions options = SphereOptions();
  Mesh first, second;
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &first).ok());
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &second).ok());
  ASSERT_EQ(first.num_nodes(), second.num_nodes());
  EXPECT_TRUE(first.nodes == second.nodes) << "bit for bit";
  EXPECT_EQ(first.tets, second.tets);
  EXPECT_EQ(first.element_region, second.element_region);
  EXPECT_EQ(first.face_sets.at("surface").triangles, second.face_sets.at("surface").triangles);
}

TEST(LabelMesherTest, BadOptionsNameTheField) {
  const auto field_of = [](const LabelMeshOptions& o,
                           const std::vector<std::string>& names = kNames) {
    Mesh mesh;
    const Status s = MeshLabels(TwoSpheres, names, o, &mesh);
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << s.ToString();
    return s.field();
  };
  LabelMeshOptions o = SphereOptions();
  o.cell_size_mm = 0;
  EXPECT_EQ(field_of(o), "cell_size_mm");
  o = SphereOptions();
  o.facet_size_mm = -1;
  EXPECT_EQ(field_of(o), "facet_size_mm");
  o = SphereOptions();
  o.facet_distance_mm = -0.1;
  EXPECT_EQ(field_of(o), "facet_distance_mm");
  o = SphereOptions();
  o.facet_angle_deg = 40;
  EXPECT_EQ(field_of(o), "facet_angle_deg");
  o = SphereOptions();
  o.cell_radius_edge_ratio = 1.5;
  EXPECT_EQ(field_of(o), "cell_radius_edge_ratio");
  o = SphereOptions();
  o.box_max_mm.y() = o.box_min_mm.y();
  EXPECT_EQ(field_of(o), "box_max_mm");
  o = SphereOptions();
  std::swap(o.box_min_mm, o.box_max_mm);
  EXPECT_EQ(field_of(o), "box_max_mm");
  o = SphereOptions();
  o.roi_radius_mm = 5;
  o.roi_size_mm = 0;
  EXPECT_EQ(field_of(o), "roi_size_mm");
  o.roi_size_mm = 2 * o.cell_size_mm;
  EXPECT_EQ(field_of(o), "roi_size_mm");
  o.roi_radius_mm = -1;
  EXPECT_EQ(field_of(o), "roi_radius_mm");
  o = SphereOptions();
  o.region_cell_size_mm = {1};
  EXPECT_EQ(field_of(o), "region_cell_size_mm");
  o.region_cell_size_mm = {1, -1};
  EXPECT_EQ(field_of(o), "region_cell_size_mm[1]");
  o = SphereOptions();
  o.region_facet_size_mm = {1, 2, 3};
  EXPECT_EQ(field_of(o), "region_facet_size_mm");
  EXPECT_EQ(field_of(SphereOptions(), {}), "region_names");
  Mesh mesh;
  EXPECT_EQ(MeshLabels(LabelFunction(), kNames, SphereOptions(), &mesh).field(), "label");
}

// A region of interest at one side of the shell: its elements are smaller
// there than on the opposite side, and the coarse side is as without it.
TEST(LabelMesherTest, RegionOfInterestRefinesOnlyThere) {
  const auto mean_volume_near = [](const Mesh& mesh, const Eigen::Vector3d& centre_mm,
                                   double radius_mm) {
    double volume = 0;
    int count = 0;
    for (int e = 0; e < mesh.num_elements(); ++e) {
      const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e) * 1e3;  // mm
      const Eigen::Vector3d centroid = x.colwise().mean().transpose();
      if ((centroid - centre_mm).norm() > radius_mm) continue;
      const Eigen::Matrix3d edges = (x.bottomRows<3>().rowwise() - x.row(0)).transpose();
      volume += edges.determinant() / 6;
      ++count;
    }
    EXPECT_GT(count, 0);
    return volume / count;
  };
  const Eigen::Vector3d near(15, 0, 0), far(-15, 0, 0);
  LabelMeshOptions options = SphereOptions();
  Mesh plain, refined;
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &plain).ok());
  options.roi_centre_mm = near;
  options.roi_radius_mm = 4;
  options.roi_size_mm = 1.5;
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &refined).ok());
  const double plain_near = mean_volume_near(plain, near, 4);
  const double refined_near = mean_volume_near(refined, near, 4);
  const double plain_far = mean_volume_near(plain, far, 4);
  const double refined_far = mean_volume_near(refined, far, 4);
  std::printf(
      "region of interest (r = 4 mm, 1.5 mm elements): %d tetrahedra against %d; mean volume "
      "there %.3f mm^3 against %.3f, on the far side %.3f against %.3f\n",
      refined.num_elements(), plain.num_elements(), refined_near, plain_near, refined_far,
      plain_far);
  // Halving the size divides the volume by about 8; ask for 3.
  EXPECT_LT(refined_near, plain_near / 3);
  EXPECT_NEAR(refined_far, plain_far, 0.35 * plain_far);
  EXPECT_GT(refined.num_elements(), plain.num_elements());
}

// A cell bound on the core only: its tetrahedra shrink (about 8 times
// fewer per volume at half the size), the shell's stay as they were away
// from it.
TEST(LabelMesherTest, RegionCellSizeBoundsOnlyItsRegion) {
  const auto mean_volume = [](const Mesh& mesh, int region) {
    double volume = 0;
    int count = 0;
    for (int e = 0; e < mesh.num_elements(); ++e) {
      if (mesh.element_region[e] != region) continue;
      const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e) * 1e3;  // mm
      const Eigen::Vector3d centroid = x.colwise().mean().transpose();
      if (region == 0 && centroid.norm() < 15) continue;  // the shell away from the core
      const Eigen::Matrix3d edges = (x.bottomRows<3>().rowwise() - x.row(0)).transpose();
      volume += edges.determinant() / 6;
      ++count;
    }
    EXPECT_GT(count, 0);
    return volume / count;
  };
  LabelMeshOptions options = SphereOptions();
  Mesh plain, refined;
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &plain).ok());
  options.region_cell_size_mm = {0, 1.5};
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, options, &refined).ok());
  std::printf(
      "core cells at most 1.5 mm: mean core tetrahedron %.3f mm^3 against %.3f, shell %.3f "
      "against %.3f\n",
      mean_volume(refined, 1), mean_volume(plain, 1), mean_volume(refined, 0),
      mean_volume(plain, 0));
  EXPECT_LT(mean_volume(refined, 1), mean_volume(plain, 1) / 3);
  EXPECT_NEAR(mean_volume(refined, 0), mean_volume(plain, 0), 0.25 * mean_volume(plain, 0));
}

TEST(LabelMesherTest, EmptyBodyAndUnnamedLabelAreReported) {
  Mesh mesh;
  const Status empty =
      MeshLabels([](const Eigen::Vector3d&) { return 0; }, kNames, SphereOptions(), &mesh);
  EXPECT_EQ(empty.code(), Status::Code::kFailedPrecondition);
  EXPECT_NE(empty.message().find("no region found inside the box"), std::string::npos)
      << empty.message();

  const Status unnamed = MeshLabels(TwoSpheres, {"shell"}, SphereOptions(), &mesh);
  EXPECT_EQ(unnamed.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(unnamed.field(), "region_names");
  EXPECT_NE(unnamed.message().find("label 2"), std::string::npos) << unnamed.message();
}

// MakeQuadratic with the spheres as projection: the mid-edge nodes of the
// surface go onto r = 20 mm, those of the interface onto r = 10 mm, and the
// curved mesh's volumes come closer to the spheres'.
TEST(LabelMesherTest, QuadraticUpgradeProjectsMidEdgeNodesOntoTheSpheres) {
  Mesh linear;
  ASSERT_TRUE(MeshLabels(TwoSpheres, kNames, SphereOptions(), &linear).ok());
  const Mesh quadratic =
      MakeQuadratic(linear, [](const Eigen::Vector3d& x, const std::string& set) {
        // A region's whole surface is made of the other two; left to them.
        if (set.rfind("surface:", 0) == 0) return x;
        const double r = set == "surface" ? kShellRadius : kCoreRadius;
        return Eigen::Vector3d(x.normalized() * r * 1e-3);
      });
  ASSERT_TRUE(quadratic.quadratic());
  int midside = 0;
  for (int n : quadratic.face_sets.at("surface").nodes) {
    if (n < linear.num_nodes()) continue;
    ++midside;
    EXPECT_NEAR(quadratic.nodes.row(n).norm(), kShellRadius * 1e-3, 1e-12);  // 1e-9 mm
  }
  EXPECT_GT(midside, 0);
  for (int n : quadratic.face_sets.at("interface:shell|core").nodes) {
    if (n >= linear.num_nodes()) {
      EXPECT_NEAR(quadratic.nodes.row(n).norm(), kCoreRadius * 1e-3, 1e-12);
    }
  }
  const QualitySummary straight = Summarise(linear);
  const QualitySummary curved = Summarise(quadratic);
  EXPECT_TRUE(std::isfinite(curved.overall.max_jacobian_ratio)) << "an element inverted";
  EXPECT_LT(curved.overall.max_jacobian_ratio, 40) << "the thesis's limit";
  const double exact[2] = {SphereVolume(kShellRadius) - SphereVolume(kCoreRadius),
                           SphereVolume(kCoreRadius)};
  for (int r = 0; r < 2; ++r) {
    const double before = std::abs(straight.regions[r].volume * 1e9 / exact[r] - 1);
    const double after = std::abs(curved.regions[r].volume * 1e9 / exact[r] - 1);
    EXPECT_LT(after, before) << kNames[r];
    std::printf("%s: volume error %.3f %% linear, %.4f %% quadratic\n", kNames[r].c_str(),
                100 * before, 100 * after);
  }
  std::printf("quadratic: %d nodes, max Jacobian ratio %.3f\n", quadratic.num_nodes(),
              curved.overall.max_jacobian_ratio);
}

}  // namespace
}  // namespace pba
