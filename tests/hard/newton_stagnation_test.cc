// A load the body cannot carry: a neo-Hookean block whose nodal forces are
// capped (a material that saturates) pulled by a traction above the cap.
// No state balances it, so Newton's residual stops falling; the solve must
// end with a message saying the residual stagnated, at a small share of
// the iterations it spent when it went on until every cut was exhausted.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <string>

#include "analysis/finite_strain_model.h"
#include "analysis/newton_static.h"
#include "assembly/external_loads.h"
#include "linear/linear_solver.h"
#include "material/polynomial.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

// The inner model with every component of its internal force capped at
// +-cap_n [N], in the force and in the assembled right-hand side alike (so
// no step is taken at rounding level while the residual is large); the
// tangent is the inner model's.
class CappedForceModel : public FiniteStrainModel {
 public:
  CappedForceModel(std::unique_ptr<FiniteStrainModel> inner, double cap_n)
      : inner_(std::move(inner)), cap_(cap_n) {}
  std::string Describe() const override { return "capped " + inner_->Describe(); }
  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    if (!inner_->InternalForce(u, force, energy)) return false;
    *force = force->cwiseMax(-cap_).cwiseMin(cap_);
    return true;
  }
  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    PBA_RETURN_IF_ERROR(inner_->Assemble(u, dofs, options, system));
    Eigen::VectorXd force;
    double energy = 0;
    if (!inner_->InternalForce(u, &force, &energy)) return Status::Numerical("inverted");
    for (int d = 0; d < dofs.num_dofs(); ++d) {
      if (!dofs.prescribed(d)) {
        system->rhs(dofs.free_index(d)) += force(d) - std::clamp(force(d), -cap_, cap_);
      }
    }
    return Status::Ok();
  }
  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override {
    return inner_->RecoverFields(u, solution);
  }

 private:
  std::unique_ptr<FiniteStrainModel> inner_;
  double cap_;
};

struct Outcome {
  Status status;
  NewtonReport report;
};

Outcome PullCappedBlock(int stagnation_iterations) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {10, 10, 10};
  MeshSpec spec;
  spec.element_size_mm = 5;
  MeshStats stats;
  const Mesh mesh = BuildPrimitiveMesh(g, spec, &stats);
  const PolynomialMaterial material(NeoHookeanCoefficients(1000, 1e5));
  // 10 kPa on 1 cm^2 is 1 N over the top's 9 nodes; each may carry 0.02 N.
  CappedForceModel model(MakeTet4Model(mesh, material), 0.02);
  ExternalLoads loads(mesh);
  loads.AddTraction(mesh.face_sets.at("top"), Eigen::Vector3d(0, 0, 1e4));
  DofMap dofs(mesh.num_nodes());
  for (int i : mesh.face_sets.at("bottom").nodes) {
    for (int c = 0; c < 3; ++c) dofs.Prescribe(i, c, 0.0);
  }
  dofs.Finalize();
  NewtonOptions options;
  options.stagnation_iterations = stagnation_iterations;
  const auto solver = CreateCholmodSolver(ThreadContext());
  Eigen::VectorXd u = Eigen::VectorXd::Zero(dofs.num_dofs());
  Outcome out;
  out.status = SolveNewtonStatic(
      model, &loads, dofs, options, solver.get(), [](const NewtonProgress&) { return true; }, &u,
      &out.report);
  return out;
}

TEST(NewtonStagnationTest, ALoadTheBodyCannotCarryEndsSayingTheResidualStagnated) {
  const Outcome checked = PullCappedBlock(NewtonOptions().stagnation_iterations);
  const Outcome unchecked = PullCappedBlock(0);
  std::printf("stagnation check: %d iterations, %d stagnations; without: %d iterations\n%s\n",
              checked.report.total_iterations, checked.report.stagnations,
              unchecked.report.total_iterations, checked.status.message().c_str());
  ASSERT_EQ(checked.status.code(), Status::Code::kNumerical);
  EXPECT_NE(checked.status.message().find("the residual stagnated at"), std::string::npos)
      << checked.status.message();
  EXPECT_GT(checked.report.stagnations, 0);
  // Without the check the same load fails too, after every iteration of
  // every cut and without saying why.
  ASSERT_EQ(unchecked.status.code(), Status::Code::kNumerical);
  EXPECT_EQ(unchecked.status.message().find("stagnated"), std::string::npos);
  EXPECT_EQ(unchecked.report.stagnations, 0);
  EXPECT_LT(2 * checked.report.total_iterations, unchecked.report.total_iterations);
}

}  // namespace
}  // namespace pba
