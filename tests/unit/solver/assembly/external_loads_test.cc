// External loads: tractions and body forces lump to the exact resultants,
// pressure faces out of the body whatever the triangle's numbering, and the
// follower pressure's load stiffness is the derivative of its force (on a
// closed surface, where that derivative is symmetric). The same on quadratic
// meshes, whose consistent loads have their own nodal pattern and whose
// curved surfaces carry a curved cavity's pressure far more exactly. And on
// hexahedral meshes, whose bilinear quads and trilinear bricks integrate
// these loads exactly on the box and the cavity's vector area exactly on
// the shell.
#include "assembly/external_loads.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

Mesh Box(double h_mm, ElementType element = ElementType::kDefault) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec m;
  m.element = element;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

Eigen::Vector3d Resultant(const Eigen::VectorXd& f) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int a = 0; a < f.size() / 3; ++a) total += f.segment<3>(3 * a);
  return total;
}

// Every face set of the box together: its closed surface (with the mid-edge
// nodes of a quadratic mesh unless `with_midside` is false).
FaceSet WholeSurface(const Mesh& mesh, bool with_midside = true) {
  FaceSet all;
  for (const auto& [name, set] : mesh.face_sets) {
    all.triangles.insert(all.triangles.end(), set.triangles.begin(), set.triangles.end());
    all.quads.insert(all.quads.end(), set.quads.begin(), set.quads.end());
    if (with_midside) {
      all.triangle_midside.insert(all.triangle_midside.end(), set.triangle_midside.begin(),
                                  set.triangle_midside.end());
    }
  }
  return all;
}

// A displacement turning the body by 90 degrees about x: y -> z, z -> -y.
Eigen::VectorXd QuarterTurnAboutX(const Mesh& mesh) {
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    u.segment<3>(3 * i) = Eigen::Vector3d(x.x(), -x.z(), x.y()) - x;
  }
  return u;
}

// Checks K_L against the central-difference derivative of the force at a
// small random displacement, and its symmetry (a closed surface).
void ExpectStiffnessIsForceDerivative(const Mesh& mesh, const ExternalLoads& loads) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> small(-5e-4, 5e-4);
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < u.size(); ++i) u(i) = small(rng);
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();  // all free
  const SparseMatrix k = loads.Stiffness(u, dofs, 1.0);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(k);
  EXPECT_LT((dense - dense.transpose()).norm(), 1e-12 * dense.norm());
  const double step = 1e-7;
  double worst = 0;
  for (int j = 0; j < u.size(); ++j) {
    Eigen::VectorXd plus = u, minus = u;
    plus(j) += step;
    minus(j) -= step;
    const Eigen::VectorXd column = -(loads.Force(plus) - loads.Force(minus)) / (2 * step);
    worst = std::max(worst, (column - dense.col(j)).norm());
  }
  EXPECT_LT(worst, 1e-6 * dense.norm());
}

TEST(ExternalLoads, TractionAndGravityResultants) {
  const Mesh mesh = Box(5);
  ExternalLoads loads(mesh);
  loads.AddTraction(mesh.face_sets.at("top"), {100, 0, -50});  // on 10 x 20 mm
  loads.AddBodyForce({0, 0, -1040 * 9.81});                    // on 10 x 20 x 30 mm
  const Eigen::Vector3d total = loads.ReferenceResultant();
  EXPECT_NEAR(total.x(), 100 * 2e-4, 1e-12);
  EXPECT_NEAR(total.y(), 0, 1e-12);
  EXPECT_NEAR(total.z(), -50 * 2e-4 - 1040 * 9.81 * 6e-6, 1e-12);
  EXPECT_FALSE(loads.follows_deformation());
}

TEST(ExternalLoads, PressurePushesIntoTheBody) {
  const Mesh mesh = Box(5);
  for (bool follower : {false, true}) {
    ExternalLoads loads(mesh);
    loads.AddPressure(mesh.face_sets.at("top"), 1000, follower);
    loads.AddPressure(mesh.face_sets.at("x_min"), 1000, follower);
    const Eigen::Vector3d total = loads.ReferenceResultant();
    EXPECT_NEAR(total.z(), -1000 * 2e-4, 1e-12);  // top pressed down
    EXPECT_NEAR(total.x(), 1000 * 6e-4, 1e-12);   // x_min pressed towards +x
    EXPECT_NEAR(total.y(), 0, 1e-12);
    EXPECT_EQ(loads.follows_deformation(), follower);
  }
}

TEST(ExternalLoads, FollowerPressureTurnsWithTheSurface) {
  const Mesh mesh = Box(5);
  ExternalLoads loads(mesh);
  loads.AddPressure(mesh.face_sets.at("top"), 1000, true);
  const Eigen::Vector3d total = Resultant(loads.Force(QuarterTurnAboutX(mesh)));
  EXPECT_NEAR(total.y(), 1000 * 2e-4, 1e-12);  // the top now faces -y
  EXPECT_NEAR(total.z(), 0, 1e-12);
}

TEST(ExternalLoads, LoadStiffnessIsTheForceDerivativeOnAClosedSurface) {
  const Mesh mesh = Box(10);
  ExternalLoads loads(mesh);
  loads.AddPressure(WholeSurface(mesh), 2500, true);
  ExpectStiffnessIsForceDerivative(mesh, loads);
}

// One straight 10-node tetrahedron, corners (0,0,0), (2,0,0), (0,3,0),
// (0,0,4) mm (V = 4 mm^3), its bottom face (area 3 mm^2) in two face sets
// numbered either way round.
Mesh OneTet10() {
  Mesh linear;
  linear.nodes.resize(4, 3);
  linear.nodes << 0, 0, 0, 2e-3, 0, 0, 0, 3e-3, 0, 0, 0, 4e-3;
  linear.tets = {{0, 1, 2, 3}};
  linear.face_sets["up"].triangles = {{0, 1, 2}};    // normal +z: into the body
  linear.face_sets["down"].triangles = {{0, 2, 1}};  // normal -z: out of it
  for (auto& [name, set] : linear.face_sets) set.nodes = {0, 1, 2};
  return MakeQuadratic(linear);
}

TEST(ExternalLoadsQuadratic, ConsistentLoadsOfAStraightElement) {
  const Mesh mesh = OneTet10();
  const double volume = 4e-9, area = 3e-6;
  const Eigen::Vector3d b(0, 0, -1e4), t(30, -20, 10);
  ExternalLoads gravity(mesh), traction(mesh);
  gravity.AddBodyForce(b);
  traction.AddTraction(mesh.face_sets.at("down"), t);
  const std::array<int, 6>& mid = mesh.midside[0];
  for (int a = 0; a < 4; ++a) {
    EXPECT_LT((gravity.dead_force().segment<3>(3 * a) + b * volume / 20).norm(), 1e-15) << a;
    EXPECT_LT(traction.dead_force().segment<3>(3 * a).norm(), 1e-15) << a;
  }
  for (int k = 0; k < 6; ++k) {
    EXPECT_LT((gravity.dead_force().segment<3>(3 * mid[k]) - b * volume / 5).norm(), 1e-15) << k;
    // Edges 0..2 of the C3D10 order bound the bottom face; 3..5 rise from it.
    const Eigen::Vector3d expected =
        k < 3 ? Eigen::Vector3d(t * area / 3) : Eigen::Vector3d::Zero();
    EXPECT_LT((traction.dead_force().segment<3>(3 * mid[k]) - expected).norm(), 1e-15) << k;
  }
}

TEST(ExternalLoadsQuadratic, PressureFacesOutWhateverTheNumbering) {
  Mesh mesh = OneTet10();
  // Bow the bottom's edge (0,1) within its plane, outwards by 0.3 mm at its
  // middle: the face gains a parabolic segment of 2/3 x 2 x 0.3 mm^2.
  mesh.nodes.row(mesh.midside[0][0]) << 1e-3, -0.3e-3, 0;
  const double area = 3e-6 + 0.4e-6;
  for (bool follower : {false, true}) {
    ExternalLoads up(mesh), down(mesh);
    up.AddPressure(mesh.face_sets.at("up"), 1000, follower);
    down.AddPressure(mesh.face_sets.at("down"), 1000, follower);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
    // Node by node the same: the swap of two corners carried the mid-edge
    // nodes along (else the curved edge would be misplaced).
    EXPECT_LT((up.Force(zero) - down.Force(zero)).norm(), 1e-15);
    const Eigen::Vector3d total = up.ReferenceResultant();
    EXPECT_NEAR(total.z(), 1000 * area, 1e-15);  // pressed up, into the body
    EXPECT_NEAR(total.x(), 0, 1e-15);
    EXPECT_NEAR(total.y(), 0, 1e-15);
  }
}

TEST(ExternalLoadsQuadratic, TractionAndGravityResultants) {
  const Mesh mesh = MakeQuadratic(Box(5));
  ExternalLoads loads(mesh);
  loads.AddTraction(mesh.face_sets.at("top"), {100, 0, -50});  // on 10 x 20 mm
  loads.AddBodyForce({0, 0, -1040 * 9.81});                    // on 10 x 20 x 30 mm
  const Eigen::Vector3d total = loads.ReferenceResultant();
  EXPECT_NEAR(total.x(), 100 * 2e-4, 1e-12);
  EXPECT_NEAR(total.y(), 0, 1e-12);
  EXPECT_NEAR(total.z(), -50 * 2e-4 - 1040 * 9.81 * 6e-6, 1e-12);
  EXPECT_FALSE(loads.follows_deformation());
}

TEST(ExternalLoadsQuadratic, FlatTrianglesLoadOnlyTheirMidEdgeNodes) {
  const Mesh mesh = MakeQuadratic(Box(5));
  const FaceSet& top = mesh.face_sets.at("top");
  const Eigen::Vector3d t(100, 0, -50);
  ExternalLoads loads(mesh);
  loads.AddTraction(top, t);
  // Each triangle gives t A/3 to its mid-edge nodes and nothing to corners.
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  for (std::size_t i = 0; i < top.triangles.size(); ++i) {
    const auto& c = top.triangles[i];
    const Eigen::Vector3d x0 = mesh.nodes.row(c[0]).transpose();
    const double area =
        0.5 *
        (mesh.nodes.row(c[1]).transpose() - x0).cross(mesh.nodes.row(c[2]).transpose() - x0).norm();
    for (int m : top.triangle_midside[i]) expected.segment<3>(3 * m) += t * area / 3;
  }
  EXPECT_LT((loads.dead_force() - expected).norm(), 1e-12 * expected.norm());
}

TEST(ExternalLoadsQuadratic, PressurePushesIntoTheBody) {
  const Mesh mesh = MakeQuadratic(Box(5));
  for (bool follower : {false, true}) {
    ExternalLoads loads(mesh);
    loads.AddPressure(mesh.face_sets.at("top"), 1000, follower);
    loads.AddPressure(mesh.face_sets.at("x_min"), 1000, follower);
    const Eigen::Vector3d total = loads.ReferenceResultant();
    EXPECT_NEAR(total.z(), -1000 * 2e-4, 1e-12);  // top pressed down
    EXPECT_NEAR(total.x(), 1000 * 6e-4, 1e-12);   // x_min pressed towards +x
    EXPECT_NEAR(total.y(), 0, 1e-12);
    EXPECT_EQ(loads.follows_deformation(), follower);
  }
}

TEST(ExternalLoadsQuadratic, FollowerPressureTurnsWithTheSurface) {
  const Mesh mesh = MakeQuadratic(Box(5));
  ExternalLoads follower(mesh), dead(mesh);
  follower.AddPressure(mesh.face_sets.at("top"), 1000, true);
  dead.AddPressure(mesh.face_sets.at("top"), 1000, false);
  const Eigen::VectorXd u = QuarterTurnAboutX(mesh);
  const Eigen::Vector3d turned = Resultant(follower.Force(u));
  EXPECT_NEAR(turned.y(), 1000 * 2e-4, 1e-12);  // the top now faces -y
  EXPECT_NEAR(turned.z(), 0, 1e-12);
  const Eigen::Vector3d fixed = Resultant(dead.Force(u));
  EXPECT_NEAR(fixed.z(), -1000 * 2e-4, 1e-12);  // the reference normal still
  EXPECT_NEAR(fixed.y(), 0, 1e-12);
}

TEST(ExternalLoadsQuadratic, LoadStiffnessIsTheForceDerivativeOnAClosedSurface) {
  const Mesh mesh = MakeQuadratic(Box(10));
  ExternalLoads loads(mesh);
  loads.AddPressure(WholeSurface(mesh), 2500, true);
  ExpectStiffnessIsForceDerivative(mesh, loads);
}

TEST(ExternalLoadsQuadratic, MidEdgeNodesFoundFromTheElementsWhenASetLacksThem) {
  const Mesh mesh = MakeQuadratic(Box(10));
  ExternalLoads with(mesh), without(mesh);
  with.AddPressure(WholeSurface(mesh, true), 2500, true);
  without.AddPressure(WholeSurface(mesh, false), 2500, true);
  with.AddTraction(WholeSurface(mesh, true), {1, 2, 3});
  without.AddTraction(WholeSurface(mesh, false), {1, 2, 3});
  Eigen::VectorXd u = QuarterTurnAboutX(mesh);
  EXPECT_EQ(with.Force(u), without.Force(u));
}

// The octant of a shell of radii 10 and 20 mm; when quadratic, its boundary
// mid-edge nodes on the true spheres.
Mesh ShellOctant(bool quadratic, ElementType element = ElementType::kDefault) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kSphericalShell;
  g.spherical_shell.inner_radius_mm = 10;
  g.spherical_shell.outer_radius_mm = 20;
  MeshSpec m;
  m.element = element;
  m.element_size_mm = 5;
  MeshStats stats;
  const Mesh linear = BuildPrimitiveMesh(g, m, &stats);
  if (!quadratic) return linear;
  return MakeQuadratic(linear, [](const Eigen::Vector3d& x, const std::string& set) {
    if (set == "inner") return Eigen::Vector3d(10e-3 * x.normalized());
    if (set == "outer") return Eigen::Vector3d(20e-3 * x.normalized());
    return x;  // the cut planes are flat
  });
}

TEST(ExternalLoadsQuadratic, CurvedSurfacesCarryTheCavityPressure) {
  // Pressure p on the inner octant (radius a) pushes the body outwards with
  // p times the octant's projection on each coordinate plane, p pi a^2 / 4
  // per axis. The discrete surfaces differ from the sphere only along the
  // cut planes, by chords (linear) or parabolic arcs (quadratic) in place of
  // the quarter circles.
  const double p = 1000, a = 10e-3, exact = p * std::numbers::pi * a * a / 4;
  double error[2];
  for (bool quadratic : {false, true}) {
    const Mesh mesh = ShellOctant(quadratic);
    ExternalLoads loads(mesh);
    loads.AddPressure(mesh.face_sets.at("inner"), p, true);
    const Eigen::Vector3d total = loads.ReferenceResultant();
    error[quadratic] = (total - Eigen::Vector3d::Constant(exact)).cwiseAbs().maxCoeff() / exact;
  }
  // About 1.1e-2 and 1e-5 at this size: the chord's area deficit falls as
  // h^2, the parabola's as h^4.
  EXPECT_LT(error[0], 0.02);
  EXPECT_LT(error[1], 5e-5);
  EXPECT_LT(error[1], error[0] / 100);
}

TEST(ExternalLoadsQuadratic, CurvedSurfacesAndElementsCarryTheirArea) {
  // A uniform traction's resultant is t times the loaded area, here the
  // outer octant's 4 pi b^2 / 8; gravity's is b times the volume, here the
  // shell octant's 4 pi (b^3 - a^3) / 24.
  const double a = 10e-3, b = 20e-3;
  const double area = std::numbers::pi * b * b / 2;
  const double volume = std::numbers::pi * (b * b * b - a * a * a) / 6;
  double area_error[2], volume_error[2];
  for (bool quadratic : {false, true}) {
    const Mesh mesh = ShellOctant(quadratic);
    ExternalLoads traction(mesh), gravity(mesh);
    traction.AddTraction(mesh.face_sets.at("outer"), {0, 0, 1});
    gravity.AddBodyForce({0, 0, 1});
    area_error[quadratic] = std::abs(traction.ReferenceResultant().z() - area) / area;
    volume_error[quadratic] = std::abs(gravity.ReferenceResultant().z() - volume) / volume;
  }
  // About 1.5e-2 and 3e-2 linear, 6e-5 and 9e-5 quadratic.
  EXPECT_LT(area_error[1], area_error[0] / 100);
  EXPECT_LT(volume_error[1], volume_error[0] / 100);
}

Mesh HexBox(double h_mm) { return Box(h_mm, ElementType::kHex8); }

TEST(ExternalLoadsHex, TractionGravityAndPressureResultants) {
  const Mesh mesh = HexBox(5);
  ASSERT_TRUE(mesh.hexahedral());
  ExternalLoads loads(mesh);
  loads.AddTraction(mesh.face_sets.at("top"), {100, 0, -50});  // on 10 x 20 mm
  loads.AddBodyForce({0, 0, -1040 * 9.81});                    // on 10 x 20 x 30 mm
  const Eigen::Vector3d total = loads.ReferenceResultant();
  EXPECT_NEAR(total.x(), 100 * 2e-4, 1e-12);
  EXPECT_NEAR(total.y(), 0, 1e-12);
  EXPECT_NEAR(total.z(), -50 * 2e-4 - 1040 * 9.81 * 6e-6, 1e-12);
  EXPECT_FALSE(loads.follows_deformation());
  for (bool follower : {false, true}) {
    ExternalLoads pressure(mesh);
    pressure.AddPressure(mesh.face_sets.at("top"), 1000, follower);
    pressure.AddPressure(mesh.face_sets.at("x_min"), 1000, follower);
    pressure.AddPressure(mesh.face_sets.at("y_max"), 500, follower);
    const Eigen::Vector3d pushed = pressure.ReferenceResultant();
    EXPECT_NEAR(pushed.z(), -1000 * 2e-4, 1e-12);  // top pressed down
    EXPECT_NEAR(pushed.x(), 1000 * 6e-4, 1e-12);   // x_min pressed towards +x
    EXPECT_NEAR(pushed.y(), -500 * 3e-4, 1e-12);   // y_max pressed towards -y
    EXPECT_EQ(pressure.follows_deformation(), follower);
    EXPECT_FALSE(pressure.empty());
  }
}

TEST(ExternalLoadsHex, FlatQuadsAndBricksShareTheirLoadEqually) {
  // Every quad of the box a 5 mm square, every brick a 5 mm cube: a quarter
  // of t A (or -p n A) to each quad node, an eighth of b V to each brick
  // node.
  const Mesh mesh = HexBox(5);
  const FaceSet& top = mesh.face_sets.at("top");
  const Eigen::Vector3d t(100, 0, -50), b(0, 0, -1e4);
  const double p = 1000, area = 25e-6, volume = 125e-9;
  ExternalLoads traction(mesh), gravity(mesh), pressure(mesh);
  traction.AddTraction(top, t);
  gravity.AddBodyForce(b);
  pressure.AddPressure(top, p, true);
  const int n = 3 * mesh.num_nodes();
  Eigen::VectorXd expected_t = Eigen::VectorXd::Zero(n), expected_b = Eigen::VectorXd::Zero(n),
                  expected_p = Eigen::VectorXd::Zero(n);
  for (const auto& quad : top.quads) {
    for (int a : quad) {
      expected_t.segment<3>(3 * a) += t * area / 4;
      expected_p.segment<3>(3 * a) += -p * area / 4 * Eigen::Vector3d::UnitZ();
    }
  }
  for (const auto& hex : mesh.hexes) {
    for (int a : hex) expected_b.segment<3>(3 * a) += b * volume / 8;
  }
  EXPECT_LT((traction.dead_force() - expected_t).norm(), 1e-12 * expected_t.norm());
  EXPECT_LT((gravity.dead_force() - expected_b).norm(), 1e-12 * expected_b.norm());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  EXPECT_LT((pressure.Force(zero) - expected_p).norm(), 1e-12 * expected_p.norm());
}

// One brick, corners of a parallelepiped sheared along x (V = 2 x 3 x 4
// mm^3), its bottom face in two face sets numbered either way round.
Mesh OneHex() {
  Mesh mesh;
  mesh.nodes.resize(8, 3);
  mesh.nodes << 0, 0, 0, 2, 0, 0, 2, 3, 0, 0, 3, 0, 1, 0, 4, 3, 0, 4, 3, 3, 4, 1, 3, 4;
  mesh.nodes *= 1e-3;
  mesh.hexes = {{0, 1, 2, 3, 4, 5, 6, 7}};
  mesh.face_sets["up"].quads = {{0, 1, 2, 3}};    // normal +z: into the body
  mesh.face_sets["down"].quads = {{1, 0, 3, 2}};  // normal -z: out of it
  for (auto& [name, set] : mesh.face_sets) set.nodes = {0, 1, 2, 3};
  return mesh;
}

TEST(ExternalLoadsHex, PressureFacesOutWhateverTheNumbering) {
  const Mesh mesh = OneHex();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  for (bool follower : {false, true}) {
    ExternalLoads up(mesh), down(mesh);
    up.AddPressure(mesh.face_sets.at("up"), 1000, follower);
    down.AddPressure(mesh.face_sets.at("down"), 1000, follower);
    EXPECT_LT((up.Force(zero) - down.Force(zero)).norm(), 1e-15);
    const Eigen::Vector3d total = up.ReferenceResultant();
    EXPECT_NEAR(total.z(), 1000 * 6e-6, 1e-15);  // pressed up, into the body
    EXPECT_NEAR(total.x(), 0, 1e-15);
    EXPECT_NEAR(total.y(), 0, 1e-15);
  }
  // The sheared brick: still b V/8 per node, V = 24 mm^3.
  ExternalLoads gravity(mesh);
  gravity.AddBodyForce({0, 0, -1e4});
  for (int a = 0; a < 8; ++a) {
    EXPECT_NEAR(gravity.dead_force()(3 * a + 2), -1e4 * 24e-9 / 8, 1e-18) << a;
  }
}

TEST(ExternalLoadsHex, FollowerPressureTurnsWithTheSurface) {
  const Mesh mesh = HexBox(5);
  ExternalLoads follower(mesh), dead(mesh);
  follower.AddPressure(mesh.face_sets.at("top"), 1000, true);
  dead.AddPressure(mesh.face_sets.at("top"), 1000, false);
  const Eigen::VectorXd u = QuarterTurnAboutX(mesh);
  const Eigen::Vector3d turned = Resultant(follower.Force(u));
  EXPECT_NEAR(turned.y(), 1000 * 2e-4, 1e-12);  // the top now faces -y
  EXPECT_NEAR(turned.z(), 0, 1e-12);
  const Eigen::Vector3d fixed = Resultant(dead.Force(u));
  EXPECT_NEAR(fixed.z(), -1000 * 2e-4, 1e-12);  // the reference normal still
  EXPECT_NEAR(fixed.y(), 0, 1e-12);
}

TEST(ExternalLoadsHex, LoadStiffnessIsTheForceDerivativeOnAClosedSurface) {
  // The random displacement warps the quads out of their planes.
  for (double h : {10.0, 5.0}) {
    const Mesh mesh = HexBox(h);
    ExternalLoads loads(mesh);
    loads.AddPressure(WholeSurface(mesh), 2500, true);
    ExpectStiffnessIsForceDerivative(mesh, loads);
  }
}

TEST(ExternalLoadsHex, CurvedSurfaceCarriesTheCavityPressure) {
  // As for the tetrahedra: p pi a^2 / 4 per axis on the inner octant. The
  // 2 x 2 rule integrates each warped bilinear quad's vector area exactly,
  // and the quads' vector areas sum to that of the surface's boundary loop
  // (half the loop integral of x x dx), here the chords of the three
  // quarter circles: 2 n chords of pi / (4 n) each per circle, n = 3 cells
  // along a patch edge (15 mm x pi / 4 of arc over h = 5 mm), so per axis
  // p a^2 n sin(pi / (4 n)) exactly and within 1.2e-2 of the sphere's.
  const double p = 1000, a = 10e-3, exact = p * std::numbers::pi * a * a / 4;
  const int n = 3;
  const double chords = p * a * a * n * std::sin(std::numbers::pi / (4 * n));
  const Mesh mesh = ShellOctant(false, ElementType::kHex8);
  ASSERT_TRUE(mesh.hexahedral());
  for (bool follower : {false, true}) {
    ExternalLoads loads(mesh);
    loads.AddPressure(mesh.face_sets.at("inner"), p, follower);
    const Eigen::Vector3d total = loads.ReferenceResultant();
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(total(axis), chords, 1e-12 * chords) << axis;
      EXPECT_NEAR(total(axis), exact, 0.012 * exact) << axis;
    }
  }
}

}  // namespace
}  // namespace pba
