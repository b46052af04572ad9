// Uniaxial stress in a bar: linear tetrahedra reproduce a linear displacement
// field exactly, so sigma_zz = E eps, the lateral strains are -nu eps and the
// end reaction is E eps A to rounding error, on any mesh.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "pba/solve.h"

namespace pba {
namespace {

constexpr double kE = 3000.0;  // Pa
constexpr double kNu = 0.45;
constexpr double kDisplacement = -0.2;  // mm, on a 20 mm bar: eps = -1 %
// Exact in exact arithmetic; the bound allows for the rounding of a sparse
// direct solve of a few thousand unknowns.
constexpr double kRelTol = 1e-8;

BoundaryConditionSpec Hold(const std::string& set, int component, double value) {
  BoundaryConditionSpec bc;
  bc.set = set;
  bc.kind = BoundaryConditionSpec::Kind::kDisplacement;
  bc.displacement_mm[component] = value;
  return bc;
}

SceneSpec BoxBar(AnalysisSpec::LinearSolver solver) {
  SceneSpec s;
  s.name = "uniaxial-bar";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {10, 10, 20};
  s.mesh.element_size_mm = 2.5;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {kE, kNu};
  // Rollers on three symmetry planes, the top face pulled along z.
  s.boundary_conditions = {Hold("bottom", 2, 0), Hold("x_min", 0, 0), Hold("y_min", 1, 0),
                           Hold("top", 2, kDisplacement)};
  s.outputs.reaction_sets = {"top", "bottom"};
  s.analysis.linear_solver = solver;
  return s;
}

void ExpectUniaxial(const Solution& solution, double length_mm, double area_mm2) {
  const double eps = kDisplacement / length_mm;
  const double sigma = kE * eps;
  const std::size_t elements = solution.von_mises_pa.size();
  ASSERT_GT(elements, 0u);
  for (std::size_t e = 0; e < elements; ++e) {
    const double* s = &solution.stress_pa[6 * e];
    const double* strain = &solution.strain[6 * e];
    ASSERT_NEAR(s[2], sigma, kRelTol * std::abs(sigma)) << "element " << e;
    for (int c : {0, 1, 3, 4, 5})
      ASSERT_NEAR(s[c], 0.0, kRelTol * std::abs(sigma)) << "element " << e;
    ASSERT_NEAR(strain[0], -kNu * eps, kRelTol * std::abs(eps));
    ASSERT_NEAR(strain[1], -kNu * eps, kRelTol * std::abs(eps));
    ASSERT_NEAR(solution.von_mises_pa[e], std::abs(sigma), kRelTol * std::abs(sigma));
  }
  const double force = sigma * area_mm2 * 1e-6;  // N
  ASSERT_EQ(solution.summary.reactions.size(), 2u);
  EXPECT_EQ(solution.summary.reactions[0].set, "top");
  EXPECT_NEAR(solution.summary.reactions[0].force_n[2], force, kRelTol * std::abs(force));
  EXPECT_NEAR(solution.summary.reactions[1].force_n[2], -force, kRelTol * std::abs(force));
  // Strain energy of a uniform field: sigma eps V / 2.
  const double volume = area_mm2 * length_mm * 1e-9;
  EXPECT_NEAR(solution.summary.strain_energy_j, 0.5 * sigma * eps * volume,
              1e-6 * std::abs(sigma * eps * volume));
  // A uniform stress is recovered exactly, so the estimated error vanishes.
  EXPECT_TRUE(solution.summary.error.estimated);
  EXPECT_LT(solution.summary.error.relative_error, 1e-6);
  EXPECT_LT(solution.summary.relative_residual, 1e-10);
}

TEST(UniaxialBarTest, BoxWithCholmodIsExact) {
  Solution solution;
  const Status status =
      SolveScene(BoxBar(AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &solution);
  ASSERT_TRUE(status.ok()) << status.ToString();
  ExpectUniaxial(solution, 20, 100);
  EXPECT_EQ(solution.summary.linear_solver, "CHOLMOD supernodal Cholesky");
}

TEST(UniaxialBarTest, EigenFallbackAgreesWithCholmod) {
  Solution cholmod, ldlt;
  ASSERT_TRUE(
      SolveScene(BoxBar(AnalysisSpec::LinearSolver::kCholmod), SolveOptions(), &cholmod).ok());
  ASSERT_TRUE(
      SolveScene(BoxBar(AnalysisSpec::LinearSolver::kEigenLdlt), SolveOptions(), &ldlt).ok());
  ExpectUniaxial(ldlt, 20, 100);
  ASSERT_EQ(cholmod.displacement_mm.size(), ldlt.displacement_mm.size());
  for (std::size_t i = 0; i < ldlt.displacement_mm.size(); ++i) {
    ASSERT_NEAR(cholmod.displacement_mm[i], ldlt.displacement_mm[i], 1e-10);
  }
}

TEST(CompressedCylinderTest, ReactionsBalanceAndErrorFallsWithRefinement) {
  // Bottom fixed, top pressed: no closed form (the fixed ends restrain the
  // lateral bulge), but the top and bottom reactions must balance, and the
  // estimated error must fall as the mesh is refined.
  double previous = INFINITY;
  for (double h : {4.0, 2.0}) {
    SceneSpec s;
    s.geometry.kind = GeometrySpec::Kind::kCylinder;
    s.geometry.cylinder = {10, 20};
    s.mesh.element_size_mm = h;
    s.material.kind = MaterialSpec::Kind::kLinearElastic;
    s.material.linear_elastic = {kE, kNu};
    BoundaryConditionSpec bottom{"bottom", BoundaryConditionSpec::Kind::kFixed, {}};
    s.boundary_conditions = {bottom, Hold("top", 2, -1.0)};
    Solution solution;
    const Status status = SolveScene(s, SolveOptions(), &solution);
    ASSERT_TRUE(status.ok()) << status.ToString();
    ASSERT_EQ(solution.summary.reactions.size(), 2u);
    // Reactions come in the order of the boundary conditions: bottom, top.
    ASSERT_EQ(solution.summary.reactions[1].set, "top");
    const auto& base = solution.summary.reactions[0].force_n;
    const auto& top = solution.summary.reactions[1].force_n;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(top[c] + base[c], 0.0, 1e-9 * std::abs(top[2])) << c;
    // Stiffer than the uniaxial bar (E A eps) because the ends cannot spread.
    const double uniaxial = kE * (-1.0 / 20) * M_PI * 100e-6;
    EXPECT_LT(top[2], uniaxial);
    const double eta = solution.summary.error.relative_error;
    EXPECT_GT(eta, 0.0);
    EXPECT_LT(eta, previous) << "h = " << h;
    previous = eta;
  }
}

TEST(SolveSceneTest, ProgressIsMonotoneAndEndsNearOne) {
  std::vector<ProgressEvent> events;
  SolveOptions options;
  options.progress = [&](const ProgressEvent& e) { events.push_back(e); };
  Solution solution;
  ASSERT_TRUE(SolveScene(BoxBar(AnalysisSpec::LinearSolver::kCholmod), options, &solution).ok());
  ASSERT_GE(events.size(), 5u);
  for (std::size_t i = 1; i < events.size(); ++i)
    EXPECT_GE(events[i].fraction, events[i - 1].fraction);
  EXPECT_GE(events.back().fraction, 0.9);
  EXPECT_EQ(events.front().phase, "mesh");
  // Every phase is timed.
  std::vector<std::string> phases;
  for (const auto& p : solution.summary.phases) phases.push_back(p.phase);
  EXPECT_EQ(phases, (std::vector<std::string>{"mesh", "assemble", "factorize", "solve", "recover",
                                              "estimate"}));
}

TEST(SolveSceneTest, CancelFlagStopsTheSolve) {
  std::atomic<bool> cancel{true};
  SolveOptions options;
  options.cancel = &cancel;
  Solution solution;
  EXPECT_EQ(SolveScene(BoxBar(AnalysisSpec::LinearSolver::kCholmod), options, &solution).code(),
            Status::Code::kCancelled);
}

}  // namespace
}  // namespace pba
