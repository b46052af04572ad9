// Rigid contact: force = dPi/dx and tangent = d(force)/dx by central
// differences for every shape, with and without multipliers; a plane
// pressing a block balances the support's reaction and matches the same
// compression prescribed on the top face; Hertz's sphere on a nearly linear
// block; Coulomb friction bounded by mu p_N; bad bodies refused.
#include "analysis/rigid_contact.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/newton_static.h"
#include "common/finite_strain_checks.h"
#include "linear/linear_solver.h"
#include "material/polynomial.h"

namespace pba {
namespace {

using testing::BoxMesh;
using Shape = ContactSpec::Shape;

constexpr double kMu = 1000;  // shear modulus [Pa]

const char* ShapeName(Shape shape) {
  return shape == Shape::kSphere ? "sphere" : shape == Shape::kFlatPunch ? "flat punch" : "plane";
}

// A body of `shape` touching the top (z = 10 mm) of a 10 mm cube near its
// centre, deep enough that some top nodes penetrate and others do not.
RigidBody BodyOnTop(Shape shape) {
  RigidBody body;
  body.shape = shape;
  body.axis = Eigen::Vector3d(0, 0, -2);  // any length
  body.motion = Eigen::Vector3d(0, 0, -1e-3);
  switch (shape) {
    case Shape::kSphere:
      body.radius = 0.004;
      body.position = Eigen::Vector3d(0.005, 0.0052, 0.0126);
      break;
    case Shape::kFlatPunch:
      body.radius = 0.0031;
      body.position = Eigen::Vector3d(0.0049, 0.0051, 0.0100);
      break;
    default:
      body.position = Eigen::Vector3d(0.005, 0.005, 0.0101);
      body.axis = Eigen::Vector3d(0.1, 0.05, -1);  // tilted: some nodes in, some out
      break;
  }
  return body;
}

// The contact's force and energy and tangent at `u` checked against central
// differences (step 1e-9 m) over the unknowns of its nodes.
void ExpectConsistent(const RigidContact& contact, const Mesh& mesh, const Eigen::VectorXd& u,
                      const std::string& label) {
  const int n = 3 * mesh.num_nodes();
  Eigen::VectorXd force = Eigen::VectorXd::Zero(n);
  double energy = 0;
  contact.AddInternalForce(u, &force, &energy);
  DofMap dofs(mesh.num_nodes());
  dofs.Finalize();
  LinearSystem system;
  system.k.resize(n, n);
  system.rhs = Eigen::VectorXd::Zero(n);
  contact.AddTangent(u, dofs, &system);
  ASSERT_TRUE(system.k.isCompressed()) << label;
  EXPECT_LT((system.rhs + force).cwiseAbs().maxCoeff(), 1e-14 * force.cwiseAbs().maxCoeff())
      << label << ": rhs = -f_int";
  const Eigen::MatrixXd k = Eigen::MatrixXd(system.k);
  const double force_scale = force.cwiseAbs().maxCoeff(), k_scale = k.cwiseAbs().maxCoeff();
  ASSERT_GT(force_scale, 0) << label;
  double force_error = 0, k_error = 0;
  const double step = 1e-9;
  for (int node : contact.nodes()) {
    for (int c = 0; c < 3; ++c) {
      const int dof = 3 * node + c;
      Eigen::VectorXd plus = u, minus = u;
      plus(dof) += step;
      minus(dof) -= step;
      Eigen::VectorXd fp = Eigen::VectorXd::Zero(n), fm = Eigen::VectorXd::Zero(n);
      double ep = 0, em = 0;
      contact.AddInternalForce(plus, &fp, &ep);
      contact.AddInternalForce(minus, &fm, &em);
      force_error = std::max(force_error, std::abs((ep - em) / (2 * step) - force(dof)));
      k_error = std::max(k_error, ((fp - fm) / (2 * step) - k.col(dof)).cwiseAbs().maxCoeff());
    }
  }
  std::printf("%s: energy %.3e J, force error %.2e, tangent error %.2e (relative)\n", label.c_str(),
              energy, force_error / force_scale, k_error / k_scale);
  EXPECT_LT(force_error, 1e-6 * force_scale) << label;
  EXPECT_LT(k_error, 1e-6 * k_scale) << label;
}

TEST(RigidContact, ForceAndTangentAreDerivatives) {
  const Mesh mesh = BoxMesh(10, 10, 10, 2.5);  // 4 x 4 x 4 cells
  const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.01, 5, 0.01);
  const Eigen::VectorXd u2 = u + testing::RandomSmoothDisplacement(mesh, 0.003, 9, 0.01);
  for (Shape shape : {Shape::kPlane, Shape::kFlatPunch, Shape::kSphere}) {
    const double penalty = DefaultContactPenalty(kMu, 2.5e-3);
    RigidContact contact(mesh, mesh.face_sets.at("top"), BodyOnTop(shape), penalty, 0, 0);
    contact.SetAmplitude(0.1);
    const ContactMeasure m = contact.Measure(u);
    ASSERT_GT(m.nodes_in_contact, 2) << ShapeName(shape);
    ASSERT_LT(m.nodes_in_contact, static_cast<int>(contact.nodes().size())) << ShapeName(shape);
    ExpectConsistent(contact, mesh, u, std::string(ShapeName(shape)) + ", lambda = 0");
    // Multipliers from one state (tolerance 0: any penetration augments),
    // checked at another.
    ASSERT_TRUE(contact.Augment(u));
    ASSERT_GT(*std::max_element(contact.multipliers().begin(), contact.multipliers().end()), 0);
    ExpectConsistent(contact, mesh, u2, std::string(ShapeName(shape)) + ", lambda > 0");
  }
}

// The state a checkpoint carries: multipliers and stick points come back
// exactly, so a restored contact gives the same forces as the original;
// a state of the wrong length is refused.
TEST(RigidContact, SavedStateRestoresTheSameForces) {
  const Mesh mesh = BoxMesh(10, 10, 10, 2.5);
  const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.01, 5, 0.01);
  const Eigen::VectorXd u2 = u + testing::RandomSmoothDisplacement(mesh, 0.003, 9, 0.01);
  const double penalty = DefaultContactPenalty(kMu, 2.5e-3);
  RigidContact contact(mesh, mesh.face_sets.at("top"), BodyOnTop(Shape::kPlane), penalty, 0.3, 0);
  contact.SetAmplitude(0.1);
  ASSERT_TRUE(contact.Augment(u));
  contact.Commit(u);  // sliding nodes move their stick points
  const std::vector<double> state = contact.SaveState();
  EXPECT_EQ(state.size(), 4 * contact.nodes().size());

  RigidContact restored(mesh, mesh.face_sets.at("top"), BodyOnTop(Shape::kPlane), penalty, 0.3, 0);
  restored.SetAmplitude(0.1);
  ASSERT_TRUE(restored.RestoreState(state).ok());
  EXPECT_EQ(restored.SaveState(), state);
  EXPECT_EQ(restored.multipliers(), contact.multipliers());
  Eigen::VectorXd f1 = Eigen::VectorXd::Zero(u.size()), f2 = f1;
  contact.AddInternalForce(u2, &f1, nullptr);
  restored.AddInternalForce(u2, &f2, nullptr);
  EXPECT_EQ((f1 - f2).cwiseAbs().maxCoeff(), 0);
  EXPECT_GT(f1.cwiseAbs().maxCoeff(), 0);

  std::vector<double> short_state(state.begin(), state.end() - 1);
  const Status status = restored.RestoreState(short_state);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
}

// Through the decorator, on a model with held and moved unknowns (the lift
// of prescribed values included): the whole tangent is the force's
// derivative.
TEST(RigidContact, DecoratedModelIsConsistent) {
  const Mesh mesh = BoxMesh(10, 10, 10, 5);
  const PolynomialMaterial material(NeoHookeanCoefficients(kMu, 1e5));
  const auto body = MakeAverageNodalPressureTet4Model(mesh, material);
  const DofMap dofs = testing::BottomHeldSomeTopMoved(mesh);
  for (Shape shape : {Shape::kPlane, Shape::kSphere}) {
    RigidContact contact(mesh, mesh.face_sets.at("top"), BodyOnTop(shape),
                         DefaultContactPenalty(kMu, 5e-3), 0, 0);
    contact.SetAmplitude(0.2);
    const auto model = WithContact(*body, {&contact});
    EXPECT_EQ(model->Describe(), body->Describe() + ", with 1 rigid contact");
    const Eigen::VectorXd u = testing::RandomSmoothDisplacement(mesh, 0.01, 3, 0.01);
    ASSERT_GT(contact.Measure(u).nodes_in_contact, 0) << ShapeName(shape);
    testing::ExpectForceIsEnergyDerivative(*model, u, ShapeName(shape), 1e-9, 1e-6);
    testing::ExpectTangentIsForceDerivative(*model, u, dofs, ShapeName(shape), 1e-9, 1e-6);
  }
}

// Solves `model` (which holds `contacts`) with the contacts following the
// load factor (amplitude a = lambda), augmenting each converged increment
// and committing each accepted one; `each` sees every accepted increment.
Status SolveWithContacts(const FiniteStrainModel& model, const DofMap& dofs,
                         const std::vector<RigidContact*>& contacts, NewtonOptions options,
                         Eigen::VectorXd* u, NewtonReport* report,
                         const std::function<void(const Eigen::VectorXd&)>& each = nullptr) {
  options.amplitude = [](double load) { return load; };
  options.begin_increment = [&](double, double to) {
    for (RigidContact* c : contacts) c->SetAmplitude(options.amplitude(to));
    return Status::Ok();
  };
  options.augment = [&](const Eigen::VectorXd& state) {
    bool again = false;
    for (RigidContact* c : contacts) again = c->Augment(state) || again;
    return again;
  };
  options.on_increment = [&](double, const Eigen::VectorXd& state) {
    for (RigidContact* c : contacts) c->Commit(state);
    if (each) each(state);
  };
  const auto solver = CreateLinearSolver(LinearSolverOptions{});
  return SolveNewtonStatic(
      model, dofs, options, solver.get(), [](const NewtonProgress&) { return true; }, u, report);
}

// Sum of the body's internal forces on the bottom face's nodes [N]: the
// force the body exerts on its support.
Eigen::Vector3d BottomForce(const Mesh& mesh, const FiniteStrainModel& body,
                            const Eigen::VectorXd& u) {
  Eigen::VectorXd force;
  EXPECT_TRUE(body.InternalForce(u, &force, nullptr));
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int n : mesh.face_sets.at("bottom").nodes) sum += force.segment<3>(3 * n);
  return sum;
}

DofMap BottomHeld(const Mesh& mesh) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  dofs.Finalize();
  return dofs;
}

// A plane pressed 10 % of the height into a block is frictionless
// compression of its top face: the same force as prescribing u_z there.
TEST(RigidContact, PlaneCompressesLikePrescribedTop) {
  const double h = 1.25e-3, height = 5e-3, depth = 0.1 * height;
  const Mesh mesh = BoxMesh(10, 10, 5, 1.25);
  const PolynomialMaterial material(NeoHookeanCoefficients(kMu, 100 * kMu));
  const auto body = MakeAverageNodalPressureTet4Model(mesh, material);
  RigidBody plane;
  plane.shape = Shape::kPlane;
  plane.position = Eigen::Vector3d(0, 0, height);
  plane.axis = Eigen::Vector3d(0, 0, -1);
  plane.motion = Eigen::Vector3d(0, 0, -depth);
  ASSERT_TRUE(plane.Validate().ok());
  const double tolerance = 1e-3 * h;
  RigidContact contact(mesh, mesh.face_sets.at("top"), plane, DefaultContactPenalty(kMu, h), 0,
                       tolerance);
  EXPECT_NEAR(std::accumulate(contact.areas().begin(), contact.areas().end(), 0.0), 1e-4, 1e-16);
  const auto model = WithContact(*body, {&contact});
  const DofMap dofs = BottomHeld(mesh);
  Eigen::VectorXd u;
  NewtonReport report;
  const Status status = SolveWithContacts(*model, dofs, {&contact}, NewtonOptions(), &u, &report);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const ContactMeasure m = contact.Measure(u);
  const Eigen::Vector3d support = BottomForce(mesh, *body, u);
  std::printf(
      "plane: %d increments, %d iterations, %d augmentations; force on the plane (%.6g, %.3g, "
      "%.6g) N, on the support (%.6g, %.3g, %.6g) N; penetration %.3g m (tolerance %.3g); "
      "area %.4g m^2, %d nodes\n",
      static_cast<int>(report.increments.size()), report.total_iterations, report.augmentations,
      m.force.x(), m.force.y(), m.force.z(), support.x(), support.y(), support.z(), m.penetration,
      tolerance, m.area, m.nodes_in_contact);
  EXPECT_GT(m.force.z(), 0);
  EXPECT_LT((m.force - support).norm(), 1e-6 * m.force.norm());
  EXPECT_LE(m.penetration, tolerance);
  EXPECT_GT(report.augmentations, 0);
  EXPECT_NEAR(m.area, 1e-4, 1e-12);

  // The same compression prescribed on the top face, lateral motion free.
  DofMap prescribed(mesh.num_nodes());
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) prescribed.Prescribe(n, c, 0.0);
  }
  for (int n : mesh.face_sets.at("top").nodes) prescribed.Prescribe(n, 2, -depth);
  prescribed.Finalize();
  NewtonReport plain_report;
  const double top = testing::NewtonTopReaction(*body, mesh, prescribed, &plain_report);
  const double error = std::abs(m.force.z() + top) / std::abs(top);
  std::printf("plane: prescribed top %.6g N, contact %.6g N, difference %.3g %%\n", -top,
              m.force.z(), 100 * error);
  EXPECT_LT(error, 0.01);
}

// A quarter of a block, 0 <= x, y <= side and 0 <= z <= height [m], whose
// cells shrink towards the axis x = y = 0 and the top face: the primitive
// mesher's uniform grid of n x n x n cells with each coordinate mapped by
// g(t) = c t + (1 - c) t^4 (t the coordinate over the side, measured from
// the axis, or down from the top), so that the cells there are c times a
// uniform grid's and stay fine over about a third of the side. Each grid
// cell stays an axis-aligned box, so the tetrahedra remain positively
// oriented, and the face sets keep their names and planes.
Mesh GradedQuarterBlock(double side, double height, int n, double c) {
  Mesh mesh = BoxMesh(n, n, n, 1);  // unit cells of 1 mm
  const double cells = 1e-3 * n;
  const auto g = [c](double t) { return c * t + (1 - c) * std::pow(t, 4); };
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    mesh.nodes(i, 0) = side * g(mesh.nodes(i, 0) / cells);
    mesh.nodes(i, 1) = side * g(mesh.nodes(i, 1) / cells);
    mesh.nodes(i, 2) = height * (1 - g(1 - mesh.nodes(i, 2) / cells));
  }
  return mesh;
}

// Symmetry planes x = 0 and y = 0, bottom held.
DofMap QuarterDofs(const Mesh& mesh) {
  DofMap dofs(mesh.num_nodes());
  for (int n : mesh.face_sets.at("x_min").nodes) dofs.Prescribe(n, 0, 0.0);
  for (int n : mesh.face_sets.at("y_min").nodes) dofs.Prescribe(n, 1, 0.0);
  for (int n : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(n, c, 0.0);
  }
  dofs.Finalize();
  return dofs;
}

struct IndentationCase {
  const char* name;
  Shape shape;
  double radius;  // of the sphere or the punch [m]
  double depth;   // indentation [m]
  double exact;   // the half-space's force [N]
};

// Indents a graded quarter block (40 mm deep, 40 mm wide, so 80 x 80 mm
// whole; finest cells 0.25 mm) of a compressible neo-Hookean (K / mu =
// 10 / 3: nu = 4 / 11, E = 30 mu / 11, linear at small strain) on the axis and compares the whole
// force with the half-space's (Johnson, Contact Mechanics, 1985, chapters 3
// and 4): a sphere of radius R at depth d, F = (4/3) E* R^(1/2) d^(3/2); a
// flat-ended punch of radius a, F = 2 a E* d; E* = E / (1 - nu^2). Returns
// the relative error. Measured on 16^3 cells: sphere +8.1 %, punch -4.3 %.
// The sphere's error falls with the cells (+6.9 % on 20^3, finest 0.16 mm):
// linear tetrahedra are stiff, and the contact's rim falls between nodes.
// The punch's sign depends on where the nodes lie around its rim (only
// nodes within the radius are held), and on a block half this size it was
// +6.4 % (the held base stiffens it).
double Indent(const IndentationCase& c, int cells) {
  const double side = 0.04, height = 0.04, bulk = 10.0 / 3 * kMu, grading = 0.1;
  const Mesh mesh = GradedQuarterBlock(side, height, cells, grading);
  const double h = grading * side / cells;  // the finest cells, under the body [m]
  const PolynomialMaterial material(NeoHookeanCoefficients(kMu, bulk));
  const auto body = MakeAverageNodalPressureTet4Model(mesh, material);
  RigidBody rigid;
  rigid.shape = c.shape;
  rigid.radius = c.radius;
  rigid.axis = Eigen::Vector3d(0, 0, -1);
  rigid.position = Eigen::Vector3d(0, 0, height + (c.shape == Shape::kSphere ? c.radius : 0));
  rigid.motion = Eigen::Vector3d(0, 0, -c.depth);
  const double tolerance = 0.005 * c.depth;
  RigidContact contact(mesh, mesh.face_sets.at("top"), rigid, DefaultContactPenalty(kMu, h), 0,
                       tolerance);
  const auto model = WithContact(*body, {&contact});
  NewtonOptions options;
  options.initial_increments = 2;
  Eigen::VectorXd u;
  NewtonReport report;
  const Status status =
      SolveWithContacts(*model, QuarterDofs(mesh), {&contact}, options, &u, &report);
  EXPECT_TRUE(status.ok()) << c.name << ": " << status.ToString();
  const ContactMeasure m = contact.Measure(u);
  const double force = 4 * m.force.z();
  const double error = (force - c.exact) / c.exact;
  std::printf(
      "%s, %d^3 cells (finest %.3g mm): force %.5g N, half-space %.5g N, error %+.2f %%; contact "
      "area %.4g mm^2 (quarter), %d nodes; penetration %.3g of the depth; %d increments, %d "
      "iterations, %d augmentations\n",
      c.name, cells, 1e3 * h, force, c.exact, 100 * error, 1e6 * m.area, m.nodes_in_contact,
      m.penetration / c.depth, static_cast<int>(report.increments.size()), report.total_iterations,
      report.augmentations);
  EXPECT_LE(m.penetration, tolerance) << c.name;
  return error;
}

double ReducedModulus() {
  const double bulk = 10.0 / 3 * kMu;
  const double e = 9 * bulk * kMu / (3 * bulk + kMu),
               nu = (3 * bulk - 2 * kMu) / (6 * bulk + 2 * kMu);
  return e / (1 - nu * nu);
}

TEST(RigidContact, SphereFollowsHertz) {
  const double radius = 0.01, depth = 3e-4;  // d / R = 0.03, contact radius 1.7 mm
  const IndentationCase hertz{
      "Hertz sphere", Shape::kSphere, radius, depth,
      4.0 / 3 * ReducedModulus() * std::sqrt(radius) * std::pow(depth, 1.5)};
  EXPECT_LT(std::abs(Indent(hertz, 16)), 0.15);
}

TEST(RigidContact, FlatPunchFollowsBoussinesq) {
  const double radius = 0.003, depth = 6e-5;  // d / a = 0.02
  const IndentationCase punch{"Boussinesq flat punch", Shape::kFlatPunch, radius, depth,
                              2 * radius * ReducedModulus() * depth};
  EXPECT_LT(std::abs(Indent(punch, 16)), 0.15);
}

// A block pressed 5 % by a plane, which then slides 1.5 mm along x: with
// Coulomb friction the tangential force on the plane never exceeds mu times
// the normal one and reaches it once the whole contact slides; without
// friction there is none.
void PressAndSlide(double friction, double* largest_ratio, double* final_ratio) {
  const double h = 1.25e-3, height = 5e-3;
  const Mesh mesh = BoxMesh(10, 10, 5, 1.25);
  const PolynomialMaterial material(NeoHookeanCoefficients(kMu, 100 * kMu));
  const auto body = MakeAverageNodalPressureTet4Model(mesh, material);
  RigidBody plane;
  plane.shape = Shape::kPlane;
  plane.position = Eigen::Vector3d(0, 0, height);
  plane.motion = Eigen::Vector3d(0, 0, -0.05 * height);
  RigidContact contact(mesh, mesh.face_sets.at("top"), plane, DefaultContactPenalty(kMu, h),
                       friction, 1e-3 * h);
  const auto model = WithContact(*body, {&contact});
  const DofMap dofs = BottomHeld(mesh);
  *largest_ratio = 0;
  *final_ratio = 0;
  int increments = 0;
  const auto check = [&](const Eigen::VectorXd& state) {
    const ContactMeasure m = contact.Measure(state);
    const double tangential = std::hypot(m.force.x(), m.force.y());
    *largest_ratio = std::max(*largest_ratio, tangential / m.force.z());
    *final_ratio = tangential / m.force.z();
    ++increments;
    EXPECT_GT(m.force.z(), 0);
    EXPECT_LE(tangential, friction * m.force.z() * (1 + 1e-6));
  };
  NewtonOptions options;
  options.max_iterations = 100;  // linear convergence while sliding
  Eigen::VectorXd u;
  NewtonReport press, slide;
  Status status = SolveWithContacts(*model, dofs, {&contact}, options, &u, &press, check);
  ASSERT_TRUE(status.ok()) << status.ToString();
  plane.position = contact.Centre();
  plane.motion = Eigen::Vector3d(1.5e-3, 0, 0);
  contact.SetBody(plane);
  contact.SetAmplitude(0);
  options.start_u = u;
  status = SolveWithContacts(*model, dofs, {&contact}, options, &u, &slide, check);
  ASSERT_TRUE(status.ok()) << status.ToString();
  const ContactMeasure m = contact.Measure(u);
  std::printf(
      "friction %.1f: force on the plane (%.5g, %.3g, %.5g) N, tangential / normal %.6f at the "
      "end, %.6f at most; %d increments, pressing %d iterations, sliding %d iterations (%d "
      "augmentations)\n",
      friction, m.force.x(), m.force.y(), m.force.z(), *final_ratio, *largest_ratio, increments,
      press.total_iterations, slide.total_iterations, slide.augmentations);
}

TEST(RigidContact, CoulombFrictionBoundsTheTangentialForce) {
  double largest = 0, final = 0;
  PressAndSlide(0.5, &largest, &final);
  EXPECT_LE(largest, 0.5 * (1 + 1e-6));
  // The whole contact slides (0.49957 measured: the nodes' slip directions
  // differ slightly, so their tractions add up to a little less).
  EXPECT_GT(final, 0.5 * (1 - 5e-3));
}

TEST(RigidContact, FrictionlessPlaneHasNoTangentialForce) {
  double largest = 0, final = 0;
  PressAndSlide(0, &largest, &final);
  EXPECT_LT(largest, 1e-12);
}

TEST(RigidContact, BadBodiesAreRefused) {
  RigidBody sphere;
  sphere.shape = Shape::kSphere;
  sphere.radius = 0.01;
  EXPECT_TRUE(sphere.Validate().ok());
  for (double radius : {0.0, -1e-3, std::nan("")}) {
    sphere.radius = radius;
    const Status status = sphere.Validate("contacts[0]");
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << radius;
    EXPECT_EQ(status.field(), "contacts[0].radius") << radius;
  }
  RigidBody punch;
  punch.shape = Shape::kFlatPunch;
  punch.radius = 0.002;
  punch.axis = Eigen::Vector3d::Zero();
  EXPECT_EQ(punch.Validate().field(), "contact.axis");
  EXPECT_NE(punch.Validate().message().find("non-zero"), std::string::npos);
  punch.axis = Eigen::Vector3d(0, 0, 3);
  EXPECT_TRUE(punch.Validate().ok());
  punch.radius = 0;
  EXPECT_EQ(punch.Validate().field(), "contact.radius");

  RigidBody plane;
  plane.shape = Shape::kPlane;  // needs no radius
  EXPECT_TRUE(plane.Validate().ok());
  plane.axis = Eigen::Vector3d::Zero();
  EXPECT_EQ(plane.Validate().field(), "contact.axis");
  plane.axis = Eigen::Vector3d(0, 0, 1);
  plane.motion = Eigen::Vector3d(0, std::nan(""), 0);
  EXPECT_EQ(plane.Validate().field(), "contact.motion");
  EXPECT_EQ(RigidBody().Validate().field(), "contact.shape");
}

// Each node's tributary area: a third of each linear triangle, a twelfth
// (corner) or a quarter (mid-edge node) of each 6-node triangle, a quarter
// of each quad; together the set's area.
TEST(RigidContact, TributaryAreasAddUpToTheSetsArea) {
  for (ElementType element : {ElementType::kTet4, ElementType::kTet10, ElementType::kHex8}) {
    const Mesh mesh = BoxMesh(10, 8, 6, 2, element);
    const FaceSet& top = mesh.face_sets.at("top");
    RigidBody plane;
    plane.shape = Shape::kPlane;
    const RigidContact contact(mesh, top, plane, 1e8, 0, 0);
    ASSERT_EQ(contact.nodes(), top.nodes);
    const double sum = std::accumulate(contact.areas().begin(), contact.areas().end(), 0.0);
    EXPECT_NEAR(sum, FaceSetArea(mesh, top), 1e-12 * sum) << static_cast<int>(element);
    EXPECT_NEAR(sum, 8e-5, 1e-12 * sum) << static_cast<int>(element);
    EXPECT_GT(*std::min_element(contact.areas().begin(), contact.areas().end()), 0)
        << static_cast<int>(element);
  }
}

TEST(RigidContact, DefaultPenaltyIsAHundredShearModuliPerElement) {
  EXPECT_DOUBLE_EQ(DefaultContactPenalty(1000, 1e-3), 1e8);
  EXPECT_DOUBLE_EQ(DefaultContactPenalty(1000, 1e-3, 10), 1e7);
}

}  // namespace
}  // namespace pba
