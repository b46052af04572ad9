// External loads of a static analysis, on the full vector of unknowns (3 per
// node, SI units):
//   - dead nodal forces, fixed in size and direction: surface tractions per
//     unit reference area and body forces such as gravity (rho g per unit
//     reference volume);
//   - pressure on boundary triangles, which in a finite-strain analysis
//     follows the surface as it moves and turns (a follower load: the
//     force acts on the current area along the current normal).
//
// A pressure p > 0 pushes into the body: on a linear triangle with current
// corners x0, x1, x2 numbered anticlockwise seen from outside, each corner
// carries f_a = -(p / 6) (x1 - x0) x (x2 - x0), one third of -p n da
// (Bonet & Wood, Nonlinear Continuum Mechanics for FEA, 2nd ed., 8.4).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "assembly/assembler.h"
#include "assembly/dof_map.h"
#include "mesh/mesh.h"

namespace pba {

class ExternalLoads {
 public:
  // An empty load set of `mesh`, which must outlive it.
  explicit ExternalLoads(const Mesh& mesh);

  // Adds a traction t [Pa] (force per reference area, fixed direction) on
  // the triangles of `set`, lumped to their corners (exact for a linear
  // triangle under a uniform traction).
  void AddTraction(const FaceSet& set, const Eigen::Vector3d& traction_pa);

  // Adds a body force b [N/m^3] (for gravity rho g) over every element,
  // a quarter of b V_e to each corner (exact for a linear tetrahedron).
  void AddBodyForce(const Eigen::Vector3d& force_per_volume);

  // Adds a pressure p [Pa] on the triangles of `set`, a boundary face set of
  // the mesh; each triangle is turned to face out of its tetrahedron. With
  // `follower`, the force follows the deformed surface; otherwise it acts on
  // the reference area along the reference normal (a small-strain analysis).
  void AddPressure(const FaceSet& set, double pressure_pa, bool follower);

  bool empty() const { return dead_.isZero(0) && pressure_.empty(); }
  // True when the force depends on the displacement (follower pressure).
  bool follows_deformation() const;

  // The external force at displacement `u` [m] for load factor 1 [N]
  // (full length, 3 per node).
  Eigen::VectorXd Force(const Eigen::VectorXd& u) const;

  // `factor` times the load stiffness K_L = -d(force)/du at `u`, on the free
  // unknowns of `dofs` (num_free x num_free, both triangles stored). Only
  // follower pressure contributes. K_L of a pressure is not symmetric
  // triangle by triangle; its skew part integrates to terms on the loaded
  // surface's boundary edges, which vanish on a closed surface or where
  // those edges are held or lie in symmetry planes. The symmetric part is
  // returned so that Cholesky applies; elsewhere Newton converges linearly
  // rather than quadratically.
  SparseMatrix Stiffness(const Eigen::VectorXd& u, const DofMap& dofs, double factor) const;

  // The dead part alone (tractions, body forces), full length [N].
  const Eigen::VectorXd& dead_force() const { return dead_; }

  // Total force of the loads at the reference configuration [N], for the
  // summary.
  Eigen::Vector3d ReferenceResultant() const;

 private:
  struct Pressure {
    std::array<int, 3> nodes;  // anticlockwise seen from outside the body
    double pressure_pa;
    bool follower;
  };
  Eigen::Vector3d Corner(int node, const Eigen::VectorXd* u) const;

  const Mesh& mesh_;
  Eigen::VectorXd dead_;
  std::vector<Pressure> pressure_;
};

}  // namespace pba
