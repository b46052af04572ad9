// The average nodal pressure tetrahedron: its force is the derivative of its
// energy and its tangent that of its force (central differences, prescribed
// columns included), it equals the plain tetrahedron on a homogeneous
// deformation, and it does not lock where the plain one does.
#include "analysis/average_nodal_pressure_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "analysis/newton_static.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

Mesh Box(double size_mm, double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {size_mm, size_mm, size_mm};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

// A smooth, inhomogeneous displacement (J varies from element to element).
Eigen::VectorXd Smooth(const Mesh& mesh, double amplitude) {
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const double x = mesh.nodes(i, 0) / 0.01, y = mesh.nodes(i, 1) / 0.01,
                 z = mesh.nodes(i, 2) / 0.01;
    u(3 * i) = amplitude * 0.01 * (0.3 * x * y + 0.1 * std::sin(3 * z));
    u(3 * i + 1) = amplitude * 0.01 * (-0.2 * z * x + 0.15 * y * y);
    u(3 * i + 2) = amplitude * 0.01 * (-0.25 * z + 0.1 * x * y * z);
  }
  return u;
}

DofMap HoldBottom(const Mesh& mesh, double top_z_m) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  for (int n : mesh.face_sets.at("top").nodes) {
    dofs.Prescribe(n, 0, 0.0);
    dofs.Prescribe(n, 1, 0.0);
    dofs.Prescribe(n, 2, top_z_m);
  }
  dofs.Finalize();
  return dofs;
}

struct MaterialCase {
  const char* name;
  std::shared_ptr<HyperelasticMaterial> material;
};

std::vector<MaterialCase> Materials() {
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / 842e3, 0, 0};
  return {{"neo_hookean", std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e5))},
          {"ogden_brain", std::make_shared<OgdenMaterial>(brain)}};
}

TEST(AverageNodalPressure, ForceIsTheEnergyDerivative) {
  const Mesh mesh = Box(10, 5);
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = Smooth(mesh, 0.15);
    Eigen::VectorXd force;
    ASSERT_TRUE(model->InternalForce(u, &force, nullptr));
    const double h = 1e-9;  // m, against displacements of ~1e-3 m
    for (int dof = 0; dof < u.size(); dof += 5) {
      Eigen::VectorXd plus = u, minus = u;
      plus(dof) += h;
      minus(dof) -= h;
      Eigen::VectorXd unused;
      double ep = 0, em = 0;
      ASSERT_TRUE(model->InternalForce(plus, &unused, &ep));
      ASSERT_TRUE(model->InternalForce(minus, &unused, &em));
      EXPECT_NEAR(force(dof), (ep - em) / (2 * h), 1e-6 * force.cwiseAbs().maxCoeff())
          << c.name << " dof " << dof;
    }
  }
}

TEST(AverageNodalPressure, TangentIsTheForceDerivativeIncludingPrescribedColumns) {
  const Mesh mesh = Box(10, 5);
  const DofMap dofs = HoldBottom(mesh, -1e-3);
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = Smooth(mesh, 0.1);
    LinearSystem plain, lifted;
    ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    ASSERT_TRUE(model->Assemble(u, dofs, lift, &lifted).ok());
    const Eigen::MatrixXd k = Eigen::MatrixXd(plain.k);
    EXPECT_LT((k - k.transpose()).norm(), 1e-10 * k.norm()) << c.name;
    const double h = 1e-9;
    Eigen::VectorXd lift_expected = plain.rhs;
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      Eigen::VectorXd plus = u, minus = u;
      plus(dof) += h;
      minus(dof) -= h;
      Eigen::VectorXd fp, fm;
      ASSERT_TRUE(model->InternalForce(plus, &fp, nullptr));
      ASSERT_TRUE(model->InternalForce(minus, &fm, nullptr));
      const Eigen::VectorXd column = (fp - fm) / (2 * h);  // d f_int / d u_dof, every row
      Eigen::VectorXd free_column(dofs.num_free());
      for (int d = 0; d < dofs.num_dofs(); ++d) {
        if (dofs.free_index(d) >= 0) free_column(dofs.free_index(d)) = column(d);
      }
      if (dofs.free_index(dof) >= 0) {
        EXPECT_LT((k.col(dofs.free_index(dof)) - free_column).norm(), 1e-5 * k.norm())
            << c.name << " column " << dof;
      } else {
        lift_expected -= free_column * dofs.prescribed_value(dof);
      }
    }
    EXPECT_LT((lifted.rhs - lift_expected).norm(), 1e-5 * (1 + lift_expected.norm())) << c.name;
  }
}

TEST(AverageNodalPressure, HomogeneousDeformationIsThePlainTetrahedron) {
  const Mesh mesh = Box(10, 2.5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  const auto anp = MakeAverageNodalPressureTet4Model(mesh, material);
  const auto plain = MakeTet4Model(mesh, material);
  Eigen::Matrix3d grad;
  grad << -0.1, 0.05, 0.02, 0.03, 0.08, -0.04, 0.01, 0.02, 0.06;
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    u.segment<3>(3 * i) = grad * mesh.nodes.row(i).transpose();
  }
  Eigen::VectorXd fa, fp;
  double ea = 0, ep = 0;
  ASSERT_TRUE(anp->InternalForce(u, &fa, &ea));
  ASSERT_TRUE(plain->InternalForce(u, &fp, &ep));
  EXPECT_LT((fa - fp).norm(), 1e-9 * fp.norm());
  EXPECT_NEAR(ea, ep, 1e-9 * ep);
}

// Bonded compression of a nearly incompressible cube (K / mu = 1e3), 2 %:
// the plain tetrahedron locks (its coarse-mesh reaction is far too stiff),
// the average nodal pressure one is close to its own fine-mesh answer.
double BondedReaction(bool average_nodal_pressure, double h_mm) {
  const Mesh mesh = Box(10, h_mm);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  const DofMap dofs = HoldBottom(mesh, -2e-4);
  const auto model = average_nodal_pressure ? MakeAverageNodalPressureTet4Model(mesh, material)
                                            : MakeTet4Model(mesh, material);
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  Eigen::VectorXd u;
  NewtonReport report;
  const Status status = SolveNewtonStatic(
      *model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; }, &u,
      &report);
  EXPECT_TRUE(status.ok()) << status.ToString();
  std::printf("  %s h = %g mm: %zu increments, %d iterations, %d modified\n",
              average_nodal_pressure ? "ANP" : "plain", h_mm, report.increments.size(),
              report.total_iterations, report.modified_iterations);
  Eigen::VectorXd force;
  EXPECT_TRUE(model->InternalForce(u, &force, nullptr));
  double reaction = 0;
  for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
  return reaction;
}

TEST(AverageNodalPressure, DoesNotLockWhereThePlainTetrahedronDoes) {
  const double plain_coarse = BondedReaction(false, 2.5);
  const double anp_coarse = BondedReaction(true, 2.5);
  const double anp_fine = BondedReaction(true, 1.25);
  std::printf(
      "bonded cube, K/mu = 1e3, 2 %%: plain %.6g N, ANP %.6g N (h = 2.5 mm); "
      "ANP %.6g N (h = 1.25 mm)\n",
      plain_coarse, anp_coarse, anp_fine);
  // The bonded corners are singular, so even ANP converges slowly; the
  // plain element's coarse answer is several times further off, and stiffer.
  EXPECT_LT(std::abs(anp_coarse - anp_fine), 0.3 * std::abs(anp_fine));
  EXPECT_GT(std::abs(plain_coarse - anp_fine), 3 * std::abs(anp_coarse - anp_fine));
  EXPECT_GT(std::abs(plain_coarse), std::abs(anp_coarse));
  // Lubricated platens would give mu (l - l^-2) A = -0.00612 N; bonding stiffens.
  EXPECT_GT(std::abs(anp_fine), 0.00612);
}

}  // namespace
}  // namespace pba
