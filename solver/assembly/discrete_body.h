// A discretised body as the integrators see it: the one seam between the
// element models and the analyses that move them (Newton's method, the
// central difference, dynamic relaxation), in the manner of MFEM's
// operators. A body gives
//   - its internal force f_int(u, v) and stored energy,
//   - its tangent stiffness, where it has one (the implicit models),
//   - its lumped mass, where it has densities (the explicit engine),
//   - its element fields (strain, stress) at a state,
//   - its history (relaxation): commit at the end of a step, save, restore.
// Implementations: FiniteStrainModel (analysis/finite_strain_model.h: TET4,
// TET4_ANP, TET10, TET10_MD, HEX8, HEX8_FULL with a tangent) and TledModel
// (explicit/tled_model.h: TET4, TET4_ANP, one-point HEX8 with a lumped
// mass). Both evaluate their materials through one material-point kernel
// (material/material_point.h); discrete_body_test checks that the two give
// the same forces where their elements are the same.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "pba/solve.h"
#include "pba/status.h"

namespace pba {

// What one evaluation of the internal force found.
struct BodyForce {
  // Every element admissible (det F > 0) and every value finite.
  bool ok = true;
  // The lowest inverted element when the body knows it; -1 otherwise.
  int inverted_element = -1;
  double energy = 0;            // stored energy at the state [J]
  double hourglass_energy = 0;  // of one-point bricks' hourglass control [J]
};

class DiscreteBody {
 public:
  virtual ~DiscreteBody() = default;

  // For the summary, e.g. "TET4_ANP, total Lagrangian".
  virtual std::string Describe() const = 0;

  // The internal force at displacement `u` [m] and velocity `v` [m/s]
  // (null: at rest; only rate terms, such as a bulk viscosity, read it),
  // full length, 3 per node [N], and the stored energy. A body whose
  // history advances with every evaluation (advances_on_evaluation(): the
  // explicit engine, each evaluation one time step) moves its history to
  // this state; any other evaluates a trial, which CommitHistory accepts.
  virtual BodyForce Force(const Eigen::VectorXd& u, const Eigen::VectorXd* v,
                          Eigen::VectorXd* f_int) = 0;
  virtual bool advances_on_evaluation() const { return false; }

  // The tangent stiffness on the free unknowns of `dofs` and rhs = -f_int
  // at `u` (see FiniteStrainModel::Assemble); kFailedPrecondition for a
  // body without one.
  virtual bool has_tangent() const { return false; }
  virtual Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs,
                          const AssemblyOptions& options, LinearSystem* system) const {
    return Status::FailedPrecondition(Describe() + " has no tangent stiffness");
  }

  // The element fields at `u` into `solution` (per element: Green-Lagrange
  // and Almansi strain, second Piola-Kirchhoff and Cauchy stress, von Mises,
  // J; the means over its integration points); returns the largest
  // Green-Lagrange component. A body that advances on evaluation gives
  // those of its last evaluation, which must have been at `u` (with its
  // stress recorded: TledModel::RecordStress).
  virtual double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const = 0;

  // Lumped mass per node [kg]; empty for a body without densities.
  virtual Eigen::VectorXd LumpedMass() const { return Eigen::VectorXd(); }

  // Accepts the state at `u` as the end of a step (a body that advances on
  // evaluation has already done so, and ignores it).
  virtual void CommitHistory(const Eigen::VectorXd& u) {}
  // The history as flat numbers (a restart file) and back; Restore fails
  // on a length that does not fit the body.
  virtual std::vector<double> SaveHistory() const { return {}; }
  virtual Status RestoreHistory(const std::vector<double>& values) {
    if (values.empty()) return Status::Ok();
    return Status::InvalidArgument("history", Describe() + " keeps no history, was given " +
                                                  std::to_string(values.size()) + " numbers");
  }
};

}  // namespace pba
