// The central-difference step and the energy balance on their own
// (explicit/central_difference.h, explicit/energy_balance.h), against
// closed-form motions of a single lumped mass.
#include "explicit/central_difference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "explicit/energy_balance.h"

namespace pba {
namespace {

struct Particle {
  Eigen::VectorXd mass = Eigen::VectorXd::Constant(1, 2.0);  // one node, 2 kg
  std::vector<PrescribedDof> prescribed = std::vector<PrescribedDof>(3);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3), v = Eigen::VectorXd::Zero(3);
  Eigen::VectorXd f_int = Eigen::VectorXd::Zero(3), f_ext = Eigen::VectorXd::Zero(3),
                  f_contact = Eigen::VectorXd::Zero(3);
};

// A constant force: central differences are exact for constant
// acceleration, u(t) = a t^2 / 2 at every step, and the balance holds to
// rounding (kinetic energy = work of the force).
TEST(CentralDifferenceTest, AConstantForceGivesTheExactParabola) {
  Particle p;
  p.f_ext(2) = 4.0;  // a = 2 m/s^2
  const CentralDifference step(p.mass, p.prescribed, 0.0, ThreadContext(1));
  Energies energy;
  const double dt = 0.1;
  double t = 0, dt_prev = 0;
  for (int n = 0; n < 50; ++n) {
    const StepWork work =
        step.Advance({&p.f_int, &p.f_ext, &p.f_contact}, {dt_prev, dt, 1, 1}, {}, &p.u, &p.v);
    ASSERT_TRUE(work.finite);
    energy.Add(work);
    // The balance at t^n (from the second step on: the first one's mean
    // of the half steps starts from v^(-1/2) = v(0)).
    if (n > 0) {
      EXPECT_NEAR(energy.Error(), 0, 1e-12 * std::max(1.0, energy.Scale())) << n;
      EXPECT_NEAR(energy.kinetic, 0.5 * 2.0 * (2.0 * t) * (2.0 * t), 1e-12) << n;
    }
    t += dt;
    dt_prev = dt;
    EXPECT_NEAR(p.u(2), 0.5 * 2.0 * t * t, 1e-12) << n;
    EXPECT_NEAR(p.v(2), 2.0 * (t - 0.5 * dt), 1e-12) << n;  // the half-step velocity
  }
  EXPECT_EQ(p.u(0), 0);
  EXPECT_EQ(p.u(1), 0);
}

// Mass-proportional damping alone: the velocity decays as exp(-alpha t) to
// second order in the step, and the damping work takes the kinetic energy
// lost.
TEST(CentralDifferenceTest, DampingTakesTheKineticEnergy) {
  Particle p;
  p.v(0) = 1.0;
  const double alpha = 5.0, dt = 1e-3;
  const CentralDifference step(p.mass, p.prescribed, alpha, ThreadContext(1));
  Energies energy;
  energy.initial_kinetic = 0.5 * 2.0 * 1.0;
  double t = 0, dt_prev = 0;
  for (int n = 0; n < 400; ++n) {
    energy.Add(
        step.Advance({&p.f_int, &p.f_ext, &p.f_contact}, {dt_prev, dt, 1, 1}, {}, &p.u, &p.v));
    t += dt;
    dt_prev = dt;
  }
  // v^(n+1/2) at t - dt / 2.
  EXPECT_NEAR(p.v(0), std::exp(-alpha * (t - 0.5 * dt)), 1e-4);
  EXPECT_GT(energy.damping.total, 0.9 * energy.initial_kinetic * (1 - std::exp(-2 * alpha * t)));
  EXPECT_LT(energy.Error(), 1e-3 * energy.initial_kinetic);
}

// A prescribed displacement is followed exactly, and the force that holds
// it is counted as external work; an orphan node stands still.
TEST(CentralDifferenceTest, PrescribedMotionAndOrphansFollowTheirRules) {
  Particle p;
  p.prescribed[2] = {PrescribedDof::kDisplacement, 0.5};  // u_z = 0.5 a(t)
  p.f_ext(0) = 1.0;
  const CentralDifference step(p.mass, p.prescribed, 0.0, ThreadContext(1));
  const StepWork work =
      step.Advance({&p.f_int, &p.f_ext, &p.f_contact}, {0, 0.1, 0.5, 0.8}, {}, &p.u, &p.v);
  EXPECT_DOUBLE_EQ(p.u(2), 0.5 * 0.8);  // at a(t^(n+1))
  EXPECT_GT(work.external_after, 0);    // the holding force did work on the way
  EXPECT_GT(p.u(0), 0);

  Particle q;
  q.f_ext(0) = 1.0;
  const CentralDifference free_step(q.mass, q.prescribed, 0.0, ThreadContext(1));
  free_step.Advance({&q.f_int, &q.f_ext, &q.f_contact}, {0, 0.1, 1, 1}, {1}, &q.u, &q.v);
  EXPECT_EQ(q.u(0), 0);  // the node is an orphan: no element holds it
  EXPECT_EQ(q.v(0), 0);
}

}  // namespace
}  // namespace pba
