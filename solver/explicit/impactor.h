// Rigid impactors of an explicit analysis: bodies whose motion is
// prescribed (Problem::contacts, moved by motion times a(t)), pushing tissue
// nodes out of themselves by a penalty (node-to-rigid-surface).
//
// Geometry, with c the body's current reference point and d its unit axis
// (into the tissue), r = x - c, s = r . d and rho = |r - s d|:
//   CYLINDER_FLAT     inside when s <= 0 and rho <= R; pushed out through
//                     the nearer of the end face (depth -s, normal d) and
//                     the side wall (depth R - rho, radial normal);
//   CYLINDER_ROUNDED  the hemisphere of centre c - R d for s > -R (depth
//                     R - |r + R d|, normal from that centre), the wall
//                     behind it (depth R - rho, radial);
//   FLAT_PUNCH        the end face alone, within the radius (depth -s);
//   SPHERE            depth R - |r|, normal r / |r|;
//   PLANE             depth -s, normal d.
// A node at depth delta > 0 feels k_a delta along the normal. The
// stiffness follows the node's mass and the time step, as LS-DYNA's
// soft-constraint option does (Hallquist, LS-DYNA Theory Manual,
// "contact"): k_a = 0.1 factor m_a / dt^2, so that each contact spring
// oscillates with omega dt = sqrt(0.1 factor), well inside the central
// difference's limit of 2 for factor <= 10; no area enters, so a node
// exposed by erosion is held as well as a surface node.
//
// Energies (kept by the time loop): the body does the work W = -sum F_body
// . dc over the steps (external work); the tissue nodes receive sum f .
// du; the difference is the contact energy (the springs' stored energy and
// any numerical loss).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "pba/status.h"
#include "scene/problem.h"

namespace pba {

struct ImpactorState {
  Eigen::Vector3d force_on_body = Eigen::Vector3d::Zero();  // [N]
  double peak_force = 0;                                    // largest |force| [N]
  double penetration = 0;                                   // deepest node now [m]
  int nodes_in_contact = 0;
};

class Impactor {
 public:
  // From a resolved contact of the problem. `candidates`: the nodes it may
  // push (the contact's set, and every node when elements may erode).
  // `mass`: lumped nodal masses; dt: the step.
  Impactor(const Contact& contact, std::vector<int> candidates, const Eigen::VectorXd& mass,
           double dt);

  // Penetration of point x into the body with reference point c: returns
  // the depth (> 0 inside, else 0) and sets *normal to the outward normal.
  double Depth(const Eigen::Vector3d& c, const Eigen::Vector3d& x, Eigen::Vector3d* normal) const;

  // Adds the contact forces on the tissue nodes at displacement `u` with
  // the body at amplitude `a` to `f` [N]; updates the force on the body.
  // Nodes listed in `skip` (orphans of erosion) are left alone.
  void AddForces(const Mesh& mesh, const Eigen::VectorXd& u, double a,
                 const std::vector<char>& skip, Eigen::VectorXd* f);
  const std::string& name() const { return name_; }
  const ImpactorState& state() const { return state_; }
  // The body's reference point at amplitude a [m].
  Eigen::Vector3d Centre(double a) const { return position_ + a * motion_; }
  double min_stiffness() const { return k_min_; }
  double max_stiffness() const { return k_max_; }
  const std::vector<int>& nodes() const { return nodes_; }

 private:
  std::string name_;
  ContactSpec::Shape shape_;
  Eigen::Vector3d position_, axis_, motion_;
  double radius_ = 0;
  std::vector<int> nodes_;
  std::vector<double> k_;  // per node [N/m]
  double k_min_ = 0, k_max_ = 0;
  ImpactorState state_;
};

}  // namespace pba
