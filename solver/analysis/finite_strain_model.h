// A discretised finite-strain body as Newton's method sees it: internal
// force, stored energy and tangent stiffness at a displacement state, a
// DiscreteBody (assembly/discrete_body.h) with a tangent. The element
// formulation (plain tet4, average nodal pressure tet4, ...) lives behind
// this interface, so the load stepping does not depend on it.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/discrete_body.h"
#include "assembly/dof_map.h"
#include "core/thread_context.h"
#include "mesh/mesh.h"
#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

class HyperelasticMaterial;
class MaterialField;

class FiniteStrainModel : public DiscreteBody {
 public:
  // Internal force of every unknown (full vector, 3 per node) [N] and the
  // stored energy [J] at displacement `u` [m]. Returns false when an element
  // inverts (J <= 0) or a value is not finite.
  virtual bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                             double* energy) const = 0;

  // A rank's share of InternalForce across MPI ranks (see AssemblyOptions::
  // own_nodes): the rows of the nodes flagged in `own` (one flag per node),
  // from the elements that touch them, and zero elsewhere, so that the
  // ranks' shares add up to the whole force, each row from one rank.
  // Returns false as InternalForce does, for the elements it evaluated. The
  // default evaluates the whole force and keeps the share.
  virtual bool InternalForceShare(const Eigen::VectorXd& u, const std::vector<char>& own,
                                  Eigen::VectorXd* force) const;

  // Tangent stiffness on the free unknowns of `dofs` and rhs = -f_int on
  // them at `u` (with options.lift_prescribed, also minus K_fp times the
  // prescribed values of `dofs`). Returns kNumerical when an element is
  // inverted at `u`.
  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override = 0;
  bool has_tangent() const final { return true; }

  // DiscreteBody: InternalForce as a trial (the velocity is not read).
  BodyForce Force(const Eigen::VectorXd& u, const Eigen::VectorXd* v, Eigen::VectorXd* f_int) final;

  // The field whose history this body commits, saves and restores: the
  // analysis's MaterialField (null, the default: none). Only one-point
  // elements keep history (MaterialField), so CommitHistory takes each
  // element's one F at u, on `threads`.
  void KeepHistoryIn(MaterialField* field, const Mesh* mesh, const ThreadContext& threads);
  void CommitHistory(const Eigen::VectorXd& u) final;
  std::vector<double> SaveHistory() const final;
  Status RestoreHistory(const std::vector<double>& values) final;

 private:
  MaterialField* history_ = nullptr;
  const Mesh* history_mesh_ = nullptr;
  ThreadContext history_threads_;
};

// Zeroes the rows (3 per node) of the nodes not flagged in `own`: what a
// rank's share of a force vector keeps.
void KeepRowsOf(const std::vector<char>& own, Eigen::VectorXd* force);

// Plain 4-node tetrahedra, each with its own F (locks when nearly
// incompressible; kept to show the difference). `mesh` and `material` must
// outlive the model.
std::unique_ptr<FiniteStrainModel> MakeTet4Model(const Mesh& mesh,
                                                 const HyperelasticMaterial& material);
// With a material per element, read in its current step at every
// evaluation; `field` must outlive the model. The models' passes run on
// `threads` (the solve's; the default, every thread OpenMP gives).
std::unique_ptr<FiniteStrainModel> MakeTet4Model(const Mesh& mesh, const MaterialField& field,
                                                 const ThreadContext& threads);

// The model of a scene's element (resolved: not kDefault) on `mesh`, which
// must have that element's node layout, with the materials of `field`; the
// one place an element type picks its implicit model. Both must outlive
// the model.
std::unique_ptr<FiniteStrainModel> MakeFiniteStrainModel(ElementType element, const Mesh& mesh,
                                                         const MaterialField& field,
                                                         const ThreadContext& threads);

// The deformation gradient of every 4-node element at `u` (one point each),
// e.g. for MaterialField::Commit.
std::vector<Eigen::Matrix3d> ElementDeformationGradients(const Mesh& mesh, const Eigen::VectorXd& u,
                                                         const ThreadContext& threads);

}  // namespace pba
