// The 10-node quadratic tetrahedron (Abaqus / CalculiX C3D10): shape
// functions, quadrature, small-strain stiffness and the quality measure of a
// curved element. Voigt order xx yy zz yz xz xy with engineering shear
// strains, as for the 4-node tetrahedron (fem/tet4.h).
//
// Node order (C3D10): corners 0..3, then the mid-edge nodes
//   4: edge (0,1)   5: edge (1,2)   6: edge (2,0)
//   7: edge (0,3)   8: edge (1,3)   9: edge (2,3)
// Natural coordinates xi = (r, s, t) on the reference tetrahedron
// r, s, t >= 0, r + s + t <= 1 (volume 1/6), corners 0: (0,0,0), 1: (1,0,0),
// 2: (0,1,0), 3: (0,0,1). With the volume coordinates L0 = 1 - r - s - t,
// L1 = r, L2 = s, L3 = t the shape functions are
//   corner a:        N_a = L_a (2 L_a - 1)
//   edge (a, b):     N   = 4 L_a L_b
// (the quadratic member of the Lagrange family on the simplex; Zienkiewicz,
// Taylor & Zhu, The Finite Element Method: Its Basis and Fundamentals, 7th
// ed., section on tetrahedral elements). The map X(xi) = sum_a N_a(xi) X_a is
// isoparametric, so a mid-edge node off the straight edge curves the element.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fem/tet4.h"

namespace pba {

using Matrix30d = Eigen::Matrix<double, 30, 30>;
using Vector30d = Eigen::Matrix<double, 30, 1>;
// One row per node, in the order above: coordinates [m], or (for gradients)
// the derivatives of N_a with respect to the three coordinates.
using Tet10Nodes = Eigen::Matrix<double, 10, 3>;
using Tet10Vector = Eigen::Matrix<double, 10, 1>;
// Strain-displacement matrix: strain = B u_e, u_e = (u0x u0y u0z u1x ...).
using Tet10BMatrix = Eigen::Matrix<double, 6, 30>;

// Corner pairs of the mid-edge nodes 4..9.
inline constexpr int kTet10Edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

// A point of a rule on the reference tetrahedron; the weights of a rule sum
// to 1/6, its volume.
struct QuadraturePoint {
  Eigen::Vector3d xi;
  double weight = 0;
};

// The 4-point rule exact for polynomials of degree 2 (Hammer, Marlowe &
// Stroud 1956): points at the volume coordinates (a, b, b, b) and their
// permutations, a = (5 + 3 sqrt 5) / 20, b = (5 - sqrt 5) / 20, weights 1/24.
// Used for stiffness and internal force, as C3D10 does.
const std::vector<QuadraturePoint>& Tet10StiffnessRule();

// The fully symmetric 14-point rule exact for degree 5, all weights positive
// (Walkington 2000, "Quadrature on simplices of arbitrary dimension"; one
// point fewer than Keast's 1986 degree-5 rule): orbits of the volume
// coordinates (a, a, b, b) x 6 and (c, c, c, 1 - 3c) x 4 for two values of c.
// For mass matrices and error integrals, whose integrands are of degree 4 on
// a straight-sided element.
const std::vector<QuadraturePoint>& Tet10MassRule();

// N_a(xi), a = 0..9.
Tet10Vector Tet10ShapeFunctions(const Eigen::Vector3d& xi);

// dN_a/dxi_j: row a, column j.
Tet10Nodes Tet10NaturalGradients(const Eigen::Vector3d& xi);

// Gradients of the shape functions with respect to the coordinates of `x`
// (rows dN_a/dX [1/m]) at natural point `xi`; returns det J, J_ij = dX_i/dxi_j
// (positive for a positively oriented element, 6 x volume for a straight one).
// `grad` is left unspecified when det J = 0.
double Tet10Gradients(const Tet10Nodes& x, const Eigen::Vector3d& xi, Tet10Nodes* grad);

// The small-strain B of physical gradients `grad` (rows dN_a/dX).
Tet10BMatrix Tet10StrainDisplacement(const Tet10Nodes& grad);

// Reference-configuration data at the points of Tet10StiffnessRule().
struct Tet10Geometry {
  std::array<Tet10Nodes, 4> grad;  // dN_a/dX at each point [1/m]
  std::array<double, 4> volume{};  // weight x det J: the point's share of volume [m^3]
  double min_jacobian = 0;         // smallest det J at the points; <= 0: inverted
};

Tet10Geometry ComputeTet10Geometry(const Tet10Nodes& x);

// Element stiffness sum_q B_q^T D B_q w_q det J_q (small strain) with the
// 4-point rule, D the 6 x 6 elasticity matrix [Pa]; 30 x 30 in the unknowns
// u_e [N/m].
Matrix30d Tet10Stiffness(const Tet10Nodes& x, const Matrix6d& d);

// Strain (Voigt, engineering shear) at natural point `xi` for element
// displacement `u` (30) [m].
Vector6d Tet10Strain(const Tet10Nodes& x, const Vector30d& u, const Eigen::Vector3d& xi);

// Volume by the 14-point rule [m^3] (exact for any mid-edge positions: det J
// is of degree 3).
double Tet10Volume(const Tet10Nodes& x);

// min det J / max det J over the four corners and the four points of the
// stiffness rule: 1 for a straight-sided element, falling as the edges bend;
// <= 0 means the element is inverted somewhere (-1 when it is inverted
// everywhere, max det J <= 0).
double Tet10JacobianRatio(const Tet10Nodes& x);

}  // namespace pba
