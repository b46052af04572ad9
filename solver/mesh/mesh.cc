#include "mesh/mesh.h"

#include <Eigen/Geometry>

namespace pba {

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

}  // namespace pba
