#include "analysis/rigid_modes.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

namespace pba {

std::string DescribeFreeRigidModes(const Mesh& mesh, const DofMap& dofs) {
  const Eigen::RowVector3d centroid = mesh.nodes.colwise().mean();
  const double length = (mesh.nodes.colwise().maxCoeff() - mesh.nodes.colwise().minCoeff()).norm();
  // Gram matrix of the six modes restricted to the prescribed unknowns, with
  // rotations scaled by the body's size so all six are comparable.
  Eigen::Matrix<double, 6, 6> gram = Eigen::Matrix<double, 6, 6>::Zero();
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    const Eigen::RowVector3d r = (mesh.nodes.row(node) - centroid) / length;
    for (int c = 0; c < 3; ++c) {
      if (!dofs.prescribed(3 * node + c)) continue;
      // Component c of each mode at this node: translation e_k, rotation e_k x r.
      Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
      row(c) = 1;
      const Eigen::Vector3d rotation_x(0, -r(2), r(1)), rotation_y(r(2), 0, -r(0)),
          rotation_z(-r(1), r(0), 0);
      row(3) = rotation_x(c);
      row(4) = rotation_y(c);
      row(5) = rotation_z(c);
      gram += row * row.transpose();
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(gram);
  const double scale = std::max(gram.trace(), 1.0);
  static const char* kNames[6] = {"translation along x", "translation along y",
                                  "translation along z", "rotation about x",
                                  "rotation about y",    "rotation about z"};
  std::string out;
  for (int i = 0; i < 6; ++i) {
    if (eigen.eigenvalues()(i) > 1e-9 * scale) continue;
    const Eigen::Matrix<double, 6, 1> mode = eigen.eigenvectors().col(i);
    std::string parts;
    for (int k = 0; k < 6; ++k) {
      if (std::abs(mode(k)) < 0.1) continue;
      parts += (parts.empty() ? "" : " combined with ") + std::string(kNames[k]);
    }
    out += (out.empty() ? "" : "; ") + parts;
  }
  if (!out.empty()) {
    char where[96];
    std::snprintf(where, sizeof where, " (rotations through (%.4g, %.4g, %.4g) mm)",
                  centroid(0) * 1e3, centroid(1) * 1e3, centroid(2) * 1e3);
    if (out.find("rotation") != std::string::npos) out += where;
  }
  return out;
}

}  // namespace pba
