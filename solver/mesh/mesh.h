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
  std::vector<int> nodes;                     // sorted, unique
};

struct Mesh {
  // nodes x 3 [m]
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> nodes;
  // Positively oriented 4-node tetrahedra (node indices).
  std::vector<std::array<int, 4>> tets;
  std::map<std::string, FaceSet> face_sets;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_elements() const { return static_cast<int>(tets.size()); }
};

// Corner coordinates of tetrahedron `e`, one row per node [m].
Eigen::Matrix<double, 4, 3> TetCorners(const Mesh& mesh, int e);

// Total area of a face set [m^2].
double FaceSetArea(const Mesh& mesh, const FaceSet& set);

}  // namespace pba
