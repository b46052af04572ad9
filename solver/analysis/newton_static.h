// Quasi-static large-deformation equilibrium by Newton-Raphson:
// f_int(u) = lambda f_ext(u) on the free unknowns, the prescribed
// displacements and the external loads ramped linearly from zero to their
// full values in increments of the load factor lambda.
//
// Each increment starts from a linearised predictor (the tangent at the last
// converged state carries the prescribed increment into the free unknowns),
// then iterates with the consistent tangent and a backtracking line search.
// Far from equilibrium a tangent that is not positive definite is replaced by
// a definite one (see newton_static.cc); close to it (relative residual
// <= 1e-4) the iteration steps with the indefinite consistent tangent itself
// (sparse LDL^T), so that it converges quadratically also to an equilibrium
// that is unstable: past a bifurcation the load path follows the fundamental
// branch, and IncrementRecord::negative_eigenvalues says so.
// An increment that inverts an element, stalls or diverges is cut in half and
// retried; one that converges quickly lets the next one grow.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "analysis/finite_strain_model.h"
#include "analysis/step_observer.h"
#include "assembly/dof_map.h"
#include "assembly/external_loads.h"
#include "linear/linear_solver.h"
#include "pba/status.h"

namespace pba {

struct NewtonOptions {
  int initial_increments = 5;
  int max_iterations = 20;  // per increment
  // An iteration has converged when all three hold:
  //   ||R_f|| <= residual_tolerance * max(||f_int||, ||lambda f_ext||)
  //     (f_int on all unknowns, reactions included; R = lambda f_ext - f_int),
  //   ||du|| <= displacement_tolerance * ||u||,
  //   |du . R| <= energy_tolerance * |du_p . K du_p| (du_p: the increment's predictor).
  // When the energy ratio is below 1e-20 the correction is rounding noise and
  // the residual and displacement tests are waived: their floors (~1e-8 for
  // K / mu = 1e6) are then reported as the increment's final residual.
  double residual_tolerance = 1e-8;
  double displacement_tolerance = 1e-8;
  double energy_tolerance = 1e-12;
  double min_increment = 1e-4;  // smallest load-factor increment before giving up
  double max_increment = 0.5;   // largest load-factor increment when growing
  int quick_iterations = 4;     // an increment this quick lets the next grow 1.5x
  bool line_search = true;
  // An attempt whose last this-many iterations together lowered the
  // relative residual by less than 5 % has stagnated (at that pace its
  // budget could not converge): it ends at once, as one that does not
  // converge, saying so, and the increment is cut; an unbalanceable load,
  // a singular or inconsistent system would otherwise spend every
  // iteration of every cut at full cost. 0: never.
  int stagnation_iterations = 5;
  // Called with each converged increment's load factor and full displacement.
  std::function<void(double load_factor, const Eigen::VectorXd& u)> on_increment;

  // For analyses through time (the load factor is then t / T):
  // The scale of the prescribed values and loads at a load factor, a(lambda)
  // (a time curve); unset: a(lambda) = lambda.
  std::function<double(double load_factor)> amplitude;
  // Called before every attempt of an increment from the converged `from`
  // to `to` (again with a smaller `to` after a cut), e.g. to set a
  // viscoelastic model's time step or a rigid body's position; an error
  // stops the solve with it.
  std::function<Status(double from, double to)> begin_increment;
  // Called when an increment has converged, before it is accepted; true
  // asks for more iterations of the same increment from that state (a
  // contact's multipliers changed). At most max_augmentations times per
  // increment.
  std::function<bool(const Eigen::VectorXd& u)> augment;
  int max_augmentations = 10;
  // The largest increment allowed from a converged load factor (a corner of
  // the time curve, a relaxation time); unset: max_increment. Never below
  // min_increment.
  std::function<double(double load_factor)> max_increment_at;
  // Start from this load factor and state instead of 0 and u = 0 (a
  // restart); the state must be converged at start_load.
  double start_load = 0;
  Eigen::VectorXd start_u;
  // The size of the first increment (load factor); 0: 1 / initial_increments.
  // A restart passes the next_step its checkpoint was written with, so that
  // it takes the steps the uninterrupted solve would.
  double start_step = 0;
  // Told after on_increment (analysis/step_observer.h): step = the
  // increments converged, time_s = fraction = the load factor, next_step =
  // the size of the increment to be tried next, u = the state (e.g. to
  // write a checkpoint); an error stops the solve with it. Null: none.
  StepObservers* observers = nullptr;
};

struct IncrementRecord {
  double load_factor = 0;  // at the end of the increment
  double step = 0;         // its size (load factor)
  int iterations = 0;
  double relative_residual = 0;
  // Negative eigenvalues of the tangent of the last iteration (close to the
  // converged state): 0 when Cholesky succeeded, the count of negative LDL^T
  // pivots when it did not, -1 when that iteration used an approximate tangent.
  int negative_eigenvalues = 0;
};

struct NewtonReport {
  std::vector<IncrementRecord> increments;  // converged ones
  int total_iterations = 0;
  int cuts = 0;         // increments cut back and retried
  int stagnations = 0;  // attempts ended because the residual stagnated (stagnation_iterations)
  // Iterations whose consistent tangent was not positive definite and that
  // used the tangent without pressure initial-stress terms instead, or
  // (modified) an earlier positive definite tangent.
  int approximate_iterations = 0;
  int modified_iterations = 0;
  // Iterations close to equilibrium whose consistent tangent was not
  // positive definite and that stepped with it all the same (LDL^T).
  int indefinite_iterations = 0;
  int augmentations = 0;                 // times `augment` asked for more iterations
  std::vector<std::string> cut_reasons;  // why each cut happened
  // Wall time [s] spent assembling tangents, in factorisations and solves,
  // and evaluating residuals (line search included).
  double assembly_s = 0;
  double linear_solve_s = 0;
  double residual_s = 0;
  // Tangents assembled, and of them those assembled partitioned between MPI
  // ranks (AssemblyOptions::own_nodes).
  int tangents = 0;
  int partitioned_tangents = 0;
};

// Where the solve is, for progress reports and cancellation.
struct NewtonProgress {
  double load_factor = 0;  // last converged
  int iteration = 0;       // within the current increment; 0 = its predictor
  double relative_residual = 0;
};

// Solves for the full displacement vector `u` (3 per node, metres). The
// targets of the prescribed unknowns are taken from `dofs`.
// `keep_going` is polled before every iteration; returning false
// stops with kCancelled. Returns kNumerical naming the load factor reached
// and the last failure when the increments cannot be cut any further.
Status SolveNewtonStatic(const FiniteStrainModel& model, const DofMap& dofs,
                         const NewtonOptions& options, LinearSolver* solver,
                         const std::function<bool(const NewtonProgress&)>& keep_going,
                         Eigen::VectorXd* u, NewtonReport* report);

// The same with external loads (tractions, body forces, follower pressure),
// ramped with the load factor; `loads` may be null.
Status SolveNewtonStatic(const FiniteStrainModel& model, const ExternalLoads* loads,
                         const DofMap& dofs, const NewtonOptions& options, LinearSolver* solver,
                         const std::function<bool(const NewtonProgress&)>& keep_going,
                         Eigen::VectorXd* u, NewtonReport* report);

}  // namespace pba
