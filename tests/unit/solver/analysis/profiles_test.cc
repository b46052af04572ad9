// Line profiles: point location on structured meshes of every element
// type, exact interpolation of a linear displacement field, tensor
// components along the line, points outside the body, the summary, the
// speed on 1e5 elements, and a solved scene written to profile_<name>.csv.
#include "analysis/profiles.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pba/solve.h"

namespace pba {
namespace {
namespace fs = std::filesystem;

enum class Kind { kTet4, kTet10, kHex8 };

// A box [0, n0 h] x [0, n1 h] x [0, n2 h] [mm] of cubes: bricks, or six
// positively oriented tetrahedra per cube (around its main diagonal), the
// 10-node ones with straight edges (mid-edge nodes at the middles).
Solution BoxMesh(Kind kind, std::array<int, 3> n, double h) {
  Solution s;
  const auto id = [&](int i, int j, int k) {
    return static_cast<int64_t>((k * (n[1] + 1) + j) * (n[0] + 1) + i);
  };
  for (int k = 0; k <= n[2]; ++k) {
    for (int j = 0; j <= n[1]; ++j) {
      for (int i = 0; i <= n[0]; ++i) {
        for (double x : {i * h, j * h, k * h}) s.nodes_mm.push_back(x);
      }
    }
  }
  const auto node = [&](int64_t a) { return Eigen::Vector3d(&s.nodes_mm[3 * a]); };
  std::vector<std::array<int64_t, 4>> tets;
  for (int k = 0; k < n[2]; ++k) {
    for (int j = 0; j < n[1]; ++j) {
      for (int i = 0; i < n[0]; ++i) {
        const int64_t c[8] = {
            id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
            id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if (kind == Kind::kHex8) {
          s.tets.insert(s.tets.end(), c, c + 8);
          continue;
        }
        // Paths from corner 0 to corner 6 along the edges: x y z in each order.
        const int paths[6][2] = {{1, 2}, {1, 5}, {3, 2}, {3, 7}, {4, 5}, {4, 7}};
        for (const auto& p : paths) {
          std::array<int64_t, 4> t = {c[0], c[p[0]], c[p[1]], c[6]};
          const double volume =
              (node(t[1]) - node(t[0])).cross(node(t[2]) - node(t[0])).dot(node(t[3]) - node(t[0]));
          if (volume < 0) std::swap(t[1], t[2]);
          tets.push_back(t);
        }
      }
    }
  }
  s.nodes_per_element = kind == Kind::kHex8 ? 8 : kind == Kind::kTet10 ? 10 : 4;
  for (const auto& t : tets) {
    s.tets.insert(s.tets.end(), t.begin(), t.end());
    if (kind != Kind::kTet10) continue;
    // Mid-edge nodes of their own (not shared; the locator does not care).
    const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    for (const auto& e : edges) {
      const Eigen::Vector3d m = 0.5 * (node(t[e[0]]) + node(t[e[1]]));
      s.tets.push_back(static_cast<int64_t>(s.nodes_mm.size() / 3));
      for (int c = 0; c < 3; ++c) s.nodes_mm.push_back(m[c]);
    }
  }
  const std::size_t nodes = s.nodes_mm.size() / 3, elements = s.tets.size() / s.nodes_per_element;
  s.displacement_mm.assign(3 * nodes, 0);
  s.stress_pa.assign(6 * elements, 0);
  s.strain.assign(6 * elements, 0);
  s.von_mises_pa.assign(elements, 0);
  return s;
}

SceneSpec WithProfile(ProfileSpec profile) {
  SceneSpec scene;
  scene.outputs.profiles = {std::move(profile)};
  return scene;
}

ProfileSpec Line(const std::string& name, std::array<double, 3> from, std::array<double, 3> to,
                 int points) {
  ProfileSpec p;
  p.name = name;
  p.from_mm = from;
  p.to_mm = to;
  p.points = points;
  return p;
}

// Uniaxial stress sigma along x and its strain: the stress along any line is
// sigma t_x^2, the mean stress sigma / 3, everywhere inside; outside the
// box every value past the position is empty.
TEST(Profiles, UniaxialStressAlongTheLineEverywhereAndEmptyOutside) {
  const double sigma = 250, e = 3000, nu = 0.3;
  for (Kind kind : {Kind::kTet4, Kind::kTet10, Kind::kHex8}) {
    Solution s = BoxMesh(kind, {4, 3, 5}, 2.0);  // 8 x 6 x 10 mm
    const std::size_t ne = s.tets.size() / s.nodes_per_element;
    for (std::size_t el = 0; el < ne; ++el) {
      s.stress_pa[6 * el] = sigma;
      s.strain[6 * el] = sigma / e;
      s.strain[6 * el + 1] = s.strain[6 * el + 2] = -nu * sigma / e;
      s.von_mises_pa[el] = sigma;
    }
    // Along x through the inside, beyond both ends: x from -2 to 10 mm.
    const SceneSpec along_x = WithProfile(Line("x", {-2, 3.1, 4.7}, {10, 3.1, 4.7}, 25));
    std::vector<ProfileTable> tables;
    ASSERT_TRUE(SampleProfiles(along_x.outputs.profiles, s, &tables).ok());
    ASSERT_EQ(tables.size(), 1u);
    const ProfileTable& t = tables[0];
    ASSERT_EQ(t.columns.size(), 11u);
    EXPECT_EQ(t.columns[0], "distance_mm");
    EXPECT_EQ(t.columns[7], "stress_along_pa");
    EXPECT_EQ(t.columns[10], "strain_along");
    ASSERT_EQ(t.rows.size(), 25u);
    int inside = 0;
    for (const auto& row : t.rows) {
      const double x = row[1];
      EXPECT_NEAR(row[0], x + 2, 1e-12);
      if (x < -1e-9 || x > 8 + 1e-9) {
        for (int c = 4; c < 11; ++c) EXPECT_TRUE(std::isnan(row[c])) << x;
        continue;
      }
      ++inside;
      EXPECT_NEAR(row[7], sigma, 1e-9) << x;
      EXPECT_NEAR(row[8], sigma / 3, 1e-9);
      EXPECT_NEAR(row[9], sigma, 1e-9);
      EXPECT_NEAR(row[10], sigma / e, 1e-15);
    }
    EXPECT_EQ(inside, 17);  // x = 0, 0.5, ..., 8: the ends on the faces count
    const std::vector<ProfileSummary> summary = SummariseProfiles(tables);
    ASSERT_EQ(summary.size(), 1u);
    EXPECT_EQ(summary[0].points, 25);
    EXPECT_EQ(summary[0].inside, 17);
    EXPECT_NEAR(summary[0].max_stress_along_pa, sigma, 1e-9);

    // A diagonal in the x-y plane: sigma cos^2(45 deg), strain likewise.
    const SceneSpec diagonal = WithProfile(Line("d", {1, 1, 5}, {5, 5, 5}, 0));
    ASSERT_TRUE(SampleProfiles(diagonal.outputs.profiles, s, &tables).ok());
    ASSERT_EQ(tables[0].rows.size(), 50u);  // 0 points: 50
    for (const auto& row : tables[0].rows) {
      EXPECT_NEAR(row[7], sigma / 2, 1e-9);
      EXPECT_NEAR(row[10], 0.5 * (1 - nu) * sigma / e, 1e-15);
    }
  }
}

// A shear: t . sigma . t doubles the tensor's off-diagonal entry, the
// strain's Voigt entry is the engineering shear (twice the tensor's).
// A finite-strain solution's Euler-Almansi strain is taken over its
// Green-Lagrange one.
TEST(Profiles, ShearComponentsAndTheAlmansiStrain) {
  Solution s = BoxMesh(Kind::kTet4, {2, 2, 2}, 1.0);
  const std::size_t ne = s.tets.size() / 4;
  s.almansi_strain.assign(6 * ne, 0);
  for (std::size_t el = 0; el < ne; ++el) {
    s.stress_pa[6 * el + 5] = 100;       // sigma_xy
    s.strain[6 * el + 5] = 1.0;          // not read: the Almansi strain is there
    s.almansi_strain[6 * el + 5] = 0.2;  // gamma_xy = 2 e_xy
  }
  std::vector<ProfileTable> tables;
  ASSERT_TRUE(
      SampleProfiles(WithProfile(Line("s", {0.2, 0.2, 1}, {1.8, 1.8, 1}, 5)).outputs.profiles, s,
                     &tables)
          .ok());
  for (const auto& row : tables[0].rows) {
    EXPECT_NEAR(row[7], 100, 1e-9);    // 2 sigma_xy t_x t_y, t_x t_y = 1/2
    EXPECT_NEAR(row[8], 0, 1e-12);     // no mean stress
    EXPECT_NEAR(row[10], 0.1, 1e-12);  // gamma_xy t_x t_y
  }
}

// A point on a face shared by two elements takes the mean of their
// element fields; one inside a single element, that element's.
TEST(Profiles, APointOnASharedFaceTakesTheMeanOfItsElements) {
  Solution s = BoxMesh(Kind::kHex8, {2, 1, 1}, 1.0);  // bricks [0, 1] and [1, 2] in x
  s.stress_pa[0] = 100;
  s.stress_pa[6] = 300;
  s.von_mises_pa = {100, 300};
  std::vector<ProfileTable> tables;
  ASSERT_TRUE(
      SampleProfiles(WithProfile(Line("x", {0.5, 0.5, 0.5}, {1.5, 0.5, 0.5}, 3)).outputs.profiles,
                     s, &tables)
          .ok());
  ASSERT_EQ(tables[0].rows.size(), 3u);
  EXPECT_NEAR(tables[0].rows[0][7], 100, 1e-12);
  EXPECT_NEAR(tables[0].rows[1][7], 200, 1e-12);  // x = 1, the shared face
  EXPECT_NEAR(tables[0].rows[1][9], 200, 1e-12);
  EXPECT_NEAR(tables[0].rows[2][7], 300, 1e-12);
  const ElementLocator locator(s.nodes_mm, s.tets, 8);
  EXPECT_EQ(locator.LocateAll(Eigen::Vector3d(1, 0.5, 0.5)).size(), 2u);
  EXPECT_EQ(locator.LocateAll(Eigen::Vector3d(1, 1, 1)).size(), 2u);
  EXPECT_TRUE(locator.LocateAll(Eigen::Vector3d(2.01, 0.5, 0.5)).empty());
}

// u = A x + b lies in every element's space: interpolated exactly at any
// point, element boundaries included.
TEST(Profiles, LinearDisplacementIsInterpolatedExactly) {
  Eigen::Matrix3d a;
  a << 0.01, -0.02, 0.003, 0.005, 0.02, -0.01, -0.004, 0.006, -0.03;
  const Eigen::Vector3d b(0.1, -0.2, 0.3);
  for (Kind kind : {Kind::kTet4, Kind::kTet10, Kind::kHex8}) {
    Solution s = BoxMesh(kind, {5, 4, 3}, 1.5);
    // A brick grid sheared into parallelepipeds: the map is still affine.
    if (kind == Kind::kHex8) {
      for (std::size_t i = 0; i < s.nodes_mm.size(); i += 3)
        s.nodes_mm[i] += 0.3 * s.nodes_mm[i + 2];
    }
    for (std::size_t i = 0; i < s.nodes_mm.size() / 3; ++i) {
      const Eigen::Vector3d u = a * Eigen::Vector3d(&s.nodes_mm[3 * i]) + b;
      for (int c = 0; c < 3; ++c) s.displacement_mm[3 * i + c] = u[c];
    }
    std::vector<ProfileTable> tables;
    const SceneSpec scene = WithProfile(Line("x", {0.8, 2.9, 2.2}, {7.4, 2.9, 2.2}, 101));
    ASSERT_TRUE(SampleProfiles(scene.outputs.profiles, s, &tables).ok());
    int inside = 0;
    for (const auto& row : tables[0].rows) {
      if (std::isnan(row[4])) continue;
      ++inside;
      const Eigen::Vector3d u = a * Eigen::Vector3d(row[1], row[2], row[3]) + b;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(row[4 + c], u[c], 1e-12) << "x = " << row[1];
    }
    EXPECT_EQ(inside, 101);
  }
}

// 1e5 elements and 1000 points: well under a second (grid build included).
TEST(Profiles, FastOnAHundredThousandElements) {
  const Solution s = BoxMesh(Kind::kTet4, {26, 26, 25}, 1.0);  // 101400 tetrahedra
  ASSERT_GT(s.tets.size() / 4, 100000u);
  const auto start = std::chrono::steady_clock::now();
  std::vector<ProfileTable> tables;
  ASSERT_TRUE(SampleProfiles(WithProfile(Line("d", {0, 0, 0}, {26, 26, 25}, 1000)).outputs.profiles,
                             s, &tables)
                  .ok());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  int inside = 0;
  for (const auto& row : tables[0].rows) inside += std::isnan(row[4]) ? 0 : 1;
  std::printf("%zu elements, 1000 points: %.3f s, %d inside\n", s.tets.size() / 4, seconds, inside);
  EXPECT_EQ(inside, 1000);
  EXPECT_LT(seconds, 1.0);
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A solved bar in uniaxial compression, its profiles written beside
// result.h5: the header, one row per point, the known stress, empty cells
// outside, and the summary's line and note.
TEST(Profiles, SolvedSceneWritesProfileCsv) {
  SceneSpec scene;
  scene.name = "profile-test";
  scene.geometry.kind = GeometrySpec::Kind::kBox;
  scene.geometry.box.size_mm = {4, 4, 8};
  scene.mesh.element_size_mm = 2;
  scene.material.kind = MaterialSpec::Kind::kLinearElastic;
  scene.material.linear_elastic = {3000, 0.0};  // no lateral contraction: the bottom holds none
  BoundaryConditionSpec bottom{"bottom", BoundaryConditionSpec::Kind::kFixed, {}};
  BoundaryConditionSpec top{"top", BoundaryConditionSpec::Kind::kDisplacement, {}};
  top.displacement_mm[2] = -0.4;
  scene.boundary_conditions = {bottom, top};
  scene.outputs.profiles = {Line("axis", {2, 2, 0}, {2, 2, 8}, 5),
                            Line("beyond", {2, 2, 4}, {2, 2, 12}, 3)};
  Solution solution;
  const Status solved = SolveScene(scene, {}, &solution);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  ASSERT_EQ(solution.summary.profiles.size(), 2u);
  EXPECT_EQ(solution.summary.profiles[0].inside, 5);
  EXPECT_EQ(solution.summary.profiles[1].inside, 2);  // z = 4, 8 in; 12 out
  // E eps = 3000 x (-0.05) = -150 Pa, uniform.
  EXPECT_NEAR(solution.summary.profiles[0].max_stress_along_pa, -150, 1e-6);
  bool noted = false;
  for (const std::string& note : solution.summary.notes) {
    noted = noted || note.find("profile beyond: 1 of its 3 points lie outside") == 0;
  }
  EXPECT_TRUE(noted);

  std::string dir = (fs::temp_directory_path() / "pba-profiles.XXXXXX").string();
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  ASSERT_TRUE(WriteResultFiles(scene, &solution, dir).ok());
  const std::string axis = ReadText(fs::path(dir) / "profile_axis.csv");
  std::istringstream lines(axis);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line,
            "distance_mm,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,stress_along_pa,mean_stress_pa,"
            "von_mises_pa,strain_along");
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(std::getline(lines, line));
    double d, x, y, z, ux, uy, uz, along, mean, vm, strain;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &d, &x, &y,
                          &z, &ux, &uy, &uz, &along, &mean, &vm, &strain),
              11)
        << line;
    EXPECT_NEAR(d, 2.0 * i, 1e-12);
    EXPECT_NEAR(z, 2.0 * i, 1e-12);
    EXPECT_NEAR(uz, -0.05 * z, 1e-9);
    EXPECT_NEAR(ux, 0, 1e-9);
    EXPECT_NEAR(along, -150, 1e-6);
    EXPECT_NEAR(mean, -50, 1e-6);
    EXPECT_NEAR(vm, 150, 1e-6);
    EXPECT_NEAR(strain, -0.05, 1e-12);
  }
  EXPECT_FALSE(std::getline(lines, line));
  const std::string beyond = ReadText(fs::path(dir) / "profile_beyond.csv");
  EXPECT_NE(beyond.find("\n8,2,2,12,,,,,,,\n"), std::string::npos) << beyond;
  fs::remove_all(dir);
}

// A finite-strain bar on symmetry planes, stretched uniformly to 0.95 of
// its length along z: the strain along z is the Euler-Almansi
// (1 - 1 / lambda^2) / 2, not the Green-Lagrange (lambda^2 - 1) / 2, and the
// stress along the line the element's Cauchy sigma_zz.
TEST(Profiles, FiniteStrainGivesTheAlmansiStrainAlongTheLine) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec scene;
  scene.name = "almansi";
  scene.geometry.kind = GeometrySpec::Kind::kBox;
  scene.geometry.box.size_mm = {4, 4, 8};
  scene.mesh.element_size_mm = 2;
  scene.material.kind = MaterialSpec::Kind::kNeoHookean;
  scene.material.neo_hookean = {1000, 1e4};
  scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  BoundaryConditionSpec top{"top", K::kDisplacement, {}};
  top.displacement_mm[2] = -0.4;
  scene.boundary_conditions = {
      {"x_min", K::kSymmetry, {}}, {"y_min", K::kSymmetry, {}}, {"bottom", K::kSymmetry, {}}, top};
  scene.outputs.profiles = {Line("z", {1.3, 2.7, 0}, {1.3, 2.7, 8}, 9)};
  Solution solution;
  const Status solved = SolveScene(scene, {}, &solution);
  ASSERT_TRUE(solved.ok()) << solved.ToString();
  ASSERT_FALSE(solution.almansi_strain.empty());
  const double lambda = 0.95, almansi = 0.5 * (1 - 1 / (lambda * lambda));
  const double sigma_zz = solution.stress_pa[2];  // uniform: any element's
  ASSERT_LT(sigma_zz, 0);
  ASSERT_EQ(solution.profiles.size(), 1u);
  for (const auto& row : solution.profiles[0].rows) {
    EXPECT_NEAR(row[6], -0.05 * row[3], 1e-9);  // uz
    EXPECT_NEAR(row[10], almansi, 1e-9);
    EXPECT_NEAR(row[7], sigma_zz, 1e-6 * std::abs(sigma_zz));
  }
}

}  // namespace
}  // namespace pba
