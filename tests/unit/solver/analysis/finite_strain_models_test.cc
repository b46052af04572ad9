// Every finite-strain element against every hyperelastic material: the
// internal force is the central-difference derivative of the stored energy
// and the assembled tangent the derivative of the force, column by column,
// on a small mesh under a smooth, inhomogeneous displacement. The element
// tests check more of each element; this one checks the whole matrix.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/finite_strain_model.h"
#include "analysis/hex8_model.h"
#include "analysis/tet10_model.h"
#include "common/finite_strain_checks.h"
#include "material/ogden.h"
#include "material/polynomial.h"
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

// The one-material overload of each model factory.
using Maker = std::unique_ptr<FiniteStrainModel> (*)(const Mesh&, const HyperelasticMaterial&);

std::vector<ElementCase> Elements() {
  return {
      {"TET4", ElementType::kTet4, false, static_cast<Maker>(MakeTet4Model)},
      {"TET4_ANP", ElementType::kTet4, false,
       static_cast<Maker>(MakeAverageNodalPressureTet4Model)},
      {"TET10", ElementType::kTet4, true, static_cast<Maker>(MakeTet10Model)},
      {"TET10_MD", ElementType::kTet4, true, static_cast<Maker>(MakeTet10MdModel)},
      {"HEX8", ElementType::kHex8, false, static_cast<Maker>(MakeHex8Model)},
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

// Two cells a side.
Mesh CubeMesh(const ElementCase& element) {
  const double size_mm = kSize * 1e3;
  Mesh mesh = testing::BoxMesh(size_mm, size_mm, size_mm, size_mm / 2, element.mesh_element);
  return element.quadratic ? MakeQuadratic(mesh) : mesh;
}

using Case = std::tuple<int, int>;  // element, material

class FiniteStrainModels : public ::testing::TestWithParam<Case> {};

TEST_P(FiniteStrainModels, ForceAndTangentAreDerivatives) {
  const ElementCase element = Elements()[std::get<0>(GetParam())];
  const MaterialCase material_case = Materials()[std::get<1>(GetParam())];
  const Mesh mesh = CubeMesh(element);
  const auto material = material_case.make();
  const auto model = element.make(mesh, *material);
  // Smooth and inhomogeneous, a few percent strain.
  const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.04, 11, kSize);
  const double step = 1e-7 * kSize;
  testing::ExpectForceIsEnergyDerivative(*model, u, element.name, step, 1e-6);
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();  // every unknown free: the whole tangent
  testing::ExpectTangentIsForceDerivative(*model, u, dofs, element.name, step, 1e-6);
}

std::string CaseName(const ::testing::TestParamInfo<Case>& info) {
  return Elements()[std::get<0>(info.param)].name + "_" + Materials()[std::get<1>(info.param)].name;
}

INSTANTIATE_TEST_SUITE_P(EveryElementAndMaterial, FiniteStrainModels,
                         ::testing::Combine(::testing::Range(0,
                                                             static_cast<int>(Elements().size())),
                                            ::testing::Range(0, 5)),
                         CaseName);

// Across MPI ranks each rank assembles the columns of its own nodes, with
// every element that touches one, and its own nodes' rows of the right-hand
// side, which the ranks then add up (AssemblyOptions::own_nodes). On one
// process that sum is the caller's, so each share is assembled here in
// turn: its columns must be the whole tangent's, bit for bit, its other
// columns empty, and the shares' right-hand sides must add up to the
// whole one, prescribed values lifted; the same for the internal force
// (InternalForceShare). Three shares, cut across the cube
// and not along any element, so that elements straddle them.
TEST(PartitionedAssembly, OwnColumnsAreTheWholeTangentsAndRightHandSidesAddUp) {
  const auto material = Materials()[0].make();
  for (const ElementCase& element : Elements()) {
    SCOPED_TRACE(element.name);
    const double size_mm = kSize * 1e3;
    Mesh mesh = testing::BoxMesh(size_mm, size_mm, size_mm, size_mm / 3, element.mesh_element);
    if (element.quadratic) mesh = MakeQuadratic(mesh);
    const auto model = element.make(mesh, *material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.04, 7, kSize);
    // Bottom held, top pressed down; the rest free.
    DofMap dofs(mesh.num_nodes());
    for (int n = 0; n < mesh.num_nodes(); ++n) {
      const double z = mesh.nodes(n, 2);
      for (int c = 0; c < 3; ++c) {
        if (z < 1e-9) dofs.Prescribe(n, c, 0.0);
      }
      if (z > kSize - 1e-9) dofs.Prescribe(n, 2, -0.02 * kSize);
    }
    dofs.Finalize();
    AssemblyOptions options;
    options.lift_prescribed = true;
    LinearSystem whole;
    ASSERT_TRUE(model->Assemble(u, dofs, options, &whole).ok());
    ASSERT_EQ(whole.own_nodes, nullptr);

    std::vector<int> node_of_unknown(dofs.num_free());
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
      if (dofs.free_index(dof) >= 0) node_of_unknown[dofs.free_index(dof)] = dof / 3;
    }
    Eigen::VectorXd whole_force;
    ASSERT_TRUE(model->InternalForce(u, &whole_force, nullptr));
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(dofs.num_free());
    Eigen::VectorXd force_sum = Eigen::VectorXd::Zero(whole_force.size());
    for (int share = 0; share < 3; ++share) {
      std::vector<char> own(mesh.num_nodes());
      for (int n = 0; n < mesh.num_nodes(); ++n) {
        const double t = (mesh.nodes(n, 0) + 0.7 * mesh.nodes(n, 1)) / (1.7 * kSize);
        own[n] = std::min(2, static_cast<int>(3 * t)) == share;
      }
      options.own_nodes = &own;
      LinearSystem part;
      ASSERT_TRUE(model->Assemble(u, dofs, options, &part).ok());
      EXPECT_EQ(part.own_nodes, &own);
      ASSERT_EQ(part.k.rows(), whole.k.rows());
      Eigen::Index owned_columns = 0;
      for (int j = 0; j < dofs.num_free(); ++j) {
        const Eigen::VectorXd mine = part.k.col(j), all = whole.k.col(j);
        if (own[node_of_unknown[j]]) {
          ++owned_columns;
          EXPECT_EQ(mine, all) << "column " << j;
        } else {
          EXPECT_EQ(part.k.col(j).nonZeros(), 0) << "column " << j << " is another share's";
        }
        if (!own[node_of_unknown[j]]) {
          EXPECT_EQ(part.rhs(j), 0.0) << "row " << j << " is another share's";
        }
      }
      EXPECT_GT(owned_columns, 0);
      EXPECT_LT(owned_columns, dofs.num_free());
      sum += part.rhs;
      // The residual's share, the same way.
      Eigen::VectorXd force;
      ASSERT_TRUE(model->InternalForceShare(u, own, &force));
      for (int n = 0; n < mesh.num_nodes(); ++n) {
        if (!own[n]) {
          EXPECT_TRUE(force.segment<3>(3 * n).isZero(0)) << "node " << n;
        }
      }
      force_sum += force;
    }
    EXPECT_EQ(sum, whole.rhs);
    EXPECT_EQ(force_sum, whole_force);
  }
}

}  // namespace
}  // namespace pba
