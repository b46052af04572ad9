// The 10-node tetrahedron as a finite-strain model: force = dPi/du and
// tangent = d(force)/du by central differences on a curved mesh, prescribed
// values lifted, a homogeneous stretch in equilibrium with its traction, a
// Newton uniaxial solve reaching the homogeneous answer, the lowest inverted
// element named; and the small-strain assembly passing the patch test.
#include "analysis/tet10_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "analysis/newton_static.h"
#include "fem/tet10_finite_strain.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

Mesh LinearBox(double sx_mm, double sy_mm, double sz_mm, double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {sx_mm, sy_mm, sz_mm};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

// A quadratic 10 mm cube with straight edges.
Mesh Cube(double h_mm) { return MakeQuadratic(LinearBox(10, 10, 10, h_mm)); }

// The same with its side faces' mid-edge nodes bulged out by up to 0.3 mm,
// so that the boundary elements are curved.
Mesh BulgedCube(double h_mm) {
  return MakeQuadratic(LinearBox(10, 10, 10, h_mm),
                       [](const Eigen::Vector3d& x, const std::string& set) {
                         Eigen::Vector3d y = x;
                         const double bump = 3e-4 * std::sin(x.z() / 0.01 * 3.14159);
                         if (set == "x_min") y.x() -= bump;
                         if (set == "x_max") y.x() += bump;
                         if (set == "y_min") y.y() -= bump;
                         if (set == "y_max") y.y() += bump;
                         return y;
                       });
}

// A smooth displacement with random coefficients, linear, quadratic and
// sinusoidal in X, so that F varies inside the elements [m].
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
                 z = mesh.nodes(i, 2) / 0.01;
    const double basis[7] = {x, y, z, x * y, y * z, z * x, std::sin(3 * (x + 2 * y - z))};
    for (int k = 0; k < 3; ++k) {
      double value = 0;
      for (int b = 0; b < 7; ++b) value += c[k][b] * basis[b];
      u(3 * i + k) = amplitude * 0.01 * value;
    }
  }
  return u;
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

TEST(Tet10Model, DescribesItself) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  EXPECT_EQ(MakeTet10Model(mesh, material)->Describe(),
            "TET10 (quadratic, 4-point integration), total Lagrangian");
}

TEST(Tet10Model, ForceIsTheEnergyDerivative) {
  const Mesh mesh = BulgedCube(5);  // 2 x 2 x 2 cells
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeTet10Model(mesh, *c.material);
    const Eigen::VectorXd u = RandomSmooth(mesh, 0.06, 7);
    Eigen::VectorXd force;
    double energy = 0;
    ASSERT_TRUE(model->InternalForce(u, &force, &energy)) << c.name;
    ASSERT_EQ(force.size(), u.size());
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
      EXPECT_NEAR(force(dof), (ep - em) / (2 * h), 1e-6 * scale) << c.name << " dof " << dof;
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

TEST(Tet10Model, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = BulgedCube(5);
  const DofMap dofs = SomeFixed(mesh);
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeTet10Model(mesh, *c.material);
    const Eigen::VectorXd u = RandomSmooth(mesh, 0.05, 11);
    LinearSystem plain, lifted;
    ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    ASSERT_TRUE(model->Assemble(u, dofs, lift, &lifted).ok());
    ASSERT_EQ(plain.k.rows(), dofs.num_free());
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
      const Eigen::VectorXd column = (fp - fm) / (2 * h);
      Eigen::VectorXd free_column(dofs.num_free());
      for (int d = 0; d < dofs.num_dofs(); ++d) {
        if (!dofs.prescribed(d)) free_column(dofs.free_index(d)) = column(d);
      }
      if (dofs.prescribed(dof)) {
        lift_expected -= free_column * dofs.prescribed_value(dof);
      } else {
        // The whole column, zeros included: a pattern gap shows up here.
        worst = std::max(worst, (k.col(dofs.free_index(dof)) - free_column).cwiseAbs().maxCoeff());
      }
    }
    EXPECT_LT(worst, 1e-6 * scale) << c.name;
    ASSERT_GT(lift_expected.cwiseAbs().maxCoeff(), 0) << c.name;
    EXPECT_LT((lifted.rhs - plain.rhs - lift_expected).cwiseAbs().maxCoeff(),
              1e-6 * lift_expected.cwiseAbs().maxCoeff())
        << c.name;
  }
}

// A homogeneous stretch: no force on interior nodes, and the top face's
// nodal forces add up to the traction P_zz A (P = F S).
TEST(Tet10Model, HomogeneousStretchIsInEquilibriumWithItsTraction) {
  const Mesh mesh = Cube(5);
  const Eigen::Vector3d stretch(1.05, 0.97, 0.9);
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    u.segment<3>(3 * i) =
        (stretch.array() - 1).matrix().cwiseProduct(mesh.nodes.row(i).transpose());
  }
  std::set<int> boundary;
  for (const auto& [name, set] : mesh.face_sets)
    boundary.insert(set.nodes.begin(), set.nodes.end());
  ASSERT_LT(static_cast<int>(boundary.size()), mesh.num_nodes());
  for (const MaterialCase& c : Materials()) {
    const auto model = MakeTet10Model(mesh, *c.material);
    Eigen::VectorXd force;
    double energy = 0;
    ASSERT_TRUE(model->InternalForce(u, &force, &energy));
    const Eigen::Matrix3d f = stretch.asDiagonal();
    const Eigen::Matrix3d p = f * VoigtToSymmetric(c.material->Stress(f));
    EXPECT_NEAR(energy, 1e-6 * c.material->Energy(f), 1e-12 * energy) << c.name;
    const double area = 1e-4, traction = p(2, 2) * area;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      if (!boundary.count(i)) {
        EXPECT_LT(force.segment<3>(3 * i).norm(), 1e-12 * std::abs(traction)) << c.name << " " << i;
      }
    }
    double top = 0;
    for (int n : mesh.face_sets.at("top").nodes) top += force(3 * n + 2);
    EXPECT_NEAR(top, traction, 1e-12 * std::abs(traction)) << c.name;
  }
}

TEST(Tet10Model, InvertedElementIsReportedByItsLowestIndex) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  const auto model = MakeTet10Model(mesh, material);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  int centre = -1;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if ((mesh.nodes.row(i) - Eigen::RowVector3d(0.005, 0.005, 0.005)).norm() < 1e-9) centre = i;
  }
  ASSERT_GE(centre, 0);
  u(3 * centre) = 0.008;
  int first_inverted = -1;
  for (int e = 0; e < mesh.num_elements() && first_inverted < 0; ++e) {
    Tet10FiniteStrainResult r;
    if (!Tet10FiniteStrain(Tet10Coordinates(mesh, e), GatherElementTet10(mesh, e, u), material,
                           false, &r)) {
      first_inverted = e;
    }
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

// Uniaxial nominal stress P_zz of the uncoupled neo-Hookean
// W = (mu/2)(I1b - 3) + (K/2)(J - 1)^2 at axial stretch `l` with free lateral
// faces: sigma = (mu/J) dev(b_bar) + K (J - 1) I (Holzapfel, Nonlinear Solid
// Mechanics, eq. 6.148, b_bar = J^-2/3 b); the lateral stretch a makes
// sigma_xx vanish, and P_zz = J sigma_zz / l with J = a^2 l.
double UniaxialNominalStress(double mu, double k, double l) {
  const auto cauchy = [&](double a, double stretch) {
    const double j = a * a * l, i1 = 2 * a * a + l * l;
    return mu / j * std::pow(j, -2.0 / 3) * (stretch * stretch - i1 / 3) + k * (j - 1);
  };
  double lo = 0.5, hi = 2;  // sigma_xx(lo) < 0 < sigma_xx(hi) in compression
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cauchy(mid, mid) < 0 ? lo : hi) = mid;
  }
  const double a = 0.5 * (lo + hi);
  return a * a * cauchy(a, l);
}

TEST(Tet10Model, NewtonUniaxialCompressionReachesTheHomogeneousAnswer) {
  const Mesh mesh = Cube(5);
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, (stretch - 1) * 0.01);
  dofs.Finalize();
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  for (double ratio : {1e1, 1e3}) {
    const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
    const auto model = MakeTet10Model(mesh, material);
    Eigen::VectorXd u;
    NewtonReport report;
    const Status status = SolveNewtonStatic(
        *model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; }, &u,
        &report);
    ASSERT_TRUE(status.ok()) << status.ToString();
    Eigen::VectorXd force;
    ASSERT_TRUE(model->InternalForce(u, &force, nullptr));
    double reaction = 0;
    for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
    const double exact = UniaxialNominalStress(mu, ratio * mu, stretch);
    std::printf(
        "  K/mu = %5.0e: P_zz = %.8f Pa (semi-analytic %.8f), %zu increments, %d iterations\n",
        ratio, reaction / area, exact, report.increments.size(), report.total_iterations);
    EXPECT_NEAR(reaction / area, exact, 1e-6 * std::abs(exact)) << "K/mu " << ratio;
    // The homogeneous field, mid-edge nodes included: u_z = (l - 1) Z.
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      EXPECT_NEAR(u(3 * i + 2), (stretch - 1) * mesh.nodes(i, 2), 1e-9) << i;
    }
  }
}

// Small-strain patch test of AssembleLinearSystemTet10: uniaxial stress by a
// prescribed top displacement and symmetry planes is reproduced exactly, at
// corners and mid-edge nodes alike.
TEST(AssembleLinearSystemTet10, UniaxialStressIsExact) {
  const Mesh mesh = MakeQuadratic(LinearBox(10, 8, 6, 3));
  const double e = 3000, nu = 0.3, delta = 1e-4, height = 0.006;
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, delta);
  dofs.Finalize();
  LinearSystem system;
  ASSERT_TRUE(AssembleLinearSystemTet10(
                  mesh, IsotropicElasticity(e, nu), dofs, ColourElements(mesh),
                  [](double) { return true; }, &system)
                  .ok());
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  ASSERT_TRUE(solver->Factorize(system.k).ok());
  Eigen::VectorXd u_free;
  ASSERT_TRUE(solver->Solve(system.rhs, &u_free).ok());
  const double strain = delta / height;
  double worst = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
    const Eigen::Vector3d exact(-nu * strain * x.x(), -nu * strain * x.y(), strain * x.z());
    for (int c = 0; c < 3; ++c) {
      const int dof = 3 * i + c;
      const double value =
          dofs.prescribed(dof) ? dofs.prescribed_value(dof) : u_free(dofs.free_index(dof));
      worst = std::max(worst, std::abs(value - exact(c)));
    }
  }
  EXPECT_LT(worst, 1e-10 * delta);
}

}  // namespace
}  // namespace pba
