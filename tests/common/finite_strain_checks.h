// The checks every finite-strain model test makes, written once: a random
// smooth displacement, the boundary conditions of the derivative, uniaxial,
// bonded and patch tests, the semi-analytic uniaxial stress, and the
// central-difference checks that the internal force is the derivative of the
// stored energy and the assembled tangent the derivative of the force
// (FEBio's FETangentDiagnostic, Ceres's gradient_checker). The element tests
// (tests/unit/solver/analysis/*_model_test.cc) keep what is particular to
// one element.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "analysis/finite_strain_model.h"
#include "analysis/newton_static.h"
#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "linear/linear_solver.h"
#include "material/hyperelastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"
#include "mesh/mesh.h"
#include "mesh/primitive_mesher.h"

namespace pba::testing {

// A box of sx x sy x sz mm [m out] from the primitive mesher, cells of
// about h mm, face sets x_min ... y_max, bottom, top.
inline Mesh BoxMesh(double sx_mm, double sy_mm, double sz_mm, double h_mm,
                    ElementType element = ElementType::kDefault) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {sx_mm, sy_mm, sz_mm};
  MeshSpec options;
  options.element_size_mm = h_mm;
  options.element = element;
  MeshStats stats;
  return BuildPrimitiveMesh(g, options, &stats);
}

// The displacement [m] that moves the node at the centre of a 10 mm cube
// (within 1e-9 m of (5, 5, 5) mm) by `ux` [m] along x and leaves the others
// still, for inverting the elements around it. No such node is a test
// failure (and gives no displacement).
inline Eigen::VectorXd CentreNodeMoved(const Mesh& mesh, double ux) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if ((mesh.nodes.row(i) - Eigen::RowVector3d(0.005, 0.005, 0.005)).norm() < 1e-9) {
      u(3 * i) = ux;
      return u;
    }
  }
  ADD_FAILURE() << "no node at the centre of the cube";
  return u;
}

// The lowest element index for which `inverted` holds, or -1.
inline int LowestElement(const Mesh& mesh, const std::function<bool(int element)>& inverted) {
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (inverted(e)) return e;
  }
  return -1;
}

// A smooth displacement [m] with random coefficients in [-1, 1] (seeded by
// `seed`), linear, quadratic and sinusoidal in X / length_m, so that F, and J,
// vary from element to element and inside higher-order elements:
// u_k = amplitude length_m sum_b c_kb basis_b, 3 per node in node order.
// Across a body of size length_m the strain is of the order of `amplitude`.
inline Eigen::VectorXd RandomSmoothDisplacement(const Mesh& mesh, double amplitude, unsigned seed,
                                                double length_m) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coefficient(-1, 1);
  double c[3][7];
  for (auto& row : c) {
    for (double& v : row) v = coefficient(rng);
  }
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const double x = mesh.nodes(i, 0) / length_m, y = mesh.nodes(i, 1) / length_m,
                 z = mesh.nodes(i, 2) / length_m;
    const double basis[7] = {x, y, z, x * y, y * z, z * x, std::sin(3 * (x + 2 * y - z))};
    for (int k = 0; k < 3; ++k) {
      double value = 0;
      for (int b = 0; b < 7; ++b) value += c[k][b] * basis[b];
      u(3 * i + k) = amplitude * length_m * value;
    }
  }
  return u;
}

struct MaterialCase {
  const char* name;
  std::shared_ptr<HyperelasticMaterial> material;
};

// A nearly incompressible neo-Hookean (mu = 1 kPa, K / mu = 100) and the
// one-term Ogden brain fit (mu_1 = 842 Pa, alpha_1 = -4.7).
inline std::vector<MaterialCase> NeoHookeanAndOgdenBrain() {
  OgdenCoefficients brain;
  brain.terms = {{842, -4.7}};
  brain.volumetric.d = {2 / 842e3, 0, 0};  // K / mu = 1e3
  return {{"neo_hookean", std::make_shared<PolynomialMaterial>(NeoHookeanCoefficients(1000, 1e5))},
          {"ogden_brain", std::make_shared<OgdenMaterial>(brain)}};
}

// Bottom held, every other top node displaced (nonzero prescribed values in
// z and x, for the lift), everything else free.
inline DofMap BottomHeldSomeTopMoved(const Mesh& mesh) {
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

// Uniaxial stress of a box: symmetry planes x_min (u_x = 0), y_min
// (u_y = 0) and bottom (u_z = 0), the top face moved by `top_displacement_m`
// in z, the lateral faces free.
inline DofMap UniaxialDofs(const Mesh& mesh, double top_displacement_m) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) dofs.Prescribe(n, 2, 0.0);
  for (int n : mesh.face_sets.at("top").nodes) dofs.Prescribe(n, 2, top_displacement_m);
  dofs.Finalize();
  return dofs;
}

// Bonded compression (platens glued): bottom held, the top face moved by
// `top_displacement_m` in z with x and y held.
inline DofMap BondedCompressionDofs(const Mesh& mesh, double top_displacement_m) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  for (int n : mesh.face_sets.at("top").nodes) {
    dofs.Prescribe(n, 0, 0.0);
    dofs.Prescribe(n, 1, 0.0);
    dofs.Prescribe(n, 2, top_displacement_m);
  }
  dofs.Finalize();
  return dofs;
}

// Sum of the z internal forces on the top face's nodes [N]: the reaction
// there when `force` is in equilibrium.
inline double TopReaction(const Mesh& mesh, const Eigen::VectorXd& force) {
  double reaction = 0;
  for (int n : mesh.face_sets.at("top").nodes) reaction += force(3 * n + 2);
  return reaction;
}

// Solves `model` under `dofs` with SolveNewtonStatic (default options,
// CHOLMOD) and returns the z reaction on the top face [N], the solution in
// `u` [m] when given. A failed solve is a test failure and gives NaN.
inline double NewtonTopReaction(const FiniteStrainModel& model, const Mesh& mesh,
                                const DofMap& dofs, NewtonReport* report,
                                Eigen::VectorXd* u = nullptr) {
  const auto solver = CreateLinearSolver(LinearSolverOptions{});
  Eigen::VectorXd solution;
  const Status status = SolveNewtonStatic(
      model, dofs, NewtonOptions(), solver.get(), [](const NewtonProgress&) { return true; },
      &solution, report);
  if (u != nullptr) *u = solution;
  if (!status.ok()) {
    ADD_FAILURE() << status.ToString();
    return std::numeric_limits<double>::quiet_NaN();
  }
  Eigen::VectorXd force;
  if (!model.InternalForce(solution, &force, nullptr)) {
    ADD_FAILURE() << "the converged state has an inverted element";
    return std::numeric_limits<double>::quiet_NaN();
  }
  return TopReaction(mesh, force);
}

// Uniaxial nominal stress P_zz [Pa] of the uncoupled neo-Hookean
// W = (mu/2)(I1b - 3) + (K/2)(J - 1)^2 at axial stretch `stretch` with free
// lateral faces: sigma = (mu/J) dev(b_bar) + K (J - 1) I (Holzapfel,
// Nonlinear Solid Mechanics, eq. 6.148, b_bar = J^-2/3 b); the lateral
// stretch a makes sigma_xx vanish, and P_zz = J sigma_zz / l with J = a^2 l.
// The bisection brackets a in [0.5, 2], enough in compression.
inline double UniaxialNominalStress(double mu, double bulk, double stretch) {
  const double l = stretch;
  const auto cauchy = [&](double a, double along) {
    const double j = a * a * l, i1 = 2 * a * a + l * l;
    return mu / j * std::pow(j, -2.0 / 3) * (along * along - i1 / 3) + bulk * (j - 1);
  };
  double lo = 0.5, hi = 2;  // sigma_xx(lo) < 0 < sigma_xx(hi) in compression
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cauchy(mid, mid) < 0 ? lo : hi) = mid;
  }
  const double a = 0.5 * (lo + hi);
  return a * a * cauchy(a, l);
}

// The internal force of `model` at `u` [m] is the central difference, with
// step `step_m`, of the stored energy, in every unknown: the worst error is
// below `tolerance` times the largest force. Also: the energy is positive.
// `label` names the case in failures.
inline void ExpectForceIsEnergyDerivative(const FiniteStrainModel& model, const Eigen::VectorXd& u,
                                          const std::string& label, double step_m = 1e-9,
                                          double tolerance = 1e-6) {
  Eigen::VectorXd force;
  double energy = 0;
  ASSERT_TRUE(model.InternalForce(u, &force, &energy)) << label;
  ASSERT_EQ(force.size(), u.size()) << label;
  EXPECT_GT(energy, 0) << label;
  const double scale = force.cwiseAbs().maxCoeff();
  double worst = 0;
  int worst_dof = -1;
  for (int dof = 0; dof < u.size(); ++dof) {
    Eigen::VectorXd plus = u, minus = u, unused;
    plus(dof) += step_m;
    minus(dof) -= step_m;
    double ep = 0, em = 0;
    ASSERT_TRUE(model.InternalForce(plus, &unused, &ep)) << label << " dof " << dof;
    ASSERT_TRUE(model.InternalForce(minus, &unused, &em)) << label << " dof " << dof;
    const double error = std::abs(force(dof) - (ep - em) / (2 * step_m));
    if (error > worst) {
      worst = error;
      worst_dof = dof;
    }
  }
  EXPECT_LE(worst, tolerance * scale) << label << " dof " << worst_dof;
}

// The tangent of `model` assembled at `u` [m] on the free unknowns of `dofs`:
// - is square in them and symmetric (to 1e-12 of its largest entry, and of
//   its Frobenius norm);
// - comes with rhs = -f_int on the free unknowns (to 1e-12, in the max and
//   the 2-norm);
// - is, column by column and zeros included (a gap in the sparsity pattern
//   shows), the central difference of the force with step `step_m`: the
//   worst entry within `tolerance` of K's largest, the worst column's norm
//   within `tolerance` of K's Frobenius norm;
// - and with AssemblyOptions::lift_prescribed adds -K_fp u_p to the rhs,
//   K_fp by the same differences, to `lift_tolerance` of its largest entry
//   (nothing added when no prescribed value is nonzero).
inline void ExpectTangentIsForceDerivative(const FiniteStrainModel& model, const Eigen::VectorXd& u,
                                           const DofMap& dofs, const std::string& label,
                                           double step_m = 1e-9, double tolerance = 1e-6,
                                           double lift_tolerance = 1e-6) {
  LinearSystem plain, lifted;
  ASSERT_TRUE(model.Assemble(u, dofs, AssemblyOptions(), &plain).ok()) << label;
  AssemblyOptions lift;
  lift.lift_prescribed = true;
  ASSERT_TRUE(model.Assemble(u, dofs, lift, &lifted).ok()) << label;
  ASSERT_EQ(plain.k.rows(), dofs.num_free()) << label;
  ASSERT_EQ(plain.k.cols(), dofs.num_free()) << label;
  const Eigen::MatrixXd k = Eigen::MatrixXd(plain.k);
  const double scale = k.cwiseAbs().maxCoeff();
  EXPECT_LT((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << label;
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm()) << label;

  Eigen::VectorXd force;
  ASSERT_TRUE(model.InternalForce(u, &force, nullptr)) << label;
  Eigen::VectorXd minus_force(dofs.num_free());
  bool lifts = false;  // some prescribed value is nonzero
  for (int d = 0; d < dofs.num_dofs(); ++d) {
    if (!dofs.prescribed(d)) minus_force(dofs.free_index(d)) = -force(d);
    if (dofs.prescribed(d) && dofs.prescribed_value(d) != 0) lifts = true;
  }
  EXPECT_LT((plain.rhs - minus_force).cwiseAbs().maxCoeff(), 1e-12 * force.cwiseAbs().maxCoeff())
      << label;
  EXPECT_LT((plain.rhs - minus_force).norm(), 1e-12 * minus_force.norm()) << label;

  Eigen::VectorXd lift_expected = Eigen::VectorXd::Zero(dofs.num_free());  // -K_fp u_p
  double worst = 0, worst_norm = 0;
  int worst_dof = -1;
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    Eigen::VectorXd plus = u, minus = u, fp, fm;
    plus(dof) += step_m;
    minus(dof) -= step_m;
    ASSERT_TRUE(model.InternalForce(plus, &fp, nullptr)) << label << " dof " << dof;
    ASSERT_TRUE(model.InternalForce(minus, &fm, nullptr)) << label << " dof " << dof;
    const Eigen::VectorXd column = (fp - fm) / (2 * step_m);  // d f_int / d u_dof
    Eigen::VectorXd free_column(dofs.num_free());
    for (int d = 0; d < dofs.num_dofs(); ++d) {
      if (!dofs.prescribed(d)) free_column(dofs.free_index(d)) = column(d);
    }
    if (dofs.prescribed(dof)) {
      lift_expected -= free_column * dofs.prescribed_value(dof);
    } else {
      const Eigen::VectorXd error = k.col(dofs.free_index(dof)) - free_column;
      if (error.cwiseAbs().maxCoeff() > worst) {
        worst = error.cwiseAbs().maxCoeff();
        worst_dof = dof;
      }
      worst_norm = std::max(worst_norm, error.norm());
    }
  }
  EXPECT_LT(worst, tolerance * scale) << label << " dof " << worst_dof;
  EXPECT_LT(worst_norm, tolerance * k.norm()) << label;
  if (lifts) {
    ASSERT_GT(lift_expected.cwiseAbs().maxCoeff(), 0) << label;
    EXPECT_LT((lifted.rhs - plain.rhs - lift_expected).cwiseAbs().maxCoeff(),
              lift_tolerance * lift_expected.cwiseAbs().maxCoeff())
        << label;
  } else {
    EXPECT_EQ((lifted.rhs - plain.rhs).cwiseAbs().maxCoeff(), 0) << label;
  }
}

// A homogeneous stretch diag(1.05, 0.97, 0.9) of `mesh` (a 10 mm cube with
// interior nodes): the energy is the material's energy density times the
// volume, no force acts on an interior node, and the top face's nodal
// forces add up to the traction P_zz A (P = F S, A = 1 cm^2).
inline void ExpectHomogeneousStretchBalancesItsTraction(const FiniteStrainModel& model,
                                                        const HyperelasticMaterial& material,
                                                        const Mesh& mesh,
                                                        const std::string& label) {
  const Eigen::Vector3d stretch(1.05, 0.97, 0.9);
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    u.segment<3>(3 * i) =
        (stretch.array() - 1).matrix().cwiseProduct(mesh.nodes.row(i).transpose());
  }
  std::set<int> boundary;
  for (const auto& [name, set] : mesh.face_sets) {
    boundary.insert(set.nodes.begin(), set.nodes.end());
  }
  ASSERT_LT(static_cast<int>(boundary.size()), mesh.num_nodes());
  Eigen::VectorXd force;
  double energy = 0;
  ASSERT_TRUE(model.InternalForce(u, &force, &energy)) << label;
  const Eigen::Matrix3d f = stretch.asDiagonal();
  const Eigen::Matrix3d p = f * VoigtToSymmetric(material.Stress(f));
  EXPECT_NEAR(energy, 1e-6 * material.Energy(f), 1e-12 * energy) << label;
  const double area = 1e-4, traction = p(2, 2) * area;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (!boundary.count(i)) {
      EXPECT_LT(force.segment<3>(3 * i).norm(), 1e-12 * std::abs(traction)) << label << " " << i;
    }
  }
  EXPECT_NEAR(TopReaction(mesh, force), traction, 1e-12 * std::abs(traction)) << label;
}

// `model` refuses the state `u` in which element `first_inverted` is the
// lowest-numbered inverted one: InternalForce fails, and Assemble returns
// kNumerical naming that element.
inline void ExpectInversionReported(const FiniteStrainModel& model, const Mesh& mesh,
                                    const Eigen::VectorXd& u, int first_inverted,
                                    const std::string& label) {
  Eigen::VectorXd force;
  EXPECT_FALSE(model.InternalForce(u, &force, nullptr)) << label;
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();
  LinearSystem system;
  const Status status = model.Assemble(u, dofs, AssemblyOptions(), &system);
  EXPECT_EQ(status.code(), Status::Code::kNumerical) << label;
  EXPECT_NE(status.message().find("element " + std::to_string(first_inverted) + " "),
            std::string::npos)
      << label << ": " << status.message();
}

// Solves the small-strain `system` assembled under UniaxialDofs(mesh,
// strain * height) (CHOLMOD) and returns the largest difference [m] from
// the exact uniaxial field u = (-nu e X, -nu e Y, e Z), over every unknown,
// prescribed ones included. A failed solve is a test failure and gives NaN.
inline double UniaxialPatchError(const Mesh& mesh, const DofMap& dofs, const LinearSystem& system,
                                 double nu, double strain) {
  const auto solver = CreateLinearSolver(LinearSolverOptions{});
  Eigen::VectorXd u_free;
  if (!solver->Factorize(system.k).ok() || !solver->Solve(system.rhs, &u_free).ok()) {
    ADD_FAILURE() << "the patch test's system did not solve";
    return std::numeric_limits<double>::quiet_NaN();
  }
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
  return worst;
}

}  // namespace pba::testing
