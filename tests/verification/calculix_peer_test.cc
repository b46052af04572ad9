// Peer check: the same meshed model, exported as an Abaqus deck, solved by
// CalculiX (Debian package calculix-ccx, installed by scripts/deps.sh). Same
// mesh, same element (C3D4, or C3D10 for TET10 scenes), same constraints: the
// answers must agree to the precision CalculiX prints (7 significant digits).
// Each case prints a row of the speed-beside-error table in
// docs/validation.md.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <utility>
#include <vector>

#include "common/calculix.h"
#include "common/scene_builders.h"
#include "common/subprocess.h"
#include "pba/solve.h"

namespace pba {

// Cases print as their names in GoogleTest's and ctest's listings (found by
// argument-dependent lookup, so in SceneSpec's namespace).
void PrintTo(const SceneSpec& scene, std::ostream* os) { *os << '"' << scene.name << '"'; }

namespace {
using testing::CcxResult;
using testing::CcxRun;
using testing::CcxSetName;
using testing::FindCcx;
using testing::ParseDat;
using testing::RunCcx;
using testing::TempDir;

// CalculiX prints 7 significant digits.
constexpr double kPrintPrecision = 5e-6;
// Nonlinear steps: both Newton solvers stop at a relative residual of 1e-8,
// but CalculiX measures it against its average nodal force, a smaller scale
// than PBA's, so its answer may sit a few 1e-6 from the exact discrete one.
constexpr double kNonlinearPrecision = 2e-5;

using testing::Condition;

SceneSpec Scene(const std::string& name, GeometrySpec geometry, double h,
                std::vector<BoundaryConditionSpec> conditions) {
  SceneSpec s;
  s.name = name;
  s.geometry = geometry;
  s.mesh.element_size_mm = h;
  s.material.kind = MaterialSpec::Kind::kLinearElastic;
  s.material.linear_elastic = {3000, 0.45};
  s.boundary_conditions = std::move(conditions);
  return s;
}

GeometrySpec Box() {
  GeometrySpec box;
  box.kind = GeometrySpec::Kind::kBox;
  box.box.size_mm = {20, 20, 30};
  return box;
}

GeometrySpec Cylinder() {
  GeometrySpec cylinder;
  cylinder.kind = GeometrySpec::Kind::kCylinder;
  cylinder.cylinder = {10, 20};
  return cylinder;
}

SceneSpec NeoHookeanBlock() {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec neo =
      Scene("neo-Hookean block, bonded, pressed 20 % (nonlinear)", Box(), 2.5,
            {Condition("bottom", K::kFixed), Condition("top", K::kDisplacement, {0.0, 0.0, -6.0})});
  neo.material.kind = MaterialSpec::Kind::kNeoHookean;
  neo.material.neo_hookean = {1000, 5e4};
  neo.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  neo.mesh.element = ElementType::kTet4;  // CalculiX's C3D4 is the plain tetrahedron
  return neo;
}

// 10-node elements (C3D10): every mid-edge node is an unknown of both
// codes, compared like a corner. The pressure on x_max, held by the x_min
// rollers, checks the deck's face labels and PBA's quadratic face load
// against CalculiX's. Only x_min's reaction is compared: CalculiX prints
// a node's internal force as its RF, so on a set sharing nodes with the
// loaded face (every other side) it counts their share of the pressure
// as reaction, which PBA does not.
SceneSpec StretchedBlock10() {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec stretched10 =
      Scene("10-node block, rollers, top pulled 0.3 mm, 20 Pa on x_max", Box(), 5,
            {Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
             Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
             Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, 0.3}),
             Condition("x_max", K::kPressure)});
  stretched10.boundary_conditions.back().pressure_pa = 20;
  stretched10.outputs.reaction_sets = {"x_min"};
  stretched10.mesh.element = ElementType::kTet10;
  return stretched10;
}

// Plain tetrahedra (C3D4): finite strain, small strain, oblique orthotropy.
std::vector<SceneSpec> FourNodeCases() {
  using K = BoundaryConditionSpec::Kind;
  const GeometrySpec box = Box();
  const GeometrySpec cylinder = Cylinder();
  SceneSpec ogden =
      Scene("Ogden brain cylinder, bottom fixed, top pressed 15 % (nonlinear)", cylinder, 1.5,
            {Condition("bottom", K::kFixed),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -3.0})});
  ogden.material.kind = MaterialSpec::Kind::kOgden;
  ogden.material.ogden.terms = {{842, -4.7}};
  ogden.material.ogden.bulk_modulus_pa = 842e2;
  ogden.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  ogden.mesh.element = ElementType::kTet4;
  // CalculiX's own Newton diverges now and then from a first increment of
  // 0.2 on this model (NaN forces); 0.05 keeps it on track.
  ogden.analysis.nonlinear.increments = 20;
  // Oblique material axes (none along x, y or z) couple the stretch to shear
  // and make the field inhomogeneous, so the deck's *ORIENTATION and
  // ENGINEERING CONSTANTS must mean what PBA's frame and constants mean.
  SceneSpec orthotropic =
      Scene("orthotropic block, oblique axes, rollers, top pulled 0.3 mm", box, 2.5,
            {Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
             Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
             Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, 0.3})});
  orthotropic.material.kind = MaterialSpec::Kind::kOrthotropicElastic;
  OrthotropicElasticParams& p = orthotropic.material.orthotropic_elastic;
  p = {6000, 3000, 1500, 0.3, 0.35, 0.4, 1500, 900, 600};
  p.axis_1 = {1, 2, 0.5};
  p.axis_2 = {-1, 0.3, 2};
  return {
      NeoHookeanBlock(),
      ogden,
      Scene("block, bottom fixed, top pressed 1.5 mm", box, 2,
            {Condition("bottom", K::kFixed), Condition("top", K::kDisplacement, {0.0, 0.0, -1.5})}),
      Scene("block, rollers, top pulled 0.3 mm", box, 2.5,
            {Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
             Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
             Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, 0.3})}),
      Scene("cylinder, bottom fixed, top pressed 1 mm", cylinder, 1.5,
            {Condition("bottom", K::kFixed),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -1.0})}),
      orthotropic,
  };
}

std::vector<SceneSpec> TenNodeCases() {
  using K = BoundaryConditionSpec::Kind;
  // Inhomogeneous fields: a bonded block bulging under a pressure, whose
  // reactions sit on the set opposite the loaded face; a cylinder, whose
  // side's mid-edge nodes lie on the curved surface and must go into the
  // deck there. No pressure on a face with curved edges: CalculiX integrates
  // a C3D10 face load with 3 points, exact only on straight-edged faces,
  // where PBA's rule is exact on curved ones too.
  SceneSpec bonded10 = Scene("10-node block, bottom fixed, 50 Pa on top", Box(), 5,
                             {Condition("bottom", K::kFixed), Condition("top", K::kPressure)});
  bonded10.boundary_conditions.back().pressure_pa = 50;
  bonded10.mesh.element = ElementType::kTet10;
  SceneSpec cylinder10 =
      Scene("10-node cylinder, bottom fixed, top pressed 0.5 mm", Cylinder(), 2.5,
            {Condition("bottom", K::kFixed),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -0.5})});
  cylinder10.mesh.element = ElementType::kTet10;
  // The first case on 10-node elements (C3D10 with NLGEOM), at a coarser
  // size for the same number of nodes.
  SceneSpec neo10 = NeoHookeanBlock();
  neo10.name = "10-node neo-Hookean block, bonded, pressed 20 % (nonlinear)";
  neo10.mesh.element_size_mm = 5;
  neo10.mesh.element = ElementType::kTet10;
  return {StretchedBlock10(), neo10, bonded10, cylinder10};
}

// 8-node bricks (C3D8). CalculiX's C3D8 is fully integrated, which locks
// where PBA's mean-dilatation brick does not, so the two agree only where
// the strain is uniform: the stretched block with its pressure (face
// labels S1..S6, the quadrilateral face load) and, at finite strain, the
// same block compressed to 80 %.
std::vector<SceneSpec> BrickCases() {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec stretched8 = StretchedBlock10();
  stretched8.name = "8-node block, rollers, top pulled 0.3 mm, 20 Pa on x_max";
  stretched8.mesh.element = ElementType::kHex8;
  stretched8.mesh.element_size_mm = 2.5;
  SceneSpec compressed8 =
      Scene("8-node neo-Hookean block, rollers, top pressed 20 % (nonlinear)", Box(), 5,
            {Condition("bottom", K::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
             Condition("x_min", K::kDisplacement, {0.0, std::nullopt, std::nullopt}),
             Condition("y_min", K::kDisplacement, {std::nullopt, 0.0, std::nullopt}),
             Condition("top", K::kDisplacement, {std::nullopt, std::nullopt, -6.0})});
  compressed8.material = NeoHookeanBlock().material;
  compressed8.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  compressed8.mesh.element = ElementType::kHex8;
  // The fully integrated brick is C3D8 itself: non-uniform fields compare,
  // at small and at finite strain.
  SceneSpec bonded8 =
      Scene("8-node full-integration block, bottom fixed, top pressed 1.5 mm", Box(), 2.5,
            {Condition("bottom", K::kFixed), Condition("top", K::kDisplacement, {0.0, 0.0, -1.5})});
  bonded8.mesh.element = ElementType::kHex8Full;
  SceneSpec neo8 = NeoHookeanBlock();
  neo8.name = "8-node full-integration neo-Hookean block, bonded, pressed 20 % (nonlinear)";
  neo8.mesh.element = ElementType::kHex8Full;
  return {stretched8, compressed8, bonded8, neo8};
}

// Further into finite strain on plain tetrahedra: Mooney-Rivlin, and a
// brain-sized ellipsoid.
std::vector<SceneSpec> LargeStrainCases() {
  using K = BoundaryConditionSpec::Kind;
  // Mooney-Rivlin (*HYPERELASTIC, MOONEY-RIVLIN, the I2 term), further into
  // finite strain: the cylinder pressed 30 %. mu0 = 2 (C10 + C01) = 1 kPa,
  // brain-like; K / mu0 = 50 keeps the plain tetrahedron's locking mild and
  // CalculiX's Newton on track. The top is held sideways: left to slide, its
  // nodes' sideways motion is so soft that CalculiX accepts increments whose
  // last correction there is still a few percent of the increment (its
  // residual test passes), and it stops 3e-5 to 8e-5 from PBA's answer.
  SceneSpec mooney = Scene(
      "Mooney-Rivlin cylinder, bottom fixed, top pressed 30 % and held (nonlinear)", Cylinder(),
      1.5, {Condition("bottom", K::kFixed), Condition("top", K::kDisplacement, {0.0, 0.0, -6.0})});
  mooney.material.kind = MaterialSpec::Kind::kMooneyRivlin;
  mooney.material.mooney_rivlin = {300, 200, 5e4};
  mooney.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  mooney.mesh.element = ElementType::kTet4;
  mooney.analysis.nonlinear.increments = 10;
  // The "brain": an ellipsoid of a brain's size, its base held on a patch and
  // a patch on its crown pressed 5 mm down and held sideways (a bonded
  // punch), neo-Hookean with K / mu = 50 on plain tetrahedra.
  GeometrySpec brain;
  brain.kind = GeometrySpec::Kind::kEllipsoid;
  brain.ellipsoid.semi_axes_mm = {70, 60, 50};
  brain.patches = {PatchSpec::Ball("punch", "surface", {0, 0, 50}, 15),
                   PatchSpec::Ball("base", "surface", {0, 0, -50}, 30)};
  SceneSpec indented =
      Scene("ellipsoidal brain, base held, crown patch pressed 5 mm (nonlinear)", brain, 10,
            {Condition("base", K::kFixed), Condition("punch", K::kDisplacement, {0.0, 0.0, -5.0})});
  indented.material = mooney.material;
  indented.material.kind = MaterialSpec::Kind::kNeoHookean;
  indented.material.neo_hookean = {1000, 5e4};
  indented.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
  indented.mesh.element = ElementType::kTet4;
  return {mooney, indented};
}

// The cases in a fixed order: their index names them (case0, case1, ...).
std::vector<SceneSpec> Cases() {
  std::vector<SceneSpec> cases;
  for (std::vector<SceneSpec> (*group)() :
       {FourNodeCases, TenNodeCases, BrickCases, LargeStrainCases}) {
    for (SceneSpec& scene : group()) cases.push_back(std::move(scene));
  }
  return cases;
}

class CalculixPeerTest : public ::testing::TestWithParam<SceneSpec> {};

TEST_P(CalculixPeerTest, SameModelSameAnswer) {
  const std::string ccx = FindCcx();
  ASSERT_FALSE(ccx.empty()) << "CalculiX (ccx) not found; scripts/deps.sh installs calculix-ccx";
  const SceneSpec& scene = GetParam();
  const double precision = scene.analysis.type == AnalysisSpec::Type::kNonlinearStatic
                               ? kNonlinearPrecision
                               : kPrintPrecision;
  Solution ours;
  const Status solved = SolveScene(scene, SolveOptions(), &ours);
  ASSERT_TRUE(solved.ok()) << solved.ToString();

  TempDir dir;
  ASSERT_TRUE(ExportAbaqusInput(scene, dir.path() / "model.inp").ok());
  // One thread: with two, CalculiX sums its stiffness and forces in an
  // order that changes from run to run, and on the Ogden cylinder it now
  // and then diverged in its first increment (NaN forces, exit code 255). The speed comparison on
  // both cores is the peer benchmark's.
  const CcxRun run = RunCcx(ccx, dir.path(), "model", /*threads=*/1);
  ASSERT_EQ(run.process.exit_code, 0) << run.process.out << run.process.err;
  const CcxResult peer = ParseDat(dir.path() / "model.dat");

  // Compared against the largest reaction: a set that only rolls carries
  // rounding noise, not a force.
  double scale = 0;
  for (const Reaction& r : ours.summary.reactions) {
    for (double f : r.force_n) scale = std::max(scale, std::abs(f));
  }
  double worst_force = 0;
  for (const Reaction& r : ours.summary.reactions) {
    const auto it = peer.totals.find(CcxSetName(r.set));
    ASSERT_NE(it, peer.totals.end()) << r.set;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(r.force_n[c], it->second[c], precision * scale) << r.set << " component " << c;
      worst_force = std::max(worst_force, std::abs(r.force_n[c] - it->second[c]) / scale);
    }
  }
  const std::size_t nodes = ours.displacement_mm.size() / 3;
  ASSERT_EQ(peer.displacement.size(), nodes);
  double u_max = 0, u_diff = 0;
  for (std::size_t i = 0; i < nodes; ++i) {
    const auto& u = peer.displacement.at(static_cast<int>(i) + 1);
    for (int c = 0; c < 3; ++c) {
      u_max = std::max(u_max, std::abs(u[c]));
      u_diff = std::max(u_diff, std::abs(ours.displacement_mm[3 * i + c] * 1e-3 - u[c]));
    }
  }
  EXPECT_LT(u_diff, precision * u_max);
  std::printf("| %s | %lld | %.3e | %.3e | %.3f s | %.3f s | %.2g %% (ZZ) |\n", scene.name.c_str(),
              static_cast<long long>(ours.summary.dofs), worst_force, u_diff / u_max,
              ours.summary.wall_time_s, run.wall_seconds, 100 * ours.summary.error.relative_error);
}

INSTANTIATE_TEST_SUITE_P(Cases, CalculixPeerTest, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<SceneSpec>& info) {
                           return "case" + std::to_string(info.index);
                         });

}  // namespace
}  // namespace pba
