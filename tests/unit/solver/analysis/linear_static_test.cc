// LINEAR_STATIC with an orthotropic material: a cube on rollers pulled along
// one axis is in uniaxial stress when that axis is a material direction i,
// so sigma / eps = E_i, the lateral strains are -nu_ij eps and the reaction
// is E_i eps A, exactly (linear tetrahedra reproduce the linear field). Run
// with the material frame along x, y, z, permuted, and turned about z.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba {
namespace {

using testing::Condition;

constexpr double kEdgeMm = 10;
constexpr double kPullMm = 0.1;   // eps = 1 %
constexpr double kRelTol = 1e-8;  // exact up to the rounding of a direct solve

OrthotropicElasticParams Sample() {
  return {6000, 3000, 1500, 0.3, 0.35, 0.4, 1500, 900, 600, {1, 0, 0}, {0, 1, 0}};
}

// nu_ij for any i != j (0-based), from nu_ji = nu_ij E_j / E_i.
double Nu(const OrthotropicElasticParams& p, int i, int j) {
  const double e[3] = {p.e1_pa, p.e2_pa, p.e3_pa};
  const double upper[3][3] = {{0, p.nu12, p.nu13}, {0, 0, p.nu23}, {0, 0, 0}};
  return i < j ? upper[i][j] : upper[j][i] * e[i] / e[j];
}

// A cube on rollers at x = 0, y = 0, z = 0, its far face normal to
// `direction` pulled by kPullMm along it.
SceneSpec PulledCube(const OrthotropicElasticParams& material, int direction) {
  using K = BoundaryConditionSpec::Kind;
  static const char* kFar[3] = {"x_max", "y_max", "top"};
  SceneSpec s;
  s.name = "orthotropic-cube";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {kEdgeMm, kEdgeMm, kEdgeMm};
  s.mesh.element_size_mm = 2.5;
  s.material.kind = MaterialSpec::Kind::kOrthotropicElastic;
  s.material.orthotropic_elastic = material;
  std::array<std::optional<double>, 3> pull;
  pull[direction] = kPullMm;
  s.boundary_conditions = {Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
                           Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
                           Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
                           Condition(kFar[direction], K::kDisplacement, pull)};
  s.outputs.reaction_sets = {kFar[direction]};
  return s;
}

// Solves the cube pulled along global `direction` and checks uniaxial stress
// E eps there and the lateral strains -nu[c] eps in the other directions c.
void ExpectUniaxial(const OrthotropicElasticParams& material, int direction, double e,
                    const std::array<double, 3>& nu) {
  Solution solution;
  const Status status = SolveScene(PulledCube(material, direction), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const double eps = kPullMm / kEdgeMm;
  const double sigma = e * eps;
  ASSERT_GT(solution.von_mises_pa.size(), 0u);
  for (std::size_t el = 0; el < solution.von_mises_pa.size(); ++el) {
    const double* stress = &solution.stress_pa[6 * el];
    const double* strain = &solution.strain[6 * el];
    for (int c = 0; c < 6; ++c) {
      ASSERT_NEAR(stress[c], c == direction ? sigma : 0.0, kRelTol * sigma)
          << "element " << el << " stress component " << c;
    }
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(strain[c], c == direction ? eps : -nu[c] * eps, kRelTol * eps)
          << "element " << el << " strain component " << c;
    }
    for (int c = 3; c < 6; ++c) ASSERT_NEAR(strain[c], 0.0, kRelTol * eps);
  }
  const double force = sigma * kEdgeMm * kEdgeMm * 1e-6;  // N
  ASSERT_EQ(solution.summary.reactions.size(), 1u);
  EXPECT_NEAR(solution.summary.reactions[0].force_n[direction], force, kRelTol * force);
  const double volume = std::pow(kEdgeMm * 1e-3, 3);
  EXPECT_NEAR(solution.summary.strain_energy_j, 0.5 * sigma * eps * volume,
              1e-6 * sigma * eps * volume);
  // The recovered stress is uniform, so the error measured with the
  // compliance vanishes.
  EXPECT_LT(solution.summary.error.relative_error, 1e-6);
}

struct Frame {
  const char* label;
  std::array<double, 3> axis_1, axis_2;
  std::array<int, 3> material_axis;  // material direction (0-based) along x, y, z
};
void PrintTo(const Frame& f, std::ostream* os) { *os << f.label; }

class OrthotropicCubeTest : public ::testing::TestWithParam<Frame> {};

TEST_P(OrthotropicCubeTest, EachMaterialAxisGivesItsModulusAndContractions) {
  const Frame& frame = GetParam();
  OrthotropicElasticParams p = Sample();
  p.axis_1 = frame.axis_1;
  p.axis_2 = frame.axis_2;
  const double e[3] = {p.e1_pa, p.e2_pa, p.e3_pa};
  for (int direction = 0; direction < 3; ++direction) {
    SCOPED_TRACE("pulled along global axis " + std::to_string(direction));
    const int i = frame.material_axis[direction];
    std::array<double, 3> nu{};
    for (int c = 0; c < 3; ++c) {
      if (c != direction) nu[c] = Nu(p, i, frame.material_axis[c]);
    }
    ExpectUniaxial(p, direction, e[i], nu);
  }
}

INSTANTIATE_TEST_SUITE_P(Frames, OrthotropicCubeTest,
                         ::testing::Values(Frame{"global", {1, 0, 0}, {0, 1, 0}, {0, 1, 2}},
                                           // 1 = y, 2 = z, 3 = y x z = x.
                                           Frame{"cyclic", {0, 1, 0}, {0, 0, 1}, {2, 0, 1}},
                                           // 1 = -z, 2 = x, 3 = -y; unnormalised axes.
                                           Frame{"flipped", {0, 0, -3}, {2, 0, 0.5}, {1, 2, 0}}),
                         [](const ::testing::TestParamInfo<Frame>& info) {
                           return std::string(info.param.label);
                         });

TEST(OrthotropicCubeTurnedTest, PullAlongAxisThreeWithTheFrameTurnedAboutIt) {
  // With nu31 = nu32 (nu13 / E1 = nu23 / E2) the 1-2 plane contracts
  // equally in every direction, so turning the frame 30 degrees about z
  // keeps a z pull uniaxial: any error in the rotated shear coupling would
  // leave in-plane shear stress or strain behind.
  OrthotropicElasticParams p = Sample();
  p.nu13 = 0.4;
  p.nu23 = 0.2;
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  p.axis_1 = {c, s, 0};
  p.axis_2 = {-s, c, 0};
  const double nu31 = Nu(p, 2, 0);
  ASSERT_NEAR(nu31, Nu(p, 2, 1), 1e-15);
  ExpectUniaxial(p, 2, p.e3_pa, {nu31, nu31, 0});
}

}  // namespace
}  // namespace pba
