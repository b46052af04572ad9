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
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "analysis/newton_static.h"
#include "common/finite_strain_checks.h"
#include "fem/tet4_finite_strain.h"
#include "material/material_field.h"
#include "material/polynomial.h"

namespace pba {
namespace {

using testing::BoxMesh;
using testing::MaterialCase;

constexpr double kEdge = 0.01;  // of the cube [m]

Mesh Cube(double h_mm) { return BoxMesh(10, 10, 10, h_mm); }

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

TEST(AverageNodalPressure, DescribesItself) {
  const Mesh mesh = Cube(5);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e6));
  EXPECT_EQ(MakeAverageNodalPressureTet4Model(mesh, material)->Describe(),
            "TET4 with average nodal pressure (nodal volumetric energy), total Lagrangian");
}

TEST(AverageNodalPressure, ForceIsTheEnergyDerivative) {
  const Mesh mesh = Cube(5);  // 2 x 2 x 2 cells
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.08, 7, kEdge);
    const auto [j_min, j_max] = JacobianRange(mesh, u);
    ASSERT_GT(j_min, 0.5) << c.name;
    ASSERT_GT(j_max - j_min, 0.05) << c.name << ": J should vary";
    testing::ExpectForceIsEnergyDerivative(*model, u, c.name, 1e-9, 1e-7);
  }
}

TEST(AverageNodalPressure, TangentIsTheForceDerivativeAndLiftsPrescribedValues) {
  const Mesh mesh = Cube(5);
  const DofMap dofs = testing::BottomHeldSomeTopMoved(mesh);
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
    const auto model = MakeAverageNodalPressureTet4Model(mesh, *c.material);
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.06, 11, kEdge);
    testing::ExpectTangentIsForceDerivative(*model, u, dofs, c.name, 1e-9, 1e-7);
  }
}

// Two materials (a stiff growing one in half the cube), a viscous step with
// history: each node on the interface has one volumetric constraint per
// material; force and tangent stay the derivatives of the step's energy.
MaterialField TwoMaterials(const Mesh& mesh) {
  std::vector<MaterialField::Entry> entries(2);
  entries[0].material = std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e6));
  entries[0].relaxation = PronySeries{{0.5, 0.2}, {0.1, 10}};
  entries[1].material = std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(2000, 6e3));
  entries[1].growth_strain = 0.2;
  std::vector<int> of_element(mesh.num_elements(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    double x = 0;
    for (int a : mesh.tets[e]) x += mesh.nodes(a, 0) / 4;
    of_element[e] = x > kEdge / 2;
  }
  return MaterialField(std::move(entries), std::move(of_element), ThreadContext());
}

TEST(AverageNodalPressure, MaterialsGrowthAndHistoryKeepForceAndTangentExact) {
  const Mesh mesh = Cube(2.5);
  MaterialField field = TwoMaterials(mesh);
  const auto model = MakeAverageNodalPressureTet4Model(mesh, field, ThreadContext());
  // A committed step, then a trial step with history and growth.
  field.BeginStep(0.05, 0.5);
  field.Commit(ElementDeformationGradients(
      mesh, testing::RandomSmoothDisplacement(mesh, 0.04, 3, kEdge), ThreadContext()));
  field.BeginStep(0.05, 1.0);
  const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.06, 5, kEdge);
  testing::ExpectForceIsEnergyDerivative(*model, u, "two materials", 1e-9, 1e-7);
  testing::ExpectTangentIsForceDerivative(*model, u, testing::BottomHeldSomeTopMoved(mesh),
                                          "two materials", 1e-9, 1e-7);
}

TEST(AverageNodalPressure, AGrownBodyIsStressFreeAtItsGrownShape) {
  // Growth by 10 % in every direction of a nearly incompressible body: the
  // nodal volume ratios must reach 1.331 with no energy.
  const Mesh mesh = Cube(2.5);
  std::vector<MaterialField::Entry> entries(2);
  entries[0].material = std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e7));
  entries[1].material = std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e7));
  entries[1].growth_strain = 0.1;
  std::vector<int> of_element(mesh.num_elements(), 1);
  MaterialField grown(std::move(entries), std::move(of_element), ThreadContext());
  grown.BeginStep(0, 1.0);
  // All of the cube grows and nothing holds it but rigid modes: the model
  // is stress-free at u = 0.1 X.
  const auto model = MakeAverageNodalPressureTet4Model(mesh, grown, ThreadContext());
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int a = 0; a < mesh.num_nodes(); ++a)
    u.segment<3>(3 * a) = 0.1 * mesh.nodes.row(a).transpose();
  Eigen::VectorXd force;
  double energy = 0;
  ASSERT_TRUE(model->InternalForce(u, &force, &energy));
  EXPECT_LT(force.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(std::abs(energy), 1e-15);
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
  const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.03, 3, kEdge);
  LinearSystem anp, plain;
  ASSERT_TRUE(MakeAverageNodalPressureTet4Model(mesh, material)
                  ->Assemble(u, dofs, AssemblyOptions(), &anp)
                  .ok());
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
  const Mesh mesh = BoxMesh(10, 8, 6, 2);  // elements of several shapes
  for (const MaterialCase& c : testing::NeoHookeanAndOgdenBrain()) {
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
  const Eigen::VectorXd u = testing::CentreNodeMoved(mesh, 0.008);
  const int first_inverted = testing::LowestElement(mesh, [&](int e) {
    return DeformationGradient(ComputeTet4Geometry(TetCorners(mesh, e)), GatherElement(mesh, e, u))
               .determinant() <= 0;
  });
  ASSERT_GE(first_inverted, 0);
  testing::ExpectInversionReported(*model, mesh, u, first_inverted, "TET4_ANP");
}

// Bonded compression (platens glued: x, y of bottom and top held) of a
// 10 mm cube, K / mu = 1e4, by `compression` (a fraction of the height).
double BondedReaction(bool nodal_pressure, double h_mm, double compression) {
  const Mesh mesh = Cube(h_mm);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e7));
  const DofMap dofs = testing::BondedCompressionDofs(mesh, -compression * 0.01);
  const auto model = nodal_pressure ? MakeAverageNodalPressureTet4Model(mesh, material)
                                    : MakeTet4Model(mesh, material);
  NewtonReport report;
  const double reaction = testing::NewtonTopReaction(*model, mesh, dofs, &report);
  std::printf(
      "  %-5s h = %4.3g mm, %4.3g %%: reaction %.6g N (%zu increments, %d iterations, %d cuts, "
      "%d modified)\n",
      nodal_pressure ? "ANP" : "plain", h_mm, 100 * compression, reaction, report.increments.size(),
      report.total_iterations, report.cuts,
      report.approximate_iterations + report.modified_iterations);
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

TEST(AverageNodalPressure, UniaxialStressApproachesTheIncompressibleAnswer) {
  const Mesh mesh = Cube(5);
  const double stretch = 0.8, mu = 1000, area = 1e-4;
  const DofMap dofs = testing::UniaxialDofs(mesh, (stretch - 1) * 0.01);
  const double incompressible = mu * (stretch - 1 / (stretch * stretch));  // -762.5 Pa
  double previous_gap = 1e300;
  for (double ratio : {1e1, 1e2, 1e3, 1e4, 1e5, 1e6}) {
    const PolynomialMaterial material(NeoHookeanCoefficients(mu, ratio * mu));
    const auto model = MakeAverageNodalPressureTet4Model(mesh, material);
    NewtonReport report;
    const double nominal = testing::NewtonTopReaction(*model, mesh, dofs, &report) / area;
    const double exact = testing::UniaxialNominalStress(mu, ratio * mu, stretch);
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
