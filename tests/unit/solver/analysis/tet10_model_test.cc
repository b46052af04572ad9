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
#include <string>

#include "analysis/newton_static.h"
#include "common/finite_strain_checks.h"
#include "fem/tet10_finite_strain.h"
#include "material/linear_elastic.h"
#include "material/polynomial.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

using testing::BoxMesh;
using testing::MaterialCase;

constexpr double kEdge = 0.01;  // of the cube [m]

// A quadratic 10 mm cube with straight edges.
Mesh Cube(double h_mm) { return MakeQuadratic(BoxMesh(10, 10, 10, h_mm)); }

// The same with its side faces' mid-edge nodes bulged out by up to 0.3 mm,
// so that the boundary elements are curved.
Mesh BulgedCube(double h_mm) {
  return MakeQuadratic(BoxMesh(10, 10, 10, h_mm),
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

TEST(Tet10Model, DescribesItself) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  EXPECT_EQ(MakeTet10Model(mesh, material)->Describe(),
            "TET10 (quadratic, 4-point integration), total Lagrangian");
  EXPECT_EQ(MakeTet10MdModel(mesh, material)->Describe(),
            "TET10_MD (quadratic, 4-point integration, mean dilatation), total Lagrangian");
}

// One TET10_MD element alone has three zero modes beyond the rigid ones
// (Tet10FiniteStrainMeanDilatation.TangentAtRest); assembled, neighbours
// constrain them: the free cube's tangent at rest, nearly incompressible,
// has exactly six zero eigenvalues.
TEST(Tet10Model, MeanDilatationTangentAtRestHasOnlyTheRigidModes) {
  const Mesh mesh = BulgedCube(5);  // 2 x 2 x 2 cells, curved side faces
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  const auto model = MakeTet10MdModel(mesh, material);
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();
  LinearSystem system;
  ASSERT_TRUE(
      model->Assemble(Eigen::VectorXd::Zero(dofs.num_dofs()), dofs, AssemblyOptions(), &system)
          .ok());
  const Eigen::MatrixXd k = Eigen::MatrixXd(system.k);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(k);
  const Eigen::VectorXd lambda = eigen.eigenvalues();
  const double largest = lambda.maxCoeff();
  std::printf("TET10_MD cube at rest, K / mu = 1e4: eigenvalues 5, 6 / largest %.3g, %.3g\n",
              lambda(5) / largest, lambda(6) / largest);
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(lambda(i)), 1e-11 * largest) << i;
  EXPECT_GT(lambda(6), 1e-7 * largest);
}

TEST(Tet10Model, ForceIsTheEnergyDerivative) {
  const Mesh mesh = BulgedCube(5);  // 2 x 2 x 2 cells
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
    const auto model = MakeTet10Model(mesh, *c.material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.06, 7, kEdge);
    testing::ExpectForceIsEnergyDerivative(*model, u, c.name);
  }
}

TEST(Tet10Model, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = BulgedCube(5);
  const DofMap dofs = testing::BottomHeldSomeTopMoved(mesh);
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
    const auto model = MakeTet10Model(mesh, *c.material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.05, 11, kEdge);
    testing::ExpectTangentIsForceDerivative(*model, u, dofs, c.name);
  }
}

// A homogeneous stretch: no force on interior nodes, and the top face's
// nodal forces add up to the traction P_zz A (P = F S).
TEST(Tet10Model, HomogeneousStretchIsInEquilibriumWithItsTraction) {
  const Mesh mesh = Cube(5);
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
    testing::ExpectHomogeneousStretchBalancesItsTraction(*MakeTet10Model(mesh, *c.material),
                                                         *c.material, mesh, c.name);
  }
}

TEST(Tet10Model, InvertedElementIsReportedByItsLowestIndex) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  const auto model = MakeTet10Model(mesh, material);
  const Eigen::VectorXd u = testing::CentreNodeMoved(mesh, 0.008);
  const int first_inverted = testing::LowestElement(mesh, [&](int e) {
    Tet10FiniteStrainResult r;
    return !Tet10FiniteStrain(Tet10Coordinates(mesh, e), GatherElementTet10(mesh, e, u), material,
                              false, &r);
  });
  ASSERT_GE(first_inverted, 0);
  testing::ExpectInversionReported(*model, mesh, u, first_inverted, "TET10");
}

TEST(Tet10Model, NewtonUniaxialCompressionReachesTheHomogeneousAnswer) {
  const Mesh mesh = Cube(5);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  const DofMap dofs = testing::UniaxialDofs(mesh, (stretch - 1) * kEdge);
  for (double ratio : {1e1, 1e3}) {
    const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
    const auto model = MakeTet10Model(mesh, material);
    Eigen::VectorXd u;
    NewtonReport report;
    const double reaction = testing::NewtonTopReaction(*model, mesh, dofs, &report, &u);
    ASSERT_FALSE(std::isnan(reaction));
    const double exact = testing::UniaxialNominalStress(mu, ratio * mu, stretch);
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
  const Mesh mesh = MakeQuadratic(BoxMesh(10, 8, 6, 3));
  const double e = 3000, nu = 0.3, delta = 1e-4, height = 0.006;
  const DofMap dofs = testing::UniaxialDofs(mesh, delta);
  LinearSystem system;
  ASSERT_TRUE(AssembleLinearSystemTet10(
                  mesh, ElasticityField::Uniform(IsotropicElasticity(e, nu), mesh.num_elements()),
                  dofs, ColourElements(mesh), [](double) { return true; }, &system, ThreadContext())
                  .ok());
  const double worst = testing::UniaxialPatchError(mesh, dofs, system, nu, delta / height);
  EXPECT_LT(worst, 1e-10 * delta);
}

}  // namespace
}  // namespace pba
