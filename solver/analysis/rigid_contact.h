// Rigid bodies pressed against a face set of the tissue: node-to-rigid-surface
// contact by a penalty augmented with Lagrange multipliers (Uzawa), with
// optional regularised Coulomb friction, added to a FiniteStrainModel as a
// decorator (WithContact) so that Newton's method solves body and contact
// together.
//
// Each node a of the face set carries a tributary reference area A_a and
// sees the rigid surface through a normal gap g_a(x_a) (x_a the current
// position, reference + u) and a unit contact normal n_a on the tissue,
// the body's position being c = position + a motion at amplitude a:
//   FLAT_PUNCH  g = (x - c).d when |(x - c) - ((x - c).d) d| <= radius, else
//               no contact; n = d (d = axis, from the punch face into the
//               tissue);
//   SPHERE      g = |x - c| - radius, n = (x - c) / |x - c|;
//   PLANE       g = (x - c).d, n = d.
// The normal pressure [Pa] is p_a = max(0, lambda_a - penalty g_a), lambda_a
// the node's multiplier (0 to start with), and the contact force on the
// tissue node A_a p_a n_a [N]. It derives from the augmented-Lagrangian
// potential (Wriggers, Computational Contact Mechanics, 2nd ed. 2006, on
// penalty and augmented Lagrangian methods; Laursen, Computational Contact
// and Impact Mechanics, 2002):
//   Pi_a = A_a / (2 penalty) (max(0, lambda_a - penalty g_a)^2 - lambda_a^2),
// which is the plain penalty energy A_a penalty g_a^2 / 2 of a penetrating
// node when lambda_a = 0, and dPi_a/dx_a = -A_a p_a n_a. The contact is
// therefore part of the internal force (f_int gains -A_a p_a n_a; Newton's
// residual is f_ext - f_int) and of the stored energy, so that a line search
// may use it.
//
// The Uzawa loop (Augment) sets lambda_a <- p_a at a converged state as long
// as the deepest penetration exceeds the tolerance; each pass leaves roughly
// the fraction k / (k + penalty) of the previous penetration, k the tissue's
// stiffness per area, so with the default penalty (DefaultContactPenalty)
// one or two passes suffice.
//
// Friction (coefficient mu > 0): a tangential penalty of the same value
// regularises stick, and a return map bounds the tangential traction by
// mu p_N (Wriggers 2006; Laursen 2002, on frictional return maps). Each
// node remembers the point of the rigid body it sticks to (its position
// relative to c, taken at Commit); the elastic slip is the tangential part of the node's position
// relative to that point, g_T = (I - n n^T)((x - c) - s), and the trial
// traction t = -penalty g_T. When |t| > mu p_N the node slides and
// t <- mu p_N t / |t|. At Commit a sliding node's stick point follows so that
// the remaining elastic slip is -t / penalty. Friction is not conservative:
// its force enters InternalForce, but its work does not enter the energy,
// which remains the normal part alone. Its tangent is symmetric, as the
// linear solvers (Cholesky) need: penalty A (I - n n^T) while sticking; while
// sliding (mu p_N / |t_trial|) penalty A (I - n n^T - e e^T), e = t / |t|,
// the symmetric part of the consistent sliding tangent without its
// nonsymmetric normal-to-tangential coupling mu penalty A e n^T (and, on
// the sphere, the turn of the tangent plane). Newton then converges
// linearly, not quadratically, while nodes slide: some 15 to 60 iterations
// per increment where a frictionless one takes 4 (the tangential penalty
// itself for sliding nodes, or mu p_N / |t| (I - n n^T), converge worse).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "analysis/finite_strain_model.h"
#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "mesh/mesh.h"
#include "pba/status.h"
#include "scene/rigid_body.h"

namespace pba {

// Moves `body` along its axis (towards the tissue or back) so that it just
// touches the nearest node of `set` at amplitude 0, no node penetrating:
// the shift s along the axis d that makes the smallest gap zero (a punch:
// the nodes within its radius of its axis; a sphere: the nodes within its
// radius of the line through its centre along d; a plane: every node).
// FailedPrecondition when no node lies in the body's path.
Status PlaceTouching(const Mesh& mesh, const FaceSet& set, RigidBody* body);

// What a contact carries at a state.
struct ContactMeasure {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // on the rigid body [N]
  double area = 0;                                  // reference area of the nodes with p > 0 [m^2]
  double penetration = 0;                           // deepest penetration, max(0, -g) [m]
  int nodes_in_contact = 0;
};

class RigidContact {
 public:
  // `mesh` must outlive the contact; `set` is copied from. `body` must be
  // valid (RigidBody::Validate); its axis is normalised here. penalty
  // [Pa/m] is the contact pressure per metre of penetration, friction the
  // Coulomb coefficient (0: frictionless), tolerance [m] the deepest
  // penetration the Uzawa loop accepts.
  RigidContact(const Mesh& mesh, const FaceSet& set, RigidBody body, double penalty,
               double friction, double tolerance);

  // The body's position for the increment being solved: c = position +
  // amplitude motion.
  void SetAmplitude(double amplitude) { amplitude_ = amplitude; }
  double amplitude() const { return amplitude_; }
  // Continues from another body description (e.g. a new motion from where
  // the body now is); multipliers and stick points are kept. Must be valid.
  void SetBody(RigidBody body);
  const RigidBody& body() const { return body_; }
  // The body's current reference point c [m].
  Eigen::Vector3d Centre() const { return body_.position + amplitude_ * body_.motion; }

  // Adds -(contact force on the tissue) to `f_int` (full length, 3 per node)
  // [N] and the normal contact energy to `*energy` [J] when `energy` is not
  // null.
  void AddInternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* f_int, double* energy) const;

  // Adds the contact tangent d(f_int)/du to the 3 x 3 node blocks of the
  // free unknowns of `dofs` in system->k (entries every element pattern
  // holds), and -f_int of the contact to system->rhs. With
  // options.lift_prescribed, also -K_fp u_p of a node block that has both
  // free and prescribed components. With options.drop_pressure_stiffness,
  // the sphere's curvature term (negative semi-definite) is left out.
  // Frictionless: A (penalty n n^T - (p / r) (I - n n^T)), the second term
  // for the SPHERE only (r = |x - c|; the normal turns as the node moves).
  void AddTangent(const Eigen::VectorXd& u, const DofMap& dofs, LinearSystem* system,
                  const AssemblyOptions& options = AssemblyOptions()) const;

  // Uzawa update at a converged state: when the deepest penetration exceeds
  // the tolerance, lambda_a <- p_a for every node and true (solve again);
  // else false.
  bool Augment(const Eigen::VectorXd& u);

  // Accepts the state `u` of a converged increment: stick points of the
  // friction history (a no-op without friction).
  void Commit(const Eigen::VectorXd& u);

  ContactMeasure Measure(const Eigen::VectorXd& u) const;

  // The state carried from step to step, as flat numbers (a checkpoint):
  // per node its multiplier [Pa], then per node its stick point [m]. Restore
  // fails on a length that does not fit this contact's face set.
  std::vector<double> SaveState() const;
  Status RestoreState(const std::vector<double>& values);

  const std::vector<int>& nodes() const { return nodes_; }
  const std::vector<double>& areas() const { return areas_; }         // [m^2], per node
  const std::vector<double>& multipliers() const { return lambda_; }  // [Pa], per node
  double penalty() const { return penalty_; }
  double friction() const { return friction_; }
  double tolerance() const { return tolerance_; }

 private:
  // The contact of node k (index into nodes_) at `u`.
  struct NodeState {
    bool candidate = false;  // within a punch's radius (always true otherwise)
    double gap = 0;          // g [m]
    double pressure = 0;     // p_N [Pa]
    double distance = 0;     // |x - c| (sphere) [m]
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    Eigen::Vector3d relative = Eigen::Vector3d::Zero();  // x - c [m]
    Eigen::Vector3d traction = Eigen::Vector3d::Zero();  // tangential [Pa]
    double trial_norm = 0;                               // |t_trial| [Pa]
    bool sliding = false;
  };
  NodeState Evaluate(int k, const Eigen::VectorXd& u) const;

  const Mesh& mesh_;
  RigidBody body_;
  double penalty_;
  double friction_;
  double tolerance_;
  double amplitude_ = 0;
  std::vector<int> nodes_;
  std::vector<double> areas_;
  std::vector<double> lambda_;
  std::vector<Eigen::Vector3d> stick_;  // stick point relative to c [m]
};

// `body` with the contacts added: InternalForce and Assemble are the body's
// plus each contact's (AddInternalForce, AddTangent). `body` and the
// contacts must outlive the model; the contacts are read, not changed.
std::unique_ptr<FiniteStrainModel> WithContact(const FiniteStrainModel& body,
                                               std::vector<const RigidContact*> contacts);

// A penalty [Pa/m] for a tissue of initial shear modulus mu [Pa] meshed at
// element size h [m]: factor mu / h. A penalty is a pressure per metre of
// penetration; mu / h is the tissue's own stiffness per area at the scale
// of one element (a pressure mu over a depth h strains it by about one), so
// with factor 100 a penetration is about 1 % of the displacement that the
// same pressure causes across an element, small beside the strain-scaled
// displacement, while the tangent stays well conditioned (its contact
// entries at most ~100 times the elements'); the Uzawa loop removes the
// rest down to the tolerance.
double DefaultContactPenalty(double shear_modulus_pa, double element_size_m,
                             double factor = kImplicitPenaltyFactor);

}  // namespace pba
