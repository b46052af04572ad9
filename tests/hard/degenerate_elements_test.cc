// Hard cases: sliver and needle elements (aspect ratio > 20). No scene field
// takes a custom mesh, so the meshes are built here at the solver level: the
// structured mesh of a box squashed into a thin layer (flat slivers) or
// stretched into a bar of thin cells (needles), and a box whose interior
// nodes are pushed almost onto a face of a neighbouring tetrahedron.
//
// Under uniform uniaxial stress (rollers on x_min, y_min, bottom; the top
// moved) every linear tetrahedron holds the exact field whatever its
// shape, so the linear and the nonlinear solves must return the exact
// homogeneous motion - or fail with a message naming the element. No NaN.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/finite_strain_model.h"
#include "analysis/newton_static.h"
#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

// Longest edge over the smallest height (3 V / largest face area).
double AspectRatio(const Eigen::Matrix<double, 4, 3>& x) {
  double longest = 0, largest_face = 0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (x.row(a) - x.row(b)).norm());
  }
  const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (const auto& f : faces) {
    const Eigen::Vector3d e1 = (x.row(f[1]) - x.row(f[0])).transpose();
    const Eigen::Vector3d e2 = (x.row(f[2]) - x.row(f[0])).transpose();
    largest_face = std::max(largest_face, 0.5 * e1.cross(e2).norm());
  }
  const Eigen::Vector3d a = (x.row(1) - x.row(0)).transpose(),
                        b = (x.row(2) - x.row(0)).transpose(),
                        c = (x.row(3) - x.row(0)).transpose();
  const double volume = a.dot(b.cross(c)) / 6;
  return longest / (3 * volume / largest_face);
}

double WorstAspect(const Mesh& mesh) {
  double worst = 0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    worst = std::max(worst, AspectRatio(TetCorners(mesh, e)));
  return worst;
}

// The structured tetrahedral mesh of a box [mm], node coordinates then
// scaled by `scale` along x, y, z.
Mesh ScaledBox(std::array<double, 3> size_mm, double element_mm, Eigen::RowVector3d scale) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = size_mm;
  MeshSpec options;
  options.element_size_mm = element_mm;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    mesh.nodes.row(i) = mesh.nodes.row(i).cwiseProduct(scale);
  return mesh;
}

// Pushes interior nodes 97 % of the way towards the centroid of the face
// opposite them in one of their tetrahedra, which flattens that one into a
// sliver; a move that would invert any element is not made.
Mesh BoxWithSlivers() {
  Mesh mesh = ScaledBox({4, 4, 4}, 1, {1, 1, 1});
  const double tol = 1e-9;
  int moved = 0;
  for (int e = 0; e < mesh.num_elements() && moved < 8; e += 37) {
    for (int corner = 0; corner < 4; ++corner) {
      const int node = mesh.tets[e][corner];
      const Eigen::RowVector3d p = mesh.nodes.row(node);
      if ((p.array() < tol).any() || (p.array() > 4e-3 - tol).any()) continue;  // boundary
      Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        if (k != corner) centroid += mesh.nodes.row(mesh.tets[e][k]) / 3;
      }
      mesh.nodes.row(node) = p + 0.97 * (centroid - p);
      bool valid = true;
      for (int f = 0; f < mesh.num_elements(); ++f) {
        valid &= ComputeTet4Geometry(TetCorners(mesh, f)).volume > 0;
      }
      if (valid) {
        ++moved;
        break;
      }
      mesh.nodes.row(node) = p;
    }
  }
  EXPECT_GT(moved, 0);
  return mesh;
}

// Rollers: x on x_min, y on y_min, z on bottom; the top moved to `top_z` [m].
DofMap Rollers(const Mesh& mesh, double top_z) {
  DofMap dofs(mesh.num_nodes());
  for (int i : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(i, 0, 0.0);
  for (int i : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(i, 1, 0.0);
  for (int i : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(i, 2, 0.0);
  for (int i : mesh.face_sets.at("top").nodes) dofs.Prescribe(i, 2, top_z);
  dofs.Finalize();
  return dofs;
}

// Largest distance of the nodes from the homogeneous motion with axial
// stretch `axial` along z and `lateral` across, over the largest motion.
double RelativeError(const Mesh& mesh, const Eigen::VectorXd& u, double lateral, double axial) {
  double error = 0, largest = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double exact = ((c == 2 ? axial : lateral) - 1) * mesh.nodes(i, c);
      if (!std::isfinite(u(3 * i + c))) return INFINITY;
      error = std::max(error, std::abs(u(3 * i + c) - exact));
      largest = std::max(largest, std::abs(exact));
    }
  }
  return error / largest;
}

struct MeshCase {
  std::string name;
  std::function<Mesh()> make;
};
void PrintTo(const MeshCase& c, std::ostream* os) { *os << c.name; }

class DegenerateElementsTest : public ::testing::TestWithParam<MeshCase> {};

// Small strain: 1 % stretch, E = 3 kPa, nu = 0.45: lateral strain -nu eps.
TEST_P(DegenerateElementsTest, LinearSolveIsExactOrNamesTheElement) {
  const Mesh mesh = GetParam().make();
  const double aspect = WorstAspect(mesh);
  EXPECT_GT(aspect, 20);
  const double height = mesh.nodes.col(2).maxCoeff(), strain = 0.01, nu = 0.45;
  const DofMap dofs = Rollers(mesh, strain * height);
  LinearSystem system;
  const Status assembled = AssembleLinearSystem(
      mesh, ElasticityField::Uniform(IsotropicElasticity(3000, nu), mesh.num_elements()), dofs,
      ColourElements(mesh), [](double) { return true; }, &system, ThreadContext());
  if (!assembled.ok()) {
    EXPECT_NE(assembled.message().find("element"), std::string::npos) << assembled.message();
    return;
  }
  const auto solver = CreateCholmodSolver(ThreadContext());
  Eigen::VectorXd free;
  Status status = solver->Factorize(system.k);
  if (status.ok()) status = solver->Solve(system.rhs, &free);
  ASSERT_TRUE(status.ok()) << status.message();
  Eigen::VectorXd u(dofs.num_dofs());
  for (int d = 0; d < dofs.num_dofs(); ++d) {
    u(d) = dofs.prescribed(d) ? dofs.prescribed_value(d) : free(dofs.free_index(d));
  }
  const double error = RelativeError(mesh, u, 1 - nu * strain, 1 + strain);
  std::printf("%s: %d elements, worst aspect ratio %.1f; linear: error %.2e of the motion\n",
              GetParam().name.c_str(), mesh.num_elements(), aspect, error);
  EXPECT_LT(error, 1e-8);
}

// Finite strain: 20 % compression, neo-Hookean mu = 1 kPa, K / mu = 100,
// plain and average-nodal-pressure tetrahedra.
TEST_P(DegenerateElementsTest, NonlinearSolveIsExactOrFailsClearly) {
  const Mesh mesh = GetParam().make();
  const double height = mesh.nodes.col(2).maxCoeff(), l = 0.8, mu = 1000, bulk = 1e5;
  // The lateral stretch of uniaxial stress (sigma_xx = 0, see
  // near_incompressibility_test.cc), by bisection.
  double lo = 1e-3, hi = 10;
  for (int i = 0; i < 200; ++i) {
    const double a = 0.5 * (lo + hi), j = a * a * l;
    (mu * std::pow(j, -5.0 / 3) * (a * a - l * l) / 3 + bulk * (j - 1) < 0 ? lo : hi) = a;
  }
  const double lateral = 0.5 * (lo + hi);
  const PolynomialMaterial material(NeoHookeanCoefficients(mu, bulk));
  const DofMap dofs = Rollers(mesh, (l - 1) * height);
  for (const bool nodal_pressure : {false, true}) {
    const auto model = nodal_pressure ? MakeAverageNodalPressureTet4Model(mesh, material)
                                      : MakeTet4Model(mesh, material);
    const auto solver = CreateCholmodSolver(ThreadContext());
    Eigen::VectorXd u = Eigen::VectorXd::Zero(dofs.num_dofs());
    NewtonReport report;
    const Status status = SolveNewtonStatic(
        *model, nullptr, dofs, NewtonOptions(), solver.get(),
        [](const NewtonProgress&) { return true; }, &u, &report);
    const char* name = nodal_pressure ? "TET4_ANP" : "TET4";
    if (!status.ok()) {
      std::printf("%s, %s: failed: %s\n", GetParam().name.c_str(), name, status.message().c_str());
      EXPECT_EQ(status.code(), Status::Code::kNumerical);
      EXPECT_NE(status.message().find("element"), std::string::npos) << status.message();
      continue;
    }
    const double error = RelativeError(mesh, u, lateral, l);
    std::printf("%s, %s: error %.2e of the motion, %d iterations\n", GetParam().name.c_str(), name,
                error, report.total_iterations);
    EXPECT_LT(error, 1e-7) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, DegenerateElementsTest,
                         ::testing::Values(
                             // 10 x 10 x 0.03 mm layer of 1 x 1 x 0.03 mm cells: flat slivers.
                             MeshCase{"flat_layer",
                                      [] {
                                        return ScaledBox({10, 10, 1}, 1, {1, 1, 0.03});
                                      }},
                             // A 10 x 0.3 x 0.3 mm bar of cells 0.03 mm across: needles along z.
                             MeshCase{"needles",
                                      [] {
                                        return ScaledBox({1, 1, 10}, 1, {0.03, 0.03, 1});
                                      }},
                             MeshCase{"moved_nodes", [] { return BoxWithSlivers(); }}),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace pba
