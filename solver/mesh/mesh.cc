#include "mesh/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <unordered_map>

namespace pba {

Eigen::Matrix<double, 4, 3> TetCorners(const Mesh& mesh, int e) {
  Eigen::Matrix<double, 4, 3> x;
  for (int a = 0; a < 4; ++a) x.row(a) = mesh.nodes.row(mesh.tets[e][a]);
  return x;
}

double FaceSetArea(const Mesh& mesh, const FaceSet& set) {
  double area = 0;
  for (const auto& t : set.triangles) {
    const Eigen::Vector3d a = mesh.nodes.row(t[0]).transpose();
    const Eigen::Vector3d b = mesh.nodes.row(t[1]).transpose();
    const Eigen::Vector3d c = mesh.nodes.row(t[2]).transpose();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

std::vector<std::array<int, 2>> FaceElements(const Mesh& mesh, const FaceSet& set) {
  // Sorted triangle -> its index in the set, then one pass over the elements.
  struct Hash {
    std::size_t operator()(const std::array<int, 3>& k) const {
      return (static_cast<std::size_t>(k[0]) * 73856093u) ^
             (static_cast<std::size_t>(k[1]) * 19349663u) ^
             (static_cast<std::size_t>(k[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<int, 3>, int, Hash> index;
  index.reserve(set.triangles.size());
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    std::array<int, 3> key = set.triangles[i];
    std::sort(key.begin(), key.end());
    index.emplace(key, static_cast<int>(i));
  }
  std::vector<std::array<int, 2>> owner(set.triangles.size(), {-1, -1});
  if (index.empty()) return owner;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& tet = mesh.tets[e];
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> key;
      for (int k = 0, n = 0; k < 4; ++k) {
        if (k != skip) key[n++] = tet[k];
      }
      std::sort(key.begin(), key.end());
      const auto it = index.find(key);
      if (it != index.end()) owner[it->second] = {e, skip};
    }
  }
  return owner;
}

}  // namespace pba
