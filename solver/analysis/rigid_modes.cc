#include "analysis/rigid_modes.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "core/format.h"

namespace pba {

namespace {

// The free rigid motions of the body made of `nodes` (all of the mesh's
// when empty), as DescribeFreeRigidModes words them.
std::string FreeModes(const Mesh& mesh, const DofMap& dofs, const std::vector<int>& nodes) {
  Eigen::MatrixXd x(nodes.empty() ? mesh.num_nodes() : static_cast<int>(nodes.size()), 3);
  for (int i = 0; i < x.rows(); ++i) x.row(i) = mesh.nodes.row(nodes.empty() ? i : nodes[i]);
  const Eigen::RowVector3d centroid = x.colwise().mean();
  const double length = std::max((x.colwise().maxCoeff() - x.colwise().minCoeff()).norm(), 1e-300);
  // Gram matrix of the six modes restricted to the prescribed unknowns, with
  // rotations scaled by the body's size so all six are comparable.
  Eigen::Matrix<double, 6, 6> gram = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < x.rows(); ++i) {
    const int node = nodes.empty() ? i : nodes[i];
    const Eigen::RowVector3d r = (x.row(i) - centroid) / length;
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

}  // namespace

std::string DescribeFreeRigidModes(const Mesh& mesh, const DofMap& dofs) {
  return FreeModes(mesh, dofs, {});
}

std::string DescribeLoosePieces(const Mesh& mesh, const DofMap& dofs) {
  int pieces = 0;
  const std::vector<int> piece = MeshPieces(mesh, &pieces);
  if (pieces <= 1) return "";
  std::vector<std::vector<int>> elements(pieces);
  for (int e = 0; e < mesh.num_elements(); ++e) elements[piece[e]].push_back(e);
  // Which pieces each node is in: a node in two joins them by a hinge.
  std::vector<int> first_piece(mesh.num_nodes(), -1);
  std::vector<char> shared(mesh.num_nodes(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    for (int a : mesh.ElementNodes(e)) {
      if (first_piece[a] < 0) first_piece[a] = piece[e];
      if (first_piece[a] != piece[e]) shared[a] = 1;
    }
  }
  std::string out;
  int loose = 0;
  for (int p = 0; p < pieces; ++p) {
    std::vector<int> nodes;
    std::map<std::string, int> regions;
    for (int e : elements[p]) {
      for (int a : mesh.ElementNodes(e)) nodes.push_back(a);
      if (!mesh.element_region.empty() && !mesh.region_names.empty()) {
        ++regions[mesh.region_names[mesh.element_region[e]]];
      }
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    const std::string modes = FreeModes(mesh, dofs, nodes);
    if (modes.empty()) continue;
    if (++loose > 5) continue;
    int hinges = 0;
    Eigen::RowVector3d centre = Eigen::RowVector3d::Zero();
    for (int a : nodes) {
      hinges += shared[a];
      centre += mesh.nodes.row(a);
    }
    centre /= static_cast<double>(nodes.size());
    std::string of;
    for (const auto& [name, count] : regions) {
      of += (of.empty() ? " of " : ", ") + name + Format(" (%d)", count);
    }
    out += (out.empty() ? "" : "; ") +
           Format("%zu elements%s around (%.4g, %.4g, %.4g) mm, ", elements[p].size(), of.c_str(),
                  centre(0) * 1e3, centre(1) * 1e3, centre(2) * 1e3) +
           (hinges > 0 ? Format("joined to the rest only by %d node%s (an edge or a corner)",
                                hinges, hinges == 1 ? "" : "s")
                       : std::string("touching nothing else")) +
           ", free: " + modes;
  }
  if (loose > 5) out += Format("; and %d more", loose - 5);
  return loose == 0
             ? ""
             : Format("%d of the mesh's %d pieces (elements joined by faces) ", loose, pieces) +
                   "are not held: " + out;
}

}  // namespace pba
