// The central-difference step of explicit dynamics, on its own: given the
// forces at t^n, the velocities move to t^(n+1/2) and the displacements to
// t^(n+1), with lumped masses, mass-proportional damping and the prescribed
// motion, and the step's share of every work comes back for the energy
// balance (explicit/energy_balance.h). The time loop around it
// (explicit/explicit_dynamics.cc) computes the forces and decides the step.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/thread_context.h"
#include "explicit/explicit_setup.h"

namespace pba {

// The forces at t^n [N], one entry per unknown.
struct StepForces {
  const Eigen::VectorXd* internal = nullptr;
  const Eigen::VectorXd* external = nullptr;
  const Eigen::VectorXd* contact = nullptr;
};

// The times around t^n: dt_prev = t^n - t^(n-1), dt_next = t^(n+1) - t^n
// [s], and the load amplitude at t^n + dt_next / 2 and at t^(n+1).
struct StepTimes {
  double dt_prev = 0, dt_next = 0;
  double amplitude_half = 0, amplitude_next = 0;
};

// Each work over the step as the two halves of the trapezoidal rule:
// *_before = f^n . du^(n-1/2) / 2, *_after = f^n . du^(n+1/2) / 2 [J];
// kinetic the energy at t^n from the mean of the half-step velocities.
struct StepWork {
  double internal_before = 0, internal_after = 0;
  double external_before = 0, external_after = 0;  // loads and reactions
  double damping_before = 0, damping_after = 0;
  double contact_before = 0, contact_after = 0;
  double kinetic = 0;
  bool finite = true;  // every new velocity is finite
};

class CentralDifference {
 public:
  // node_mass: lumped mass per node [kg]; prescribed: how each unknown
  // moves at amplitude 1; damping: mass-proportional alpha [1/s]; a step
  // runs on `threads`. The references must outlive the integrator.
  CentralDifference(const Eigen::VectorXd& node_mass, const std::vector<PrescribedDof>& prescribed,
                    double damping, const ThreadContext& threads);

  // One step: v^(n-1/2) -> v^(n+1/2) and u^n -> u^(n+1) in place. A node
  // marked in `orphan` (when not empty) no longer belongs to any element
  // and stands still.
  StepWork Advance(const StepForces& forces, const StepTimes& times,
                   const std::vector<char>& orphan, Eigen::VectorXd* u, Eigen::VectorXd* v) const;

 private:
  const Eigen::VectorXd& node_mass_;
  const std::vector<PrescribedDof>& prescribed_;
  double damping_;
  ThreadContext threads_;
};

}  // namespace pba
