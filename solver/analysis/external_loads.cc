#include "analysis/external_loads.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "fem/tet4.h"

namespace pba {
namespace {

// [w]_x, the matrix of y -> w x y.
Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

}  // namespace

ExternalLoads::ExternalLoads(const Mesh& mesh)
    : mesh_(mesh), dead_(Eigen::VectorXd::Zero(3 * mesh.num_nodes())) {}

Eigen::Vector3d ExternalLoads::Corner(int node, const Eigen::VectorXd* u) const {
  Eigen::Vector3d x = mesh_.nodes.row(node).transpose();
  if (u != nullptr) x += u->segment<3>(3 * node);
  return x;
}

void ExternalLoads::AddTraction(const FaceSet& set, const Eigen::Vector3d& traction_pa) {
  for (const auto& t : set.triangles) {
    const double area = 0.5 * (Corner(t[1], nullptr) - Corner(t[0], nullptr))
                                  .cross(Corner(t[2], nullptr) - Corner(t[0], nullptr))
                                  .norm();
    for (int a : t) dead_.segment<3>(3 * a) += traction_pa * area / 3;
  }
}

void ExternalLoads::AddBodyForce(const Eigen::Vector3d& force_per_volume) {
  for (int e = 0; e < mesh_.num_elements(); ++e) {
    const double volume = std::abs(ComputeTet4Geometry(TetCorners(mesh_, e)).volume);
    for (int a : mesh_.tets[e]) dead_.segment<3>(3 * a) += force_per_volume * volume / 4;
  }
}

void ExternalLoads::AddPressure(const FaceSet& set, double pressure_pa, bool follower) {
  // The tetrahedron behind each triangle tells which side is out.
  const std::vector<std::array<int, 2>> owners = FaceElements(mesh_, set);
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    std::array<int, 3> t = set.triangles[i];
    const auto [element, corner] = owners[i];
    if (element >= 0) {
      const Eigen::Vector3d x0 = Corner(t[0], nullptr);
      const Eigen::Vector3d normal = (Corner(t[1], nullptr) - x0).cross(Corner(t[2], nullptr) - x0);
      const int inside = mesh_.tets[element][corner];
      if (normal.dot(Corner(inside, nullptr) - x0) > 0) std::swap(t[1], t[2]);
    }
    pressure_.push_back({t, pressure_pa, follower});
  }
}

bool ExternalLoads::follows_deformation() const {
  return std::any_of(pressure_.begin(), pressure_.end(),
                     [](const Pressure& p) { return p.follower; });
}

Eigen::VectorXd ExternalLoads::Force(const Eigen::VectorXd& u) const {
  Eigen::VectorXd f = dead_;
  for (const Pressure& p : pressure_) {
    const Eigen::VectorXd* state = p.follower ? &u : nullptr;
    const Eigen::Vector3d x0 = Corner(p.nodes[0], state);
    const Eigen::Vector3d area2 =
        (Corner(p.nodes[1], state) - x0).cross(Corner(p.nodes[2], state) - x0);
    for (int a : p.nodes) f.segment<3>(3 * a) -= p.pressure_pa / 6 * area2;
  }
  return f;
}

SparseMatrix ExternalLoads::Stiffness(const Eigen::VectorXd& u, const DofMap& dofs,
                                      double factor) const {
  // f_a = -(p / 6) A, A = (x1 - x0) x (x2 - x0) = x0 x x1 + x1 x x2 + x2 x x0,
  // so dA/dx_b = [x_{b+2} - x_{b+1}]_x (indices mod 3) and
  // K_L(a, b) = -df_a/dx_b = (p / 6) [w_b]_x, w_b = x_{b+2} - x_{b+1};
  // its symmetric part is (p / 12)([w_b]_x - [w_a]_x) (a skew matrix's
  // transpose is its negative).
  std::vector<Eigen::Triplet<double>> entries;
  for (const Pressure& p : pressure_) {
    if (!p.follower) continue;
    Eigen::Vector3d x[3], w[3];
    for (int k = 0; k < 3; ++k) x[k] = Corner(p.nodes[k], &u);
    for (int b = 0; b < 3; ++b) w[b] = x[(b + 2) % 3] - x[(b + 1) % 3];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        const Eigen::Matrix3d block = factor * p.pressure_pa / 12 * (Skew(w[b]) - Skew(w[a]));
        for (int r = 0; r < 3; ++r) {
          const int i = dofs.free_index(3 * p.nodes[a] + r);
          if (i < 0) continue;
          for (int c = 0; c < 3; ++c) {
            const int j = dofs.free_index(3 * p.nodes[b] + c);
            if (j >= 0) entries.emplace_back(i, j, block(r, c));
          }
        }
      }
    }
  }
  SparseMatrix k(dofs.num_free(), dofs.num_free());
  k.setFromTriplets(entries.begin(), entries.end());
  return k;
}

Eigen::Vector3d ExternalLoads::ReferenceResultant() const {
  const Eigen::VectorXd f = Force(Eigen::VectorXd::Zero(dead_.size()));
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int a = 0; a < mesh_.num_nodes(); ++a) total += f.segment<3>(3 * a);
  return total;
}

}  // namespace pba
