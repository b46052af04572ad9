// Observed convergence order on a manufactured solution (VALIDATION.md,
// "Convergence orders"): small-strain elasticity on a cube with the smooth
// displacement
//   u_i(X) = A_i sin(k X + p_i1) sin(k Y + p_i2) sin(k Z + p_i3),
// its body force b = -div sigma(u) = -(lambda + mu) grad(div u) - mu lap(u)
// (lap u_i = -3 k^2 u_i) applied through ExternalLoads, u prescribed on the
// whole boundary. The L2 norm of u_h - u falls as h^2 for linear elements
// (TET4, HEX8) and h^3 for quadratic ones (TET10); the observed order on
// the two finest meshes must be within 0.2 of that.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "assembly/assembler.h"
#include "assembly/external_loads.h"
#include "fem/hex8.h"
#include "fem/tet10.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

constexpr double kL = 0.01;  // cube edge [m]
constexpr double kE = 3000, kNu = 0.3;

struct Manufactured {
  double k = 2.3 / kL;  // not a multiple of pi / L: no symmetry helps
  double amplitude[3] = {1e-4, -0.7e-4, 0.5e-4};
  double phase[3][3] = {{0.3, 1.1, 0.7}, {0.9, 0.2, 1.4}, {1.2, 0.6, 0.1}};

  Eigen::Vector3d U(const Eigen::Vector3d& x) const {
    Eigen::Vector3d u;
    for (int i = 0; i < 3; ++i) {
      u(i) = amplitude[i];
      for (int j = 0; j < 3; ++j) u(i) *= std::sin(k * x(j) + phase[i][j]);
    }
    return u;
  }
  // d2 u_i / dX_j dX_l.
  double Second(int i, int j, int l, const Eigen::Vector3d& x) const {
    double v = amplitude[i] * k * k;
    for (int m = 0; m < 3; ++m) {
      const double a = k * x(m) + phase[i][m];
      const int order = (m == j) + (m == l);
      v *= order == 0 ? std::sin(a) : order == 1 ? std::cos(a) : -std::sin(a);
    }
    return v;
  }
  Eigen::Vector3d BodyForce(const Eigen::Vector3d& x) const {
    const double lambda = kE * kNu / ((1 + kNu) * (1 - 2 * kNu)), mu = kE / (2 * (1 + kNu));
    Eigen::Vector3d b;
    for (int j = 0; j < 3; ++j) {
      double grad_div = 0, laplacian = 0;
      for (int i = 0; i < 3; ++i) grad_div += Second(i, i, j, x);
      for (int m = 0; m < 3; ++m) laplacian += Second(j, m, m, x);
      b(j) = -(lambda + mu) * grad_div - mu * laplacian;
    }
    return b;
  }
};

enum class Element { kTet4, kTet10, kHex8 };

Mesh Cube(Element element, int cells) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {kL * 1e3, kL * 1e3, kL * 1e3};
  MeshSpec options;
  options.element_size_mm = kL * 1e3 / cells;
  if (element == Element::kHex8) options.element = ElementType::kHex8;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  return element == Element::kTet10 ? MakeQuadratic(mesh) : mesh;
}

// || u_h - u ||_L2 / || u ||_L2 after a solve on `cells` per edge.
double RelativeL2Error(Element element, int cells, const Manufactured& m) {
  const Mesh mesh = Cube(element, cells);
  DofMap dofs(mesh.num_nodes());
  for (const auto& [name, set] : mesh.face_sets) {
    for (int n : set.nodes) {
      const Eigen::Vector3d u = m.U(mesh.nodes.row(n).transpose());
      for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, u(c));
    }
  }
  dofs.Finalize();
  const ElasticityField d =
      ElasticityField::Uniform(IsotropicElasticity(kE, kNu), mesh.num_elements());
  const auto colours = ColourElements(mesh);
  const auto keep_going = [](double) { return true; };
  LinearSystem system;
  const Status assembled =
      element == Element::kTet10
          ? AssembleLinearSystemTet10(mesh, d, dofs, colours, keep_going, &system, ThreadContext())
      : element == Element::kHex8
          ? AssembleLinearSystemHex8(mesh, d, dofs, colours, keep_going, &system, ThreadContext())
          : AssembleLinearSystem(mesh, d, dofs, colours, keep_going, &system, ThreadContext());
  EXPECT_TRUE(assembled.ok()) << assembled.ToString();
  ExternalLoads loads(mesh);
  loads.AddBodyForceField([&](const Eigen::Vector3d& x) { return m.BodyForce(x); });
  const Eigen::VectorXd f = loads.dead_force();
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if (dofs.free_index(dof) >= 0) system.rhs(dofs.free_index(dof)) += f(dof);
  }
  const auto solver = CreateCholmodSolver(ThreadContext());
  Eigen::VectorXd u_free;
  EXPECT_TRUE(solver->Factorize(system.k).ok());
  EXPECT_TRUE(solver->Solve(system.rhs, &u_free).ok());
  Eigen::VectorXd u(dofs.num_dofs());
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    u(dof) = dofs.prescribed(dof) ? dofs.prescribed_value(dof) : u_free(dofs.free_index(dof));
  }

  // The error integrated with a rule of degree 5 (14 points; 3 x 3 x 3 Gauss).
  double error2 = 0, norm2 = 0;
  const auto add = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& uh, double dv) {
    const Eigen::Vector3d exact = m.U(x);
    error2 += dv * (uh - exact).squaredNorm();
    norm2 += dv * exact.squaredNorm();
  };
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (element == Element::kHex8) {
      const Hex8Nodes x = HexCorners(mesh, e);
      const double g[3] = {-std::sqrt(0.6), 0, std::sqrt(0.6)}, w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d xi(g[i], g[j], g[k]);
            const Hex8Vector n = Hex8ShapeFunctions(xi);
            Eigen::Vector3d uh = Eigen::Vector3d::Zero();
            for (int a = 0; a < 8; ++a) uh += n(a) * u.segment<3>(3 * mesh.hexes[e][a]);
            const double det = (x.transpose() * Hex8NaturalGradients(xi)).determinant();
            add(x.transpose() * n, uh, w[i] * w[j] * w[k] * std::abs(det));
          }
        }
      }
      continue;
    }
    if (element == Element::kTet10) {
      const Tet10Nodes x = Tet10Coordinates(mesh, e);
      const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
      for (const QuadraturePoint& q : Tet10MassRule()) {
        const Tet10Vector n = Tet10ShapeFunctions(q.xi);
        Eigen::Vector3d uh = Eigen::Vector3d::Zero();
        for (int a = 0; a < 10; ++a) uh += n(a) * u.segment<3>(3 * nodes[a]);
        const double det = (x.transpose() * Tet10NaturalGradients(q.xi)).determinant();
        add(x.transpose() * n, uh, q.weight * std::abs(det));
      }
      continue;
    }
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
    const double volume = std::abs(ComputeTet4Geometry(x).volume);
    for (const QuadraturePoint& q : Tet10MassRule()) {
      const Eigen::Vector4d n(1 - q.xi.sum(), q.xi.x(), q.xi.y(), q.xi.z());
      Eigen::Vector3d uh = Eigen::Vector3d::Zero();
      for (int a = 0; a < 4; ++a) uh += n(a) * u.segment<3>(3 * mesh.tets[e][a]);
      add(x.transpose() * n, uh, q.weight * 6 * volume);
    }
  }
  return std::sqrt(error2 / norm2);
}

struct OrderCase {
  std::string name;
  Element element;
  double expected_order;
  std::array<int, 3> cells;
};

class ConvergenceOrder : public ::testing::TestWithParam<OrderCase> {};

TEST_P(ConvergenceOrder, ObservedL2OrderMatchesTheElement) {
  const OrderCase& c = GetParam();
  const Manufactured m;
  double errors[3];
  for (int i = 0; i < 3; ++i) errors[i] = RelativeL2Error(c.element, c.cells[i], m);
  const double coarse_order = std::log(errors[0] / errors[1]) / std::log(2.0);
  const double order = std::log(errors[1] / errors[2]) / std::log(2.0);
  std::printf(
      "%s: relative L2 error %.3e, %.3e, %.3e on %d, %d, %d cells per edge; observed order "
      "%.2f, then %.2f\n",
      c.name.c_str(), errors[0], errors[1], errors[2], c.cells[0], c.cells[1], c.cells[2],
      coarse_order, order);
  EXPECT_NEAR(order, c.expected_order, 0.2);
}

INSTANTIATE_TEST_SUITE_P(Elements, ConvergenceOrder,
                         ::testing::Values(OrderCase{"TET4", Element::kTet4, 2, {4, 8, 16}},
                                           OrderCase{"TET10", Element::kTet10, 3, {2, 4, 8}},
                                           OrderCase{"HEX8", Element::kHex8, 2, {4, 8, 16}}),
                         [](const ::testing::TestParamInfo<OrderCase>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace pba
