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
#include "common/finite_strain_checks.h"
#include "fem/hex8_finite_strain.h"
#include "material/linear_elastic.h"
#include "material/polynomial.h"

namespace pba {
namespace {

using testing::MaterialCase;

constexpr double kEdge = 0.01;  // of the cube [m]

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

using ModelFactory = std::unique_ptr<FiniteStrainModel> (*)(const Mesh&,
                                                            const HyperelasticMaterial&);

struct ModelCase {
  const char* name;
  ModelFactory make;
};

std::vector<ModelCase> Models() {
  return {{"mean_dilatation", &MakeHex8Model}, {"full", &MakeHex8FullModel}};
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
    for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
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
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.06, 7, kEdge);
    testing::ExpectForceIsEnergyDerivative(*model, u, c.name);
  }
}

TEST(Hex8Model, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = HexCube(3, 0.2);
  const DofMap dofs = testing::BottomHeldSomeTopMoved(mesh);
  for (const Case& c : Cases()) {
    const auto model = c.make(mesh, *c.material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.05, 11, kEdge);
    testing::ExpectTangentIsForceDerivative(*model, u, dofs, c.name);

    // The definite option reaches the elements: same rhs, another
    // (symmetric) matrix.
    LinearSystem plain, definite;
    ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &plain).ok());
    AssemblyOptions drop;
    drop.drop_pressure_stiffness = true;
    ASSERT_TRUE(model->Assemble(u, dofs, drop, &definite).ok());
    const Eigen::MatrixXd k = Eigen::MatrixXd(plain.k), kd = Eigen::MatrixXd(definite.k);
    const double scale = k.cwiseAbs().maxCoeff();
    EXPECT_EQ((definite.rhs - plain.rhs).norm(), 0) << c.name;
    EXPECT_GT((kd - k).cwiseAbs().maxCoeff(), 1e-6 * scale) << c.name;
    EXPECT_LT((kd - kd.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << c.name;
  }
}

// A homogeneous stretch of a distorted mesh: no force on interior nodes,
// and the top face's nodal forces add up to the traction P_zz A (P = F S).
TEST(Hex8Model, HomogeneousStretchIsInEquilibriumWithItsTraction) {
  const Mesh mesh = HexCube(3, 0.2);
  for (const Case& c : Cases()) {
    testing::ExpectHomogeneousStretchBalancesItsTraction(*c.make(mesh, *c.material), *c.material,
                                                         mesh, c.name);
  }
}

TEST(Hex8Model, InvertedElementIsReportedByItsLowestIndex) {
  const Mesh mesh = HexCube(2);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  // The centre node far past the x_max faces of the bricks it is an x_min
  // corner of: their Gauss points next to it fold over.
  const Eigen::VectorXd u = testing::CentreNodeMoved(mesh, 0.03);
  const int first_inverted = testing::LowestElement(mesh, [&](int e) {
    Hex8FiniteStrainResult r;
    return !Hex8FiniteStrain(Hex8Coordinates(mesh, e), GatherElementHex8(mesh, e, u), material,
                             false, &r);
  });
  ASSERT_GE(first_inverted, 0);
  // Both kernels refuse the same states (an F with det F <= 0 at a point).
  for (const ModelCase& m : Models()) {
    testing::ExpectInversionReported(*m.make(mesh, material), mesh, u, first_inverted, m.name);
  }
}

TEST(Hex8Model, NewtonUniaxialCompressionReachesTheHomogeneousAnswer) {
  const Mesh mesh = HexCube(3, 0.2);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  const DofMap dofs = testing::UniaxialDofs(mesh, (stretch - 1) * kEdge);
  // The field is uniform, so the fully integrated brick does not lock here:
  // it gives the same answer as the mean-dilatation one.
  for (const ModelCase& m : Models()) {
    for (double ratio : {1e1, 1e3, 1e5}) {
      const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
      const auto model = m.make(mesh, material);
      Eigen::VectorXd u;
      NewtonReport report;
      const double reaction = testing::NewtonTopReaction(*model, mesh, dofs, &report, &u);
      ASSERT_FALSE(std::isnan(reaction)) << m.name;
      const double exact = testing::UniaxialNominalStress(mu, ratio * mu, stretch);
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
  using Assembly = Status (*)(
      const Mesh&, const ElasticityField&, const DofMap&, const std::vector<std::vector<int>>&,
      const std::function<bool(double)>&, LinearSystem*, const ThreadContext&);
  const Mesh mesh = HexCube(3, 0.2);
  const double delta = 1e-4, height = 0.01;
  const DofMap dofs = testing::UniaxialDofs(mesh, delta);
  for (Assembly assemble : {&AssembleLinearSystemHex8, &AssembleLinearSystemHex8Full}) {
    const char* name = assemble == &AssembleLinearSystemHex8 ? "B-bar" : "full";
    for (double nu : {0.3, 0.4999}) {
      LinearSystem system;
      ASSERT_TRUE(
          assemble(
              mesh, ElasticityField::Uniform(IsotropicElasticity(3000, nu), mesh.num_elements()),
              dofs, ColourElements(mesh), [](double) { return true; }, &system, ThreadContext())
              .ok());
      const double worst = testing::UniaxialPatchError(mesh, dofs, system, nu, delta / height);
      EXPECT_LT(worst, 1e-9 * delta) << name << " nu " << nu;
    }
  }
}

// Bonded compression (platens glued: x, y of bottom and top held) of a
// 10 mm cube, K / mu = 1e4, by `compression` (a fraction of the height);
// returns the z reaction on the top face [N].
// `label` names the model in the printout.
double BondedReaction(const Mesh& mesh, ModelFactory make, const char* label, double compression) {
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  const DofMap dofs = testing::BondedCompressionDofs(mesh, -compression * kEdge);
  NewtonReport report;
  const double reaction = testing::NewtonTopReaction(*make(mesh, material), mesh, dofs, &report);
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
  const Mesh tets = testing::BoxMesh(10, 10, 10, 1.25);
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
