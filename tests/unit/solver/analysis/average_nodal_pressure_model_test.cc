// The nodal-pressure (average nodal pressure) tetrahedron: force = dPi/dx and
// tangent = d(force)/dx by central differences, the plain tetrahedron on a
// homogeneous deformation, no locking in bonded compression, and the
// incompressible uniaxial answer mu (lambda - lambda^-2) as K / mu grows.
#include "analysis/average_nodal_pressure_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "analysis/newton_static.h"
#include "fem/tet4_finite_strain.h"
#include "linear/linear_solver.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

Mesh Box(double sx_mm, double sy_mm, double sz_mm, double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {sx_mm, sy_mm, sz_mm};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

Mesh Cube(double h_mm) { return Box(10, 10, 10, h_mm); }

// A smooth displacement with random coefficients: linear, quadratic and
// sinusoidal in X, so that J differs from element to element.
Eigen::VectorXd RandomSmooth(const Mesh& mesh, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coefficient(-1, 1);
  double c[3][7];
  for (auto& row : c) {
    for (double& v : row) v = coefficient(rng);
  }
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const double x = mesh.nodes(i, 0) / 0.01, y = mesh.nodes(i, 1) / 0.01,
                 z = mesh.nodes(i, 2) / 0.01;  // 0..1 across the cube
    const double basis[7] = {x, y, z, x * y, y * z, z * x, std::sin(3 * (x + 2 * y - z))};
    for (int k = 0; k < 3; ++k) {
      double value = 0;
      for (int b = 0; b < 7; ++b) value += c[k][b] * basis[b];
      u(3 * i + k) = amplitude * 0.01 * value;
    }
  }
  return u;
}

// Smallest and largest element J at `u`.
std::pair<double, double> JacobianRange(const Mesh& mesh, const Eigen::VectorXd& u) {
  double lo = 1e300, hi = -1e300;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double j =
        DeformationGradient(ComputeTet4Geometry(TetCorners(mesh, e)), GatherElement(mesh, e, u))
            .determinant();
    lo = std::min(lo, j);
    hi = std::max(hi, j);
  }
  return {lo, hi};
}

struct MaterialCase {
  const char* name;
  std::shared_ptr<HyperelasticMaterial> material;
};

std::vector<MaterialCase> Materials() {
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / 842e3, 0, 0};  // K / mu = 1e3
  return {{"neo_hookean", std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e5))},
          {"ogden_brain", std::make_shared<OgdenMaterial>(brain)}};
}

TEST(AverageNodalPressure, DescribesItself) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  EXPECT_EQ(MakeAverageNodalPressureTet4Model(mesh, material)->Describe(),
            "TET4 with average nodal pressure (nodal volumetric energy), total Lagrangian");
}

TEST(AverageNodalPressure, ForceIsTheEnergyDerivative) {
  const Mesh mesh = Cube(5);  // 2 x 2 x 2 cells
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = RandomSmooth(mesh, 0.08, 7);
    const auto [j_min, j_max] = JacobianRange(mesh, u);
    ASSERT_GT(j_min, 0.5) << c.name;
    ASSERT_GT(j_max - j_min, 0.05) << c.name << ": J should vary";
    Eigen::VectorXd force;
    double energy = 0;
    ASSERT_TRUE(model->InternalForce(u, &force, &energy));
    EXPECT_GT(energy, 0) << c.name;
    const double scale = force.cwiseAbs().maxCoeff();
    const double h = 1e-9;  // m, against displacements of ~1e-3 m
    for (int dof = 0; dof < u.size(); ++dof) {
      Eigen::VectorXd plus = u, minus = u, unused;
      plus(dof) += h;
      minus(dof) -= h;
      double ep = 0, em = 0;
      ASSERT_TRUE(model->InternalForce(plus, &unused, &ep));
      ASSERT_TRUE(model->InternalForce(minus, &unused, &em));
      EXPECT_NEAR(force(dof), (ep - em) / (2 * h), 1e-7 * scale) << c.name << " dof " << dof;
    }
  }
}

// Bottom held, some top nodes displaced (nonzero prescribed values, for the
// lift), everything else free.
DofMap SomeFixed(const Mesh& mesh) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  const std::vector<int>& top = mesh.face_sets.at("top").nodes;
  for (std::size_t k = 0; k < top.size(); k += 2) {
    dofs.Prescribe(top[k], 2, -2e-4 * (1 + 0.1 * static_cast<double>(k)));
    dofs.Prescribe(top[k], 0, 3e-5);
  }
  dofs.Finalize();
  return dofs;
}

TEST(AverageNodalPressure, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = Cube(5);
  const DofMap dofs = SomeFixed(mesh);
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = RandomSmooth(mesh, 0.06, 11);
    LinearSystem plain, lifted;
    ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    ASSERT_TRUE(model->Assemble(u, dofs, lift, &lifted).ok());
    ASSERT_EQ(plain.k.rows(), dofs.num_free());
    ASSERT_EQ(plain.k.cols(), dofs.num_free());
    const Eigen::MatrixXd k = Eigen::MatrixXd(plain.k);
    const double scale = k.cwiseAbs().maxCoeff();
    EXPECT_LT((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name;

    Eigen::VectorXd force;
    ASSERT_TRUE(model->InternalForce(u, &force, nullptr));
    Eigen::VectorXd minus_force(dofs.num_free());
    for (int d = 0; d < dofs.num_dofs(); ++d) {
      if (!dofs.prescribed(d)) minus_force(dofs.free_index(d)) = -force(d);
    }
    EXPECT_LT((plain.rhs - minus_force).cwiseAbs().maxCoeff(), 1e-12 * force.cwiseAbs().maxCoeff())
        << c.name;
    Eigen::VectorXd lift_expected = Eigen::VectorXd::Zero(dofs.num_free());  // -K_fp u_p

    const double h = 1e-9;
    double worst = 0;
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      Eigen::VectorXd plus = u, minus = u, fp, fm;
      plus(dof) += h;
      minus(dof) -= h;
      ASSERT_TRUE(model->InternalForce(plus, &fp, nullptr));
      ASSERT_TRUE(model->InternalForce(minus, &fm, nullptr));
      const Eigen::VectorXd column = (fp - fm) / (2 * h);  // d f_int / d u_dof
      Eigen::VectorXd free_column(dofs.num_free());
      for (int d = 0; d < dofs.num_dofs(); ++d) {
        if (!dofs.prescribed(d)) free_column(dofs.free_index(d)) = column(d);
      }
      if (dofs.prescribed(dof)) {
        lift_expected -= free_column * dofs.prescribed_value(dof);
      } else {
        // The whole column, zeros included: an entry missing from the
        // pattern shows up here.
        worst = std::max(worst, (k.col(dofs.free_index(dof)) - free_column).cwiseAbs().maxCoeff());
      }
    }
    EXPECT_LT(worst, 1e-7 * scale) << c.name;
    ASSERT_GT(lift_expected.cwiseAbs().maxCoeff(), 0) << c.name;
    EXPECT_LT((lifted.rhs - plain.rhs - lift_expected).cwiseAbs().maxCoeff(),
              1e-6 * lift_expected.cwiseAbs().maxCoeff())
        << c.name;
  }
}

// Nodes that share no element still couple (through a common neighbour's
// nodal volume), so the pattern is wider than the plain tetrahedron's.
TEST(AverageNodalPressure, CouplesNodesTwoElementsApart) {
  const Mesh mesh = Cube(2.5);  // 4 x 4 x 4 cells
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  dofs.Finalize();
  const Eigen::VectorXd u = RandomSmooth(mesh, 0.03, 3);
  LinearSystem anp, plain;
  ASSERT_TRUE(
      MakeAverageNodalPressureTet4Model(mesh, material)->Assemble(u, dofs, AssemblyOptions(), &anp).ok());
  ASSERT_TRUE(MakeTet4Model(mesh, material)->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
  std::printf("K_ff nonzeros, %d free unknowns: ANP %ld, plain TET4 %ld\n", dofs.num_free(),
              static_cast<long>(anp.k.nonZeros()), static_cast<long>(plain.k.nonZeros()));
  EXPECT_GT(anp.k.nonZeros(), plain.k.nonZeros());

  std::set<std::pair<int, int>> share;  // node pairs in one element
  for (const auto& t : mesh.tets) {
    for (int a : t) {
      for (int b : t) share.insert({a, b});
    }
  }
  std::vector<int> node_of(dofs.num_free());
  for (int d = 0; d < dofs.num_dofs(); ++d) {
    if (!dofs.prescribed(d)) node_of[dofs.free_index(d)] = d / 3;
  }
  int far_couplings = 0;
  const double scale = Eigen::MatrixXd(anp.k).cwiseAbs().maxCoeff();
  for (int j = 0; j < anp.k.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(anp.k, j); it; ++it) {
      if (!share.count({node_of[it.row()], node_of[j]}) && std::abs(it.value()) > 1e-6 * scale) {
        ++far_couplings;
      }
    }
  }
  EXPECT_GT(far_couplings, 0);
}

TEST(AverageNodalPressure, HomogeneousDeformationIsThePlainTetrahedron) {
  const Mesh mesh = Box(10, 8, 6, 2);  // elements of several shapes
  for (const MaterialCase& c : Materials()) {
    const auto anp = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const auto plain = MakeTet4Model(mesh, *c.material);
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
    EXPECT_LT((fa - fp).cwiseAbs().maxCoeff(), 1e-11 * fp.cwiseAbs().maxCoeff()) << c.name;
    EXPECT_NEAR(ea, ep, 1e-12 * ep) << c.name;
  }
}

TEST(AverageNodalPressure, InvertedElementIsReported) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  const auto model = MakeAverageNodalPressureTet4Model(mesh, material);
  // Push the centre node far through its neighbours.
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  int centre = -1;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if ((mesh.nodes.row(i) - Eigen::RowVector3d(0.005, 0.005, 0.005)).norm() < 1e-9) centre = i;
  }
  ASSERT_GE(centre, 0);
  u(3 * centre) = 0.008;
  int first_inverted = -1;
  for (int e = 0; e < mesh.num_elements() && first_inverted < 0; ++e) {
    const Eigen::Matrix3d f =
        DeformationGradient(ComputeTet4Geometry(TetCorners(mesh, e)), GatherElement(mesh, e, u));
    if (f.determinant() <= 0) first_inverted = e;
  }
  ASSERT_GE(first_inverted, 0);
  Eigen::VectorXd force;
  EXPECT_FALSE(model->InternalForce(u, &force, nullptr));
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();
  LinearSystem system;
  const Status status = model->Assemble(u, dofs, AssemblyOptions(), &system);
  EXPECT_EQ(status.code(), Status::Code::kNumerical);
  EXPECT_NE(status.message().find("element " + std::to_string(first_inverted) + " "),
            std::string::npos)
      << status.message();
}

// Solves with Newton and returns the z reaction on the top face [N].
double TopReaction(const FiniteStrainModel& model, const Mesh& mesh, const DofMap& dofs,
                   NewtonReport* report) {
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  Eigen::VectorXd u;
  const Status status = SolveNewtonStatic(
      model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; }, &u,
      report);
  EXPECT_TRUE(status.ok()) << status.ToString();
  Eigen::VectorXd force;
  EXPECT_TRUE(model.InternalForce(u, &force, nullptr));
  double reaction = 0;
  for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
  return reaction;
}

// Bonded compression (platens glued: x, y of bottom and top held) of a
// 10 mm cube, K / mu = 1e4, by `compression` (a fraction of the height).
double BondedReaction(bool nodal_pressure, double h_mm, double compression) {
  const Mesh mesh = Cube(h_mm);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  for (int n : mesh.face_sets.at("top").nodes) {
    dofs.Prescribe(n, 0, 0.0);
    dofs.Prescribe(n, 1, 0.0);
    dofs.Prescribe(n, 2, -compression * 0.01);
  }
  dofs.Finalize();
  const auto model =
      nodal_pressure ? MakeAverageNodalPressureTet4Model(mesh, material) : MakeTet4Model(mesh, material);
  NewtonReport report;
  const double reaction = TopReaction(*model, mesh, dofs, &report);
  std::printf(
      "  %-5s h = %4.3g mm, %4.3g %%: reaction %.6g N (%zu increments, %d iterations, %d cuts, "
      "%d modified)\n",
      nodal_pressure ? "ANP" : "plain", h_mm, 100 * compression, reaction, report.increments.size(),
      report.total_iterations, report.cuts, report.approximate_iterations + report.modified_iterations);
  return reaction;
}

// Locking is a small-strain property, and it is shown at 0.25 %: beyond
// about 0.3 % the locked plain mesh's pressures (K (J - 1) >> mu, varying
// from element to element) make its tangent indefinite and SolveNewtonStatic
// cannot follow it (it stalls in modified-Newton iterations), while the
// nodal-pressure model goes to 10 % (next test).
TEST(AverageNodalPressure, DoesNotLockWhereThePlainTetrahedronDoes) {
  const double strain = 0.0025;
  const double plain_coarse = BondedReaction(false, 2.5, strain);
  const double anp_coarse = BondedReaction(true, 2.5, strain);
  const double plain_fine = BondedReaction(false, 1.25, strain);
  const double anp_fine = BondedReaction(true, 1.25, strain);
  // Lubricated platens: 3 mu strain A = -7.5e-4 N; bonding stiffens.
  EXPECT_LT(anp_fine, -7.5e-4);
  // The plain element is many times stiffer on the coarse mesh ...
  EXPECT_GT(std::abs(plain_coarse), 5 * std::abs(anp_coarse));
  // ... and much further from the finest ANP answer than ANP's coarse one.
  EXPECT_LT(std::abs(anp_coarse - anp_fine), 0.1 * std::abs(plain_coarse - anp_fine));
  // Refining helps the plain element, but it stays far too stiff.
  EXPECT_LT(std::abs(plain_fine), std::abs(plain_coarse));
  EXPECT_GT(std::abs(plain_fine), 2 * std::abs(anp_fine));
}

TEST(AverageNodalPressure, BondedCompressionToTenPercent) {
  const double coarse = BondedReaction(true, 2.5, 0.1);
  const double fine = BondedReaction(true, 1.25, 0.1);
  // Lubricated platens would give mu (l - l^-2) A = -0.0253 N at l = 0.9;
  // bonding stiffens. The bonded edges are singular, so the coarse mesh is
  // still some 20 % stiffer.
  EXPECT_LT(fine, -0.0253);
  EXPECT_LT(coarse, fine);
  EXPECT_LT(std::abs(coarse - fine), 0.3 * std::abs(fine));
}

// Uniaxial nominal stress of the uncoupled neo-Hookean W = (mu/2)(I1b - 3) +
// (K/2)(J - 1)^2 at axial stretch `l` with free lateral faces: the lateral
// stretch a makes sigma_xx = (mu / J) J^-2/3 (a^2 - I1/3) + K (J - 1) zero
// (sigma = (mu/J) dev b_bar + U'(J) I, Holzapfel eq. 6.148 with
// b_bar = J^-2/3 b), J = a^2 l, and P_zz = J sigma_zz / l.
double UniaxialNominalStress(double mu, double k, double l) {
  const auto sigma = [&](double a, bool axial) {
    const double j = a * a * l, i1 = 2 * a * a + l * l;
    const double stretch2 = axial ? l * l : a * a;
    return mu / j * std::pow(j, -2.0 / 3) * (stretch2 - i1 / 3) + k * (j - 1);
  };
  double lo = 0.9, hi = 1.5;  // sigma_xx < 0 at lo, > 0 at hi for l = 0.8
  for (int it = 0; it < 200; ++it) {
    const double mid = (lo + hi) / 2;
    (sigma(mid, false) < 0 ? lo : hi) = mid;
  }
  const double a = (lo + hi) / 2;
  return a * a * l * sigma(a, true) / l;
}

TEST(AverageNodalPressure, UniaxialStressApproachesTheIncompressibleAnswer) {
  const Mesh mesh = Cube(5);
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, (stretch - 1) * 0.01);
  dofs.Finalize();
  const double incompressible = mu * (stretch - 1 / (stretch * stretch));  // -762.5 Pa
  double previous_gap = 1e300;
  for (double ratio : {1e1, 1e2, 1e3, 1e4, 1e5, 1e6}) {
    const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
    const auto model = MakeAverageNodalPressureTet4Model(mesh, material);
    NewtonReport report;
    const double nominal = TopReaction(*model, mesh, dofs, &report) / area;
    const double exact = UniaxialNominalStress(mu, ratio * mu, stretch);
    std::printf("  K/mu = %7.0e: P_zz = %.6f Pa (semi-analytic %.6f, incompressible %.1f)\n", ratio,
                nominal, exact, incompressible);
    EXPECT_NEAR(nominal, exact, 1e-6 * std::abs(exact)) << "K/mu " << ratio;
    const double gap = std::abs(nominal - incompressible);
    EXPECT_LT(gap, previous_gap) << "K/mu " << ratio;
    previous_gap = gap;
  }
  EXPECT_LT(previous_gap, 1e-3 * std::abs(incompressible));
}

}  // namespace
}  // namespace pba
