// The 8-node trilinear hexahedron (Abaqus C3D8 / VTK_HEXAHEDRON): shape
// functions, the 2 x 2 x 2 Gauss rule, and the small-strain stiffness with
// the B-bar mean-dilatation treatment of the volumetric strain. Voigt order
// xx yy zz yz xz xy with engineering shear strains, as for the tetrahedra
// (fem/tet4.h, fem/tet10.h).
//
// Node order (C3D8): 0-1-2-3 one face, counter-clockwise seen from the
// side of the opposite face 4-7, node 4 + i across from node i. Natural coordinates xi = (r, s, t)
// in the cube [-1, 1]^3 (volume 8), nodes at
//   0: (-1,-1,-1)  1: ( 1,-1,-1)  2: ( 1, 1,-1)  3: (-1, 1,-1)
//   4: (-1,-1, 1)  5: ( 1,-1, 1)  6: ( 1, 1, 1)  7: (-1, 1, 1)
// and the trilinear shape functions
//   N_a = (1 + r r_a)(1 + s s_a)(1 + t t_a) / 8
// (Zienkiewicz, Taylor & Zhu, The Finite Element Method: Its Basis and
// Fundamentals, 7th ed., section on Lagrange elements in three dimensions).
// The map X(xi) = sum_a N_a(xi) X_a is isoparametric; a positively oriented
// element has det J > 0 (the nodes above map to a right-handed brick).
//
// Volumetric locking: with 8 points the fully integrated element has 8
// volume constraints for its 24 - 6 = 18 deformation modes, so a nearly
// incompressible material (nu -> 1/2) stiffens it without limit. B-bar
// (Hughes 1980, "Generalization of selective integration procedures to
// anisotropic and nonlinear media", IJNME 15:1413) keeps one: at every point
// the volumetric part of B is replaced by its element mean,
//   B_bar = B - B_vol + mean(B_vol),  B_vol = (1/3) m m^T B,  m = (1 1 1 0 0 0)^T,
// mean(.) = (1/V) sum_q (.) w_q det J_q. It is valid for any 6 x 6 D, and
// the stiffness stays symmetric: K = sum_q B_bar^T D B_bar w_q det J_q.
// The plain, fully integrated element (Hex8StiffnessFull, Hex8StrainFull) is
// kept beside it: to show the locking, and to compare with codes whose C3D8
// is the plain brick (Abaqus, CalculiX). On a uniform strain the two agree.
#pragma once

#include <Eigen/Core>
#include <array>

#include "fem/tet4.h"

namespace pba {

using Matrix24d = Eigen::Matrix<double, 24, 24>;
using Vector24d = Eigen::Matrix<double, 24, 1>;
// One row per node, in the order above: coordinates [m], or (for gradients)
// the derivatives of N_a with respect to the three coordinates.
using Hex8Nodes = Eigen::Matrix<double, 8, 3>;
using Hex8Vector = Eigen::Matrix<double, 8, 1>;
// Strain-displacement matrix: strain = B u_e, u_e = (u0x u0y u0z u1x ...).
using Hex8BMatrix = Eigen::Matrix<double, 6, 24>;

// Natural coordinates of the nodes, row a = (r_a, s_a, t_a).
inline constexpr double kHex8NodeNatural[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1},
                                                  {-1, 1, -1},  {-1, -1, 1}, {1, -1, 1},
                                                  {1, 1, 1},    {-1, 1, 1}};

// A point of a rule on the cube [-1, 1]^3; the weights sum to 8.
struct Hex8QuadraturePoint {
  Eigen::Vector3d xi;
  double weight = 0;
};

// The 2 x 2 x 2 Gauss-Legendre product rule: points (+-1/sqrt 3)^3, weights
// 1, in the node order above (point q nearest node q). Exact for
// polynomials of degree 3 in each coordinate separately, so for the product
// of two trilinear functions and for det J of any trilinear brick (degree 2
// in each coordinate).
const std::array<Hex8QuadraturePoint, 8>& Hex8Rule();

// N_a(xi), a = 0..7.
Hex8Vector Hex8ShapeFunctions(const Eigen::Vector3d& xi);

// dN_a/dxi_j: row a, column j.
Hex8Nodes Hex8NaturalGradients(const Eigen::Vector3d& xi);

// Gradients of the shape functions with respect to the coordinates of `x`
// (rows dN_a/dX [1/m]) at natural point `xi`; returns det J,
// J_ij = dX_i/dxi_j (positive for a positively oriented element; V / 8 for
// a parallelepiped of volume V). `grad` is left unspecified when det J = 0.
double Hex8Gradients(const Hex8Nodes& x, const Eigen::Vector3d& xi, Hex8Nodes* grad);

// The plain small-strain B of physical gradients `grad` (rows dN_a/dX).
Hex8BMatrix Hex8StrainDisplacement(const Hex8Nodes& grad);

// B_bar of the header: B of `grad` with its volumetric part replaced by that
// of the element-mean gradients `mean_grad` (Hex8Geometry::mean_grad).
Hex8BMatrix Hex8StrainDisplacementBar(const Hex8Nodes& grad, const Hex8Nodes& mean_grad);

// Reference-configuration data at the points of Hex8Rule().
struct Hex8Geometry {
  std::array<Hex8Nodes, 8> grad;   // dN_a/dX at each point [1/m]
  std::array<double, 8> volume{};  // weight x det J: the point's share of volume [m^3]
  double element_volume = 0;       // sum of `volume` (exact for a trilinear brick) [m^3]
  // (1/V) sum_q grad[q] volume[q]: dN_a/dX averaged over the element [1/m];
  // its divergence row is the mean volumetric strain of B_bar.
  Hex8Nodes mean_grad = Hex8Nodes::Zero();
  double min_jacobian = 0;  // smallest det J at the points; <= 0: inverted
};

Hex8Geometry ComputeHex8Geometry(const Hex8Nodes& x);

// Element stiffness sum_q B_bar,q^T D B_bar,q |w_q det J_q| (small strain,
// B-bar mean dilatation) with the 2 x 2 x 2 rule, D the 6 x 6 elasticity
// matrix [Pa]; 24 x 24 in the unknowns u_e [N/m].
Matrix24d Hex8Stiffness(const Hex8Nodes& x, const Matrix6d& d);

// B-bar strain (Voigt, engineering shear) at natural point `xi` for element
// displacement `u` (24) [m]: the deviatoric part of the strain at xi, the
// volumetric part the element mean. NaN when det J = 0 at xi.
Vector6d Hex8Strain(const Hex8Nodes& x, const Vector24d& u, const Eigen::Vector3d& xi);

// The fully integrated (C3D8) stiffness sum_q B_q^T D B_q |w_q det J_q|
// with the plain B of every point: no mean dilatation, so it locks as
// nu -> 1/2 [N/m], 24 x 24 as Hex8Stiffness.
Matrix24d Hex8StiffnessFull(const Hex8Nodes& x, const Matrix6d& d);

// The plain strain B(xi) u at natural point `xi` (Voigt, engineering shear),
// the strain of the fully integrated element. NaN when det J = 0 at xi.
Vector6d Hex8StrainFull(const Hex8Nodes& x, const Vector24d& u, const Eigen::Vector3d& xi);

// Volume by the 2 x 2 x 2 rule [m^3], exact for any trilinear brick.
double Hex8Volume(const Hex8Nodes& x);

// min det J / max det J over the eight corners and the eight Gauss points:
// 1 for a parallelepiped, falling as the element is tapered or warped;
// <= 0 means it is inverted somewhere (-1 when max det J <= 0).
double Hex8JacobianRatio(const Hex8Nodes& x);

}  // namespace pba
