// Shape measures of tetrahedra, per element and summarised per region: the
// figures a mesh of the atlas is judged by (aspect ratio and Jacobian ratio
// as in the PBA thesis, section 4.4.1.1) and the dihedral angles a solver's
// conditioning suffers from.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fem/tet10.h"
#include "mesh/mesh.h"

namespace pba {

// Aspect ratio of a tetrahedron, corners one per row (any length unit):
//   A = (sum_{i=1..6} l_i^2 / 6)^{3/2} / (6 sqrt(2) V),
// the cube of the root-mean-square edge over the volume, scaled so that a
// regular tetrahedron gives exactly 1; it grows without bound as the
// element flattens. (The thesis prints the constant as 8.47867; 6 sqrt 2 =
// 8.48528 is the value for which a regular tetrahedron gives 1, the
// property the thesis states; 8.47867 would give 1.00078.) +infinity for a
// flat or inverted tetrahedron (V <= 0).
double TetAspectRatio(const Eigen::Matrix<double, 4, 3>& x);

// Smallest and largest of the six interior dihedral angles [degrees]:
// 70.5288 (arccos 1/3) for all six of a regular tetrahedron; a sliver has
// angles near 0 and 180.
std::array<double, 2> TetDihedralRangeDegrees(const Eigen::Matrix<double, 4, 3>& x);

// Jacobian ratio of a 10-node tetrahedron: max det J / min det J over the
// four corners and the four points of the 4-point rule (the reciprocal of
// Tet10JacobianRatio in fem/tet10.h, same points). 1 for straight edges
// with the mid-edge nodes at their midpoints (det J is then constant), > 1
// as the edges bend; the thesis accepts up to 40. +infinity when det J <= 0
// at one of the points (inverted there).
double Tet10MaxJacobianRatio(const Tet10Nodes& x);

// The measures of one set of elements (a region or the whole mesh).
struct QualityStats {
  int count = 0;  // elements
  // Aspect ratio (TetAspectRatio) of the corners: smallest, median, 99th
  // percentile (the value 99 % of the elements do not exceed: the smallest
  // A with at least ceil(0.99 count) elements at or below it), largest.
  double min_aspect_ratio = 0;
  double median_aspect_ratio = 0;
  double p99_aspect_ratio = 0;
  double max_aspect_ratio = 0;
  // Dihedral angles of the corners' tetrahedra over all elements [degrees].
  double min_dihedral_deg = 0;
  double max_dihedral_deg = 0;
  // Largest Tet10MaxJacobianRatio; 1 for a linear mesh (det J constant).
  double max_jacobian_ratio = 0;
  double volume = 0;  // [m^3]; curved-element volume for a quadratic mesh
};

struct QualitySummary {
  QualityStats overall;
  // regions[r] for region r (Mesh::region_names[r]); empty for a one-region
  // mesh (Mesh::element_region empty).
  std::vector<QualityStats> regions;
};

// The quality of a tetrahedral mesh (4- or 10-node). For a hexahedral mesh
// only `count` and `volume` are filled, the rest stays 0.
QualitySummary Summarise(const Mesh& mesh);

}  // namespace pba
