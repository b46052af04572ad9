// Mesh: nodes, linear tetrahedra and named boundary face sets.
// Coordinates in metres (SI inside the solver).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace pba {

// A named part of the boundary: its triangles and the nodes they touch.
struct FaceSet {
  std::vector<std::array<int, 3>> triangles;  // node indices
  // Quadratic mesh only (else empty): the mid-edge nodes of each triangle,
  // on its edges (0,1), (1,2), (2,0).
  std::vector<std::array<int, 3>> triangle_midside;
  std::vector<int> nodes;  // sorted, unique; mid-edge nodes included
};

struct Mesh {
  // nodes x 3 [m]
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> nodes;
  // Positively oriented 4-node tetrahedra (node indices); for a quadratic
  // mesh their corners.
  std::vector<std::array<int, 4>> tets;
  // Quadratic mesh only (else empty): the mid-edge nodes of each tet, in the
  // Abaqus / CalculiX C3D10 order: edges (0,1), (1,2), (2,0), (0,3), (1,3),
  // (2,3) of tets[e] (see mesh/quadratic.h, fem/tet10.h).
  std::vector<std::array<int, 6>> midside;
  std::map<std::string, FaceSet> face_sets;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_elements() const { return static_cast<int>(tets.size()); }
  bool quadratic() const { return !midside.empty(); }
};

// Corner coordinates of tetrahedron `e`, one row per node [m].
Eigen::Matrix<double, 4, 3> TetCorners(const Mesh& mesh, int e);

// Total area of a face set [m^2].
double FaceSetArea(const Mesh& mesh, const FaceSet& set);

// The tetrahedron behind each triangle of a boundary face set: for triangle
// i, {element, corner}, `corner` (0..3) being the element's node opposite the
// triangle; {-1, -1} for a triangle that is no element's face.
std::vector<std::array<int, 2>> FaceElements(const Mesh& mesh, const FaceSet& set);

}  // namespace pba
