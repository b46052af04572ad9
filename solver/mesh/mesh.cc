#include "mesh/mesh.h"

#include <Eigen/Geometry>

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

}  // namespace pba
