// External loads of a static analysis, on the full vector of unknowns (3 per
// node, SI units):
//   - dead nodal forces, fixed in size and direction: surface tractions per
//     unit reference area and body forces such as gravity (rho g per unit
//     reference volume);
//   - pressure on boundary triangles or quads, which in a finite-strain analysis
//     follows the surface as it moves and turns (a follower load: the
//     force acts on the current area along the current normal).
//
// A pressure p > 0 pushes into the body: on a linear triangle with current
// corners x0, x1, x2 numbered anticlockwise seen from outside, each corner
// carries f_a = -(p / 6) (x1 - x0) x (x2 - x0), one third of -p n da
// (Bonet & Wood, Nonlinear Continuum Mechanics for FEA, 2nd ed., 8.4).
//
// On a 10-node mesh (Mesh::shape() kTet10) a boundary triangle has six
// nodes, corners 0..2 then the mid-edge nodes of edges (0,1), (1,2), (2,0),
// and its surface is the isoparametric map x(xi, eta) = sum_a N_a x_a over
// xi, eta >= 0, xi + eta <= 1: with L0 = 1 - xi - eta, L1 = xi, L2 = eta,
// corner N_a = L_a (2 L_a - 1), mid-edge N = 4 L_a L_b (the quadratic
// triangle of the Lagrange family; Zienkiewicz, Taylor & Zhu, The Finite
// Element Method: Its Basis and Fundamentals, 7th ed.), curved where the
// mid-edge nodes lie off the straight edges. With g1 = x_,xi, g2 = x_,eta
// (current x for a follower pressure, reference X otherwise) and G1, G2 the
// same on the reference surface, the loads are consistent, not lumped:
//   traction     f_a = t  integral N_a |G1 x G2| dxi deta,
//   pressure     f_a = -p integral N_a (g1 x g2) dxi deta  (Bonet & Wood 8.4),
//   body force   f_a = b  integral N_a det J dr ds dt  (the 10-node map of
//                fem/tet10.h, over the reference tetrahedron).
// A flat triangle under a uniform traction t thus gives nothing to its
// corners and t A/3 to each mid-edge node; a straight element gives -b V/20
// to each corner and b V/5 to each mid-edge node. The surface integrals use
// the 7-point rule of degree 5 (Radon 1948; Dunavant 1985, IJNME 21), exact
// for pressure, whose integrand is of degree 4; the volume integral the
// 14-point rule of degree 5, exact as N_a det J is of degree 5.
//
// On a hexahedral mesh (Mesh::shape() kHex8) a boundary face is a bilinear
// quad, nodes 0..3 at natural (xi, eta) = (-1,-1), (1,-1), (1,1), (-1,1),
// N_a = (1 + xi xi_a)(1 + eta eta_a) / 4 over [-1, 1]^2, and an element
// the trilinear brick of Mesh::hexes, N_a = (1 + xi xi_a)(1 + eta eta_a)
// (1 + zeta zeta_a) / 8. The same consistent integrals apply, traction and
// pressure over the quad, body force over the brick, by Gauss rules of 2
// points per direction (exact for cubics in each coordinate):
//   - pressure: g1 = x_,xi is linear in eta alone and g2 = x_,eta in xi
//     alone, so N_a (g1 x g2) is at most quadratic in each and 2 x 2
//     points are exact, warped (non-planar) quads included; the result is
//     the quad's vector area shared among its nodes, a quarter each on a
//     flat parallelogram;
//   - traction: |G1 x G2| is constant on a flat parallelogram, where each
//     node gets t A/4 exactly; on other quads the rule is an approximation;
//   - body force: each column of J is constant along its own coordinate, so
//     det J and N_a det J are at most quadratic and cubic in each, and
//     2 x 2 x 2 points are exact (b V/8 per node on a parallelepiped).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
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
  // triangle under a uniform traction); on a quadratic mesh the consistent
  // load over the reference (possibly curved) 6-node triangles, their
  // mid-edge nodes found as for AddPressure; and on the quads of `set` the
  // consistent load over the reference bilinear surface.
  void AddTraction(const FaceSet& set, const Eigen::Vector3d& traction_pa);

  // Adds a body force b [N/m^3] (for gravity rho g) over every element,
  // a quarter of b V_e to each corner (exact for a linear tetrahedron); on a
  // quadratic mesh the consistent load of each 10-node element, on a
  // hexahedral one that of each trilinear brick.
  void AddBodyForce(const Eigen::Vector3d& force_per_volume);

  // Adds a body force that varies in space, b(X) [N/m^3] at reference
  // position X [m] (e.g. a manufactured solution's), integrated against the
  // shape functions with a rule of degree 5.
  using BodyForceField = std::function<Eigen::Vector3d(const Eigen::Vector3d& position)>;
  void AddBodyForceField(const BodyForceField& force_per_volume);
  // The same with the element known, b(X, e) (e.g. a density per region).
  using ElementBodyForceField =
      std::function<Eigen::Vector3d(const Eigen::Vector3d& position, int element)>;
  void AddElementBodyForceField(const ElementBodyForceField& force_per_volume);

  // Adds a pressure p [Pa] on the triangles of `set`, a boundary face set of
  // the mesh; each triangle is turned to face out of its tetrahedron. With
  // `follower`, the force follows the deformed surface; otherwise it acts on
  // the reference area along the reference normal (a small-strain analysis).
  // On a quadratic mesh the mid-edge nodes come from set.triangle_midside,
  // or, when that is empty (a set assembled by hand), from the element
  // behind each triangle. The quads of `set` likewise each face out of the
  // brick behind them (QuadFaceElements); a triangle or quad that is no
  // element's face is taken as numbered, anticlockwise seen from outside.
  void AddPressure(const FaceSet& set, double pressure_pa, bool follower);

  bool empty() const { return dead_.isZero(0) && pressure_.empty() && quad_pressure_.empty(); }
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
  //
  // On a 6-node triangle, from f_a above and d(g1 x g2) = dg1 x g2 +
  // g1 x dg2 = (N_b,eta [g1]_x - N_b,xi [g2]_x) dx_b ([w]_x: y -> w x y),
  //   K_L(a, b) = p integral N_a (N_b,eta [g1]_x - N_b,xi [g2]_x) dxi deta,
  // and its symmetric part (K_L(a, b) + K_L(b, a)^T) / 2 is [v_ab]_x with
  //   v_ab = (p / 2) integral (N_a N_b,eta - N_b N_a,eta) g1
  //                          - (N_a N_b,xi  - N_b N_a,xi ) g2 dxi deta,
  // a degree-4 integrand, integrated exactly. On a bilinear quad the same
  // with its N_a, the integrand at most quadratic in each coordinate and
  // the 2 x 2 Gauss rule exact.
  SparseMatrix Stiffness(const Eigen::VectorXd& u, const DofMap& dofs, double factor) const;

  // The dead part alone (tractions, body forces), full length [N].
  const Eigen::VectorXd& dead_force() const { return dead_; }

  // Total force of the loads at the reference configuration [N], for the
  // summary.
  Eigen::Vector3d ReferenceResultant() const;

 private:
  struct Pressure {
    std::array<int, 3> nodes;  // anticlockwise seen from outside the body
    // Quadratic mesh only: the mid-edge nodes of edges (0,1), (1,2), (2,0)
    // of `nodes`.
    std::array<int, 3> midside;
    double pressure_pa;
    bool follower;
  };
  // Pressure on a bilinear quad of a hexahedral mesh.
  struct QuadPressure {
    std::array<int, 4> nodes;  // anticlockwise seen from outside the body
    double pressure_pa;
    bool follower;
  };
  // Position of `node` [m], in the reference configuration when `u` is null.
  Eigen::Vector3d Position(int node, const Eigen::VectorXd* u) const;

  const Mesh& mesh_;
  // The kind of the mesh's boundary faces, from its shape: whether a
  // triangle is loaded as a 3-node or a 6-node one.
  const BoundaryFace face_;
  Eigen::VectorXd dead_;
  std::vector<Pressure> pressure_;
  std::vector<QuadPressure> quad_pressure_;
};

}  // namespace pba
