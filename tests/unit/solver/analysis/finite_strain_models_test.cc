// Every finite-strain element against every hyperelastic material: the
// internal force is the central-difference derivative of the stored energy
// and the assembled tangent the derivative of the force, column by column,
// on a small mesh under a smooth, inhomogeneous displacement. The element
// tests check more of each element; this one checks the whole matrix.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/finite_strain_model.h"
#include "analysis/hex8_model.h"
#include "analysis/tet10_model.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

constexpr double kSize = 6e-3;  // cube edge [m]

struct ElementCase {
  std::string name;
  ElementType mesh_element;  // how the primitive mesher cuts the cube
  bool quadratic;
  std::function<std::unique_ptr<FiniteStrainModel>(const Mesh&, const HyperelasticMaterial&)> make;
};

std::vector<ElementCase> Elements() {
  return {
      {"TET4", ElementType::kTet4, false, MakeTet4Model},
      {"TET4_ANP", ElementType::kTet4, false, MakeAverageNodalPressureTet4Model},
      {"TET10", ElementType::kTet4, true, MakeTet10Model},
      {"HEX8", ElementType::kHex8, false, MakeHex8Model},
  };
}

struct MaterialCase {
  std::string name;
  std::function<std::unique_ptr<HyperelasticMaterial>()> make;
};

std::vector<MaterialCase> Materials() {
  const double mu = 1000, bulk = 1e4;  // K / mu = 10 keeps the differences well conditioned
  return {
      {"NeoHookean",
       [=] { return std::make_unique<PolynomialMaterial>(NeoHookeanCoefficients(mu, bulk)); }},
      {"MooneyRivlin",
       [=] {
         return std::make_unique<PolynomialMaterial>(MooneyRivlinCoefficients(300, 200, bulk));
       }},
      {"PolynomialN3",
       [=] {
         PolynomialCoefficients c;
         c.order = 3;
         c.c[1][0] = 300;
         c.c[0][1] = 150;
         c.c[2][0] = 80;
         c.c[1][1] = -20;
         c.c[0][2] = 30;
         c.c[3][0] = 10;
         c.volumetric.d = {2 / bulk, 1e-5, 1e-6};
         return std::make_unique<PolynomialMaterial>(c);
       }},
      {"OgdenBrain",
       [=] {
         OgdenCoefficients c;
         c.terms = {{842, -4.7}};
         c.volumetric.d = {2 / bulk, 0, 0};
         return std::make_unique<OgdenMaterial>(c);
       }},
      {"Ogden3",
       [=] {
         OgdenCoefficients c;
         c.terms = {{600, 1.3}, {5, 5.0}, {-10, -2.0}};
         c.volumetric.d = {2 / bulk, 0, 0};
         return std::make_unique<OgdenMaterial>(c);
       }},
  };
}

Mesh CubeMesh(const ElementCase& element) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {kSize * 1e3, kSize * 1e3, kSize * 1e3};
  MeshSpec options;
  options.element_size_mm = kSize * 1e3 / 2;
  options.element = element.mesh_element;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  return element.quadratic ? MakeQuadratic(mesh) : mesh;
}

// Smooth and inhomogeneous (linear, quadratic and sinusoidal terms with
// random coefficients), up to a few percent strain.
Eigen::VectorXd Displacement(const Mesh& mesh, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coefficient(-1, 1);
  double c[3][5];
  for (auto& row : c) {
    for (double& v : row) v = coefficient(rng);
  }
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector3d x = mesh.nodes.row(i).transpose() / kSize;
    const double basis[5] = {x.x(), x.y() * x.z(), x.z() * x.x(), x.x() * x.y(),
                             std::sin(2 * x.x() + 3 * x.y() - x.z())};
    for (int k = 0; k < 3; ++k) {
      double v = 0;
      for (int b = 0; b < 5; ++b) v += c[k][b] * basis[b];
      u(3 * i + k) = 0.04 * kSize * v;
    }
  }
  return u;
}

using Case = std::tuple<int, int>;  // element, material

class FiniteStrainModels : public ::testing::TestWithParam<Case> {};

TEST_P(FiniteStrainModels, ForceAndTangentAreDerivatives) {
  const ElementCase element = Elements()[std::get<0>(GetParam())];
  const MaterialCase material_case = Materials()[std::get<1>(GetParam())];
  const Mesh mesh = CubeMesh(element);
  const auto material = material_case.make();
  const auto model = element.make(mesh, *material);
  const Eigen::VectorXd u = Displacement(mesh, 11);
  const int n = static_cast<int>(u.size());

  Eigen::VectorXd force;
  double energy = 0;
  ASSERT_TRUE(model->InternalForce(u, &force, &energy));
  const double step = 1e-7 * kSize;
  const auto energy_at = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd f;
    double w = 0;
    EXPECT_TRUE(model->InternalForce(v, &f, &w));
    return w;
  };
  const auto force_at = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd f;
    double w = 0;
    EXPECT_TRUE(model->InternalForce(v, &f, &w));
    return f;
  };
  double worst_force = 0;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd plus = u, minus = u;
    plus(i) += step;
    minus(i) -= step;
    worst_force = std::max(worst_force,
                           std::abs((energy_at(plus) - energy_at(minus)) / (2 * step) - force(i)));
  }
  EXPECT_LT(worst_force, 1e-6 * force.cwiseAbs().maxCoeff()) << element.name;

  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();  // every unknown free: the whole tangent
  LinearSystem system;
  ASSERT_TRUE(model->Assemble(u, dofs, AssemblyOptions(), &system).ok());
  const Eigen::MatrixXd k = Eigen::MatrixXd(system.k);
  EXPECT_LT((system.rhs + force).norm(), 1e-12 * force.norm());
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
  double worst_column = 0;
  for (int j = 0; j < n; ++j) {
    Eigen::VectorXd plus = u, minus = u;
    plus(j) += step;
    minus(j) -= step;
    const Eigen::VectorXd column = (force_at(plus) - force_at(minus)) / (2 * step);
    worst_column = std::max(worst_column, (column - k.col(j)).norm());
  }
  EXPECT_LT(worst_column, 1e-6 * k.norm()) << element.name;
}

std::string CaseName(const ::testing::TestParamInfo<Case>& info) {
  return Elements()[std::get<0>(info.param)].name + "_" + Materials()[std::get<1>(info.param)].name;
}

INSTANTIATE_TEST_SUITE_P(EveryElementAndMaterial, FiniteStrainModels,
                         ::testing::Combine(::testing::Range(0, 4), ::testing::Range(0, 5)),
                         CaseName);

}  // namespace
}  // namespace pba
