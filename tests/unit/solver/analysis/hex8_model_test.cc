// The mean-dilatation and the fully integrated hexahedra as finite-strain
// models, on structured brick meshes built here: colouring, force = dPi/du
// and tangent = d(force)/du by central differences (prescribed values
// lifted, the definite option honoured), a homogeneous stretch in
// equilibrium with its traction, the lowest inverted element named, Newton
// uniaxial compression reaching the homogeneous answer, the small-strain
// patch test of both linear assemblies, bonded compression of a nearly
// incompressible cube agreeing with the average nodal pressure tetrahedron,
// and the fully integrated brick locking there.
#include "analysis/hex8_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/newton_static.h"
#include "fem/hex8_finite_strain.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

// A 10 mm cube cut into n x n x n bricks [m], face sets named as the
// primitive mesher's (x_min ... y_max, bottom, top) with outward-ordered
// quadrilaterals. `jitter` moves every interior node randomly by up to that
// fraction of the cell size, so the bricks are distorted while the faces
// stay planar.
Mesh HexCube(int n, double jitter = 0) {
  const int m = n + 1;
  const double h = 0.01 / n;
  const auto id = [m](int i, int j, int k) { return i + m * (j + m * k); };
  Mesh mesh;
  mesh.nodes.resize(m * m * m, 3);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> shake(-1, 1);
  for (int k = 0; k < m; ++k) {
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        Eigen::RowVector3d x(h * i, h * j, h * k);
        const bool interior = i > 0 && i < n && j > 0 && j < n && k > 0 && k < n;
        if (interior) {
          for (int c = 0; c < 3; ++c) x(c) += jitter * h * shake(rng);
        }
        mesh.nodes.row(id(i, j, k)) = x;
      }
    }
  }
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        mesh.hexes.push_back({id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k),
                              id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
                              id(i, j + 1, k + 1)});
      }
    }
  }
  const char* names[3][2] = {{"x_min", "x_max"}, {"y_min", "y_max"}, {"bottom", "top"}};
  for (int c = 0; c < 3; ++c) {
    // (a, b, c) cyclic, so e_a x e_b = e_c: counter-clockwise in (a, b) is
    // outward on the max side.
    const int a = (c + 1) % 3, b = (c + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      FaceSet& set = mesh.face_sets[names[c][side]];
      const auto node = [&](int p, int q) {
        std::array<int, 3> ijk;
        ijk[c] = side * n;
        ijk[a] = p;
        ijk[b] = q;
        return id(ijk[0], ijk[1], ijk[2]);
      };
      for (int q = 0; q < n; ++q) {
        for (int p = 0; p < n; ++p) {
          std::array<int, 4> quad = {node(p, q), node(p + 1, q), node(p + 1, q + 1),
                                     node(p, q + 1)};
          if (side == 0) std::swap(quad[1], quad[3]);
          set.quads.push_back(quad);
        }
      }
      for (int q = 0; q <= n; ++q) {
        for (int p = 0; p <= n; ++p) set.nodes.push_back(node(p, q));
      }
      std::sort(set.nodes.begin(), set.nodes.end());
    }
  }
  return mesh;
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

using ModelFactory = std::unique_ptr<FiniteStrainModel> (*)(const Mesh&,
                                                            const HyperelasticMaterial&);

struct ModelCase {
  const char* name;
  ModelFactory make;
};

std::vector<ModelCase> Models() {
  return {{"mean_dilatation", &MakeHex8Model}, {"full", &MakeHex8FullModel}};
}

std::vector<MaterialCase> Materials() {
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / 842e3, 0, 0};  // K / mu = 1e3
  return {{"neo_hookean", std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e5))},
          {"ogden_brain", std::make_shared<OgdenMaterial>(brain)}};
}

// Every model with every material.
struct Case {
  std::string name;
  ModelFactory make;
  std::shared_ptr<HyperelasticMaterial> material;
};

std::vector<Case> Cases() {
  std::vector<Case> cases;
  for (const ModelCase& m : Models()) {
    for (const MaterialCase& c : Materials()) {
      cases.push_back({std::string(m.name) + "/" + c.name, m.make, c.material});
    }
  }
  return cases;
}

TEST(Hex8Model, DescribesItself) {
  const Mesh mesh = HexCube(2);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  EXPECT_EQ(MakeHex8Model(mesh, material)->Describe(),
            "HEX8 (2x2x2 integration, mean dilatation), total Lagrangian");
  EXPECT_EQ(MakeHex8FullModel(mesh, material)->Describe(),
            "HEX8, full 2x2x2 integration (locks when nearly incompressible), total Lagrangian");
}

TEST(Hex8Model, ColoursSeparateBricksThatShareANode) {
  const Mesh mesh = HexCube(4);
  const std::vector<std::vector<int>> colours = ColourElements(mesh);
  // An interior node is in eight bricks, so at least eight colours.
  EXPECT_GE(colours.size(), 8u);
  std::vector<int> seen(mesh.num_elements(), 0);
  for (const auto& colour : colours) {
    std::set<int> nodes;
    for (int e : colour) {
      ++seen[e];
      for (int a : mesh.hexes[e]) EXPECT_TRUE(nodes.insert(a).second) << "element " << e;
    }
  }
  for (int e = 0; e < mesh.num_elements(); ++e) EXPECT_EQ(seen[e], 1) << e;
}

TEST(Hex8Model, ForceIsTheEnergyDerivative) {
  const Mesh mesh = HexCube(3, 0.2);
  for (const Case& c : Cases()) {
    const auto model = c.make(mesh, *c.material);
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

TEST(Hex8Model, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = HexCube(3, 0.2);
  const DofMap dofs = SomeFixed(mesh);
  for (const Case& c : Cases()) {
    const auto model = c.make(mesh, *c.material);
    const Eigen::VectorXd u = RandomSmooth(mesh, 0.05, 11);
    LinearSystem plain, lifted, definite;
    ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
    AssemblyOptions lift;
    lift.lift_prescribed = true;
    ASSERT_TRUE(model->Assemble(u, dofs, lift, &lifted).ok());
    AssemblyOptions drop;
    drop.drop_pressure_stiffness = true;
    ASSERT_TRUE(model->Assemble(u, dofs, drop, &definite).ok());
    ASSERT_EQ(plain.k.rows(), dofs.num_free());
    const Eigen::MatrixXd k = Eigen::MatrixXd(plain.k);
    const double scale = k.cwiseAbs().maxCoeff();
    EXPECT_LT((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name;
    // The option reaches the elements: same rhs, another (symmetric) matrix.
    const Eigen::MatrixXd kd = Eigen::MatrixXd(definite.k);
    EXPECT_EQ((definite.rhs - plain.rhs).norm(), 0) << c.name;
    EXPECT_GT((kd - k).cwiseAbs().maxCoeff(), 1e-6 * scale) << c.name;
    EXPECT_LT((kd - kd.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name;

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

// A homogeneous stretch of a distorted mesh: no force on interior nodes,
// and the top face's nodal forces add up to the traction P_zz A (P = F S).
TEST(Hex8Model, HomogeneousStretchIsInEquilibriumWithItsTraction) {
  const Mesh mesh = HexCube(3, 0.2);
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
  for (const Case& c : Cases()) {
    const auto model = c.make(mesh, *c.material);
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

TEST(Hex8Model, InvertedElementIsReportedByItsLowestIndex) {
  const Mesh mesh = HexCube(2);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  int centre = -1;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if ((mesh.nodes.row(i) - Eigen::RowVector3d(0.005, 0.005, 0.005)).norm() < 1e-9) centre = i;
  }
  ASSERT_GE(centre, 0);
  // Far past the x_max faces of the bricks it is an x_min corner of: their
  // Gauss points next to it fold over.
  u(3 * centre) = 0.03;
  int first_inverted = -1;
  for (int e = 0; e < mesh.num_elements() && first_inverted < 0; ++e) {
    Hex8FiniteStrainResult r;
    if (!Hex8FiniteStrain(Hex8Coordinates(mesh, e), GatherElementHex8(mesh, e, u), material, false,
                          &r)) {
      first_inverted = e;
    }
  }
  ASSERT_GE(first_inverted, 0);
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();
  // Both kernels refuse the same states (an F with det F <= 0 at a point).
  for (const ModelCase& m : Models()) {
    const auto model = m.make(mesh, material);
    Eigen::VectorXd force;
    EXPECT_FALSE(model->InternalForce(u, &force, nullptr)) << m.name;
    LinearSystem system;
    const Status status = model->Assemble(u, dofs, AssemblyOptions(), &system);
    EXPECT_EQ(status.code(), Status::Code::kNumerical) << m.name;
    EXPECT_NE(status.message().find("element " + std::to_string(first_inverted) + " "),
              std::string::npos)
        << m.name << ": " << status.message();
  }
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

TEST(Hex8Model, NewtonUniaxialCompressionReachesTheHomogeneousAnswer) {
  const Mesh mesh = HexCube(3, 0.2);
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, (stretch - 1) * 0.01);
  dofs.Finalize();
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  // The field is uniform, so the fully integrated brick does not lock here:
  // it gives the same answer as the mean-dilatation one.
  for (const ModelCase& m : Models()) {
    for (double ratio : {1e1, 1e3, 1e5}) {
      const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
      const auto model = m.make(mesh, material);
      Eigen::VectorXd u;
      NewtonReport report;
      const Status status = SolveNewtonStatic(
          *model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; },
          &u, &report);
      ASSERT_TRUE(status.ok()) << m.name << ": " << status.ToString();
      Eigen::VectorXd force;
      ASSERT_TRUE(model->InternalForce(u, &force, nullptr));
      double reaction = 0;
      for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
      const double exact = UniaxialNominalStress(mu, ratio * mu, stretch);
      std::printf(
          "  %-15s K/mu = %5.0e: P_zz = %.8f Pa (semi-analytic %.8f), %zu increments, %d "
          "iterations\n",
          m.name, ratio, reaction / area, exact, report.increments.size(), report.total_iterations);
      EXPECT_NEAR(reaction / area, exact, 1e-6 * std::abs(exact)) << m.name << " K/mu " << ratio;
      // The homogeneous field, interior (distorted) nodes included: u_z = (l - 1) Z.
      for (int i = 0; i < mesh.num_nodes(); ++i) {
        EXPECT_NEAR(u(3 * i + 2), (stretch - 1) * mesh.nodes(i, 2), 1e-9) << m.name << " " << i;
      }
    }
  }
}

// Small-strain patch test of AssembleLinearSystemHex8 and
// AssembleLinearSystemHex8Full on distorted bricks: uniaxial stress by a
// prescribed top displacement and symmetry planes is reproduced exactly,
// even at nu = 0.4999 (a uniform field: no locking for either).
TEST(AssembleLinearSystemHex8, UniaxialStressIsExact) {
  using Assembly =
      Status (*)(const Mesh&, const Matrix6d&, const DofMap&, const std::vector<std::vector<int>>&,
                 const std::function<bool(double)>&, LinearSystem*);
  const Mesh mesh = HexCube(3, 0.2);
  const double delta = 1e-4, height = 0.01;
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, delta);
  dofs.Finalize();
  for (Assembly assemble : {&AssembleLinearSystemHex8, &AssembleLinearSystemHex8Full}) {
    const char* name = assemble == &AssembleLinearSystemHex8 ? "B-bar" : "full";
    for (double nu : {0.3, 0.4999}) {
      LinearSystem system;
      ASSERT_TRUE(assemble(
                      mesh, IsotropicElasticity(3000, nu), dofs, ColourElements(mesh),
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
      EXPECT_LT(worst, 1e-9 * delta) << name << " nu " << nu;
    }
  }
}

Mesh TetCube(double h_mm) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 10};
  MeshSpec m;
  m.element_size_mm = h_mm;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

// Bonded compression (platens glued: x, y of bottom and top held) of a
// 10 mm cube, K / mu = 1e4, by `compression` (a fraction of the height);
// returns the z reaction on the top face [N].
// `label` names the model in the printout.
double BondedReaction(const Mesh& mesh, ModelFactory make, const char* label, double compression) {
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
  const auto model = make(mesh, material);
  const auto solver = CreateLinearSolver(AnalysisSpec::LinearSolver::kCholmod);
  Eigen::VectorXd u;
  NewtonReport report;
  const Status status = SolveNewtonStatic(
      *model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; }, &u,
      &report);
  EXPECT_TRUE(status.ok()) << status.ToString();
  Eigen::VectorXd force;
  EXPECT_TRUE(model->InternalForce(u, &force, nullptr));
  double reaction = 0;
  for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
  std::printf(
      "  %-9s %4d elements, %4.3g %%: reaction %.6g N (%zu increments, %d iterations, %d cuts, "
      "%d approximate)\n",
      label, mesh.num_elements(), 100 * compression, reaction, report.increments.size(),
      report.total_iterations, report.cuts,
      report.approximate_iterations + report.modified_iterations);
  return reaction;
}

// The locking test of the average nodal pressure tetrahedron
// (average_nodal_pressure_model_test.cc), where the plain tetrahedron is
// many times too stiff: the mean-dilatation brick, on the same node
// spacing, agrees with the nodal-pressure answer.
TEST(Hex8Model, BondedCompressionAgreesWithTheNodalPressureTetrahedron) {
  const Mesh bricks = HexCube(8);
  const Mesh tets = TetCube(1.25);
  for (double compression : {0.0025, 0.1}) {
    const double hex = BondedReaction(bricks, &MakeHex8Model, "HEX8", compression);
    const double anp = BondedReaction(tets, &MakeAverageNodalPressureTet4Model, "ANP", compression);
    // Lubricated platens: mu (l - l^-2) A; bonding stiffens.
    const double l = 1 - compression, lubricated = 1000 * (l - 1 / (l * l)) * 1e-4;
    EXPECT_LT(hex, lubricated) << compression;
    EXPECT_LT(std::abs(hex - anp), 0.2 * std::abs(anp)) << compression;
  }
}

// The same bonded cube with the fully integrated brick: eight volume
// constraints per element against 3 unknowns per node lock it: it comes out
// over ten times stiffer than the mean-dilatation brick (which agrees with
// the nodal-pressure tetrahedron above).
TEST(Hex8Model, FullIntegrationLocksInBondedCompression) {
  const Mesh bricks = HexCube(8);
  const double compression = 0.0025;
  const double mean = BondedReaction(bricks, &MakeHex8Model, "HEX8", compression);
  const double full = BondedReaction(bricks, &MakeHex8FullModel, "HEX8_FULL", compression);
  std::printf("  full / mean dilatation: %.3g\n", full / mean);
  EXPECT_GT(full / mean, 10);
}

}  // namespace
}  // namespace pba
