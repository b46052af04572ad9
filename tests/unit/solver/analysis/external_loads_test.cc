// External loads: tractions and body forces lump to the exact resultants,
// pressure faces out of the body whatever the triangle's numbering, and the
// follower pressure's load stiffness is the derivative of its force (on a
// closed surface, where that derivative is symmetric).
#include "analysis/external_loads.h"

#include <gtest/gtest.h>

#include <random>

#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

Mesh Box(double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 20, 30};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

Eigen::Vector3d Resultant(const Eigen::VectorXd& f) {
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int a = 0; a < f.size() / 3; ++a) total += f.segment<3>(3 * a);
  return total;
}

// Every face set of the box together: its closed surface.
FaceSet WholeSurface(const Mesh& mesh) {
  FaceSet all;
  for (const auto& [name, set] : mesh.face_sets) {
    all.triangles.insert(all.triangles.end(), set.triangles.begin(), set.triangles.end());
  }
  return all;
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
  // Rotate the body by 90 degrees about x: y -> z, z -> -y.
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    u.segment<3>(3 * i) = Eigen::Vector3d(x.x(), -x.z(), x.y()) - x;
  }
  const Eigen::Vector3d total = Resultant(loads.Force(u));
  EXPECT_NEAR(total.y(), 1000 * 2e-4, 1e-12);  // the top now faces -y
  EXPECT_NEAR(total.z(), 0, 1e-12);
}

TEST(ExternalLoads, LoadStiffnessIsTheForceDerivativeOnAClosedSurface) {
  const Mesh mesh = Box(10);
  ExternalLoads loads(mesh);
  loads.AddPressure(WholeSurface(mesh), 2500, true);
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

}  // namespace
}  // namespace pba
