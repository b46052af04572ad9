// The static analyses SolveProblem dispatches to. Each fills the element
// fields of `solution` and the analysis-specific parts of its summary, and
// returns the displacement and internal force from which SolveScene derives
// the shared results (nodal fields, reactions, maxima).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/phase_clock.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

struct StaticResult {
  Eigen::VectorXd u;               // full displacement [m]
  Eigen::VectorXd internal_force;  // full internal force [N]
  // Full external force at the solution [N] (empty when there are no loads);
  // the reactions are internal_force - external_force on held unknowns.
  Eigen::VectorXd external_force;
  double strain_energy_j = 0;
  double max_strain = 0;  // largest strain component magnitude
};

// Small-strain linear elasticity, K u = f (hyperelastic models enter with
// their initial moduli).
Status SolveLinearStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                         StaticResult* result);

// Finite strain, total Lagrangian, Newton-Raphson with load stepping.
Status SolveNonlinearStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                            StaticResult* result);

// Finite strain through time (problem.time): loads, motions and
// growth follow the time curve, viscoelastic materials relax, rigid bodies
// touch the tissue; every converged step goes into the history.
Status SolveQuasiStatic(const Problem& problem, PhaseClock* clock, Solution* solution,
                        StaticResult* result);

}  // namespace pba
