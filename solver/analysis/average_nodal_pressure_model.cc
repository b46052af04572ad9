#include "analysis/average_nodal_pressure_model.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fem/tet4_finite_strain.h"
#include "material/hyperelastic.h"

namespace pba {
namespace {

// Per element at a state: the isochoric force and tangent, the current
// volume v_e and its gradient dv_e/dx = v_e grad_x N_b.
struct ElementState {
  Vector12d iso_force;
  Matrix12d iso_tangent;
  double iso_energy = 0;
  double volume = 0;                         // current v_e
  Eigen::Matrix<double, 4, 3> spatial_grad;  // grad_x N_b, one row per node
};

class AverageNodalPressureModel final : public FiniteStrainModel {
 public:
  AverageNodalPressureModel(const Mesh& mesh, const HyperelasticMaterial& material)
      : mesh_(mesh), material_(material), nodal_volume_(mesh.num_nodes(), 0.0) {
    geometry_.reserve(mesh.num_elements());
    patch_.resize(mesh.num_nodes());
    for (int e = 0; e < mesh.num_elements(); ++e) {
      geometry_.push_back(ComputeTet4Geometry(TetCorners(mesh, e)));
      for (int a : mesh.tets[e]) {
        nodal_volume_[a] += std::abs(geometry_[e].volume) / 4;
        patch_[a].push_back(e);
      }
    }
  }

  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    std::vector<ElementState> states;
    std::vector<double> j_node;
    if (!Evaluate(u, false, &states, &j_node)) return false;
    *force = Eigen::VectorXd::Zero(u.size());
    double total = 0;
    const std::vector<double> pressure = NodalPressure(j_node, &total);
    for (int e = 0; e < mesh_.num_elements(); ++e) {
      const ElementState& s = states[e];
      total += s.iso_energy;
      const Vector12d f = s.iso_force + MeanPressure(e, pressure) * VolumeGradient(s);
      for (int a = 0; a < 4; ++a) force->segment<3>(3 * mesh_.tets[e][a]) += f.segment<3>(3 * a);
    }
    if (energy) *energy = total;
    return force->allFinite() && std::isfinite(total);
  }

  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    std::vector<ElementState> states;
    std::vector<double> j_node;
    if (!Evaluate(u, true, &states, &j_node)) {
      return Status::Numerical("an element is inverted (J <= 0)");
    }
    PreparePattern(dofs);
    system->k = pattern_;
    system->rhs = Eigen::VectorXd::Zero(dofs.num_free());
    double unused = 0;
    const std::vector<double> pressure = NodalPressure(j_node, &unused);
    const auto scatter = [&](int row_dof, int col_dof, double value) {
      const int i = dofs.free_index(row_dof);
      if (i < 0 || value == 0) return;
      const int j = dofs.free_index(col_dof);
      if (j >= 0) {
        Coefficient(&system->k, i, j) += value;
      } else if (options.lift_prescribed) {
        system->rhs(i) -= value * dofs.prescribed_value(col_dof);
      }
    };
    // Element terms: isochoric tangent and p_e d2v_e/dx2.
    for (int e = 0; e < mesh_.num_elements(); ++e) {
      const ElementState& s = states[e];
      const double p = MeanPressure(e, pressure);
      Matrix12d k = s.iso_tangent;
      // d2v/dx_b dx_c = v (g_b g_c^T - g_c g_b^T), g = grad_x N.
      for (int b = 0; b < 4; ++b) {
        for (int c = 0; c < 4; ++c) {
          const Eigen::Vector3d gb = s.spatial_grad.row(b), gc = s.spatial_grad.row(c);
          k.block<3, 3>(3 * b, 3 * c) += p * s.volume * (gb * gc.transpose() - gc * gb.transpose());
        }
      }
      const Vector12d f = s.iso_force + p * VolumeGradient(s);
      const auto& tet = mesh_.tets[e];
      for (int b = 0; b < 4; ++b) {
        for (int r = 0; r < 3; ++r) {
          const int i = dofs.free_index(3 * tet[b] + r);
          if (i >= 0) system->rhs(i) -= f(3 * b + r);
          for (int c = 0; c < 4; ++c) {
            for (int q = 0; q < 3; ++q) {
              scatter(3 * tet[b] + r, 3 * tet[c] + q, k(3 * b + r, 3 * c + q));
            }
          }
        }
      }
    }
    // Nodal terms: (U''(J_a) / V_a) g_a g_a^T with g_a = dv_a/dx, supported
    // on the nodes of a's patch.
    std::vector<int> nodes;
    std::vector<Eigen::Vector3d> g;
    for (int a = 0; a < mesh_.num_nodes(); ++a) {
      if (patch_[a].empty()) continue;
      const double weight = material_.Volumetric(j_node[a]).second / nodal_volume_[a];
      nodes.clear();
      g.clear();
      for (int e : patch_[a]) {
        for (int b = 0; b < 4; ++b) {
          const int node = mesh_.tets[e][b];
          const Eigen::Vector3d contribution =
              states[e].volume / 4 * states[e].spatial_grad.row(b).transpose();
          const auto at = std::find(nodes.begin(), nodes.end(), node);
          if (at == nodes.end()) {
            nodes.push_back(node);
            g.push_back(contribution);
          } else {
            g[at - nodes.begin()] += contribution;
          }
        }
      }
      for (std::size_t m = 0; m < nodes.size(); ++m) {
        for (std::size_t n = 0; n < nodes.size(); ++n) {
          const Eigen::Matrix3d block = weight * g[m] * g[n].transpose();
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) scatter(3 * nodes[m] + r, 3 * nodes[n] + q, block(r, q));
          }
        }
      }
    }
    return Status::Ok();
  }

  std::string Describe() const override {
    return "TET4 with average nodal pressure (volumetric energy on nodal volumes), total "
           "Lagrangian";
  }

 private:
  // Element states in parallel; J at every node. False when an element is
  // inverted.
  bool Evaluate(const Eigen::VectorXd& u, bool with_tangent, std::vector<ElementState>* states,
                std::vector<double>* j_node) const {
    const int ne = mesh_.num_elements();
    states->resize(ne);
    bool ok = true;
#pragma omp parallel for schedule(static) reduction(&& : ok)
    for (int e = 0; e < ne; ++e) {
      const Tet4Geometry& g = geometry_[e];
      const Eigen::Matrix3d f = DeformationGradient(g, GatherElement(mesh_, e, u));
      const double j = f.determinant();
      if (!(j > 0) || !f.allFinite()) {
        ok = false;
        continue;
      }
      ElementState& s = (*states)[e];
      const double v0 = std::abs(g.volume);
      Vector6d stress;
      Matrix6d tangent;
      material_.Isochoric(f, &s.iso_energy, &stress, with_tangent ? &tangent : nullptr);
      s.iso_energy *= v0;
      const BMatrix b = GreenLagrangeVariation(g, f);
      s.iso_force = v0 * b.transpose() * stress;
      if (with_tangent) {
        s.iso_tangent = v0 * b.transpose() * tangent * b;
        const Eigen::Matrix<double, 4, 4> geo =
            g.grad * VoigtToSymmetric(stress) * g.grad.transpose();
        for (int a = 0; a < 4; ++a) {
          for (int c = 0; c < 4; ++c) {
            s.iso_tangent.block<3, 3>(3 * a, 3 * c).diagonal().array() += v0 * geo(a, c);
          }
        }
      }
      s.volume = j * v0;
      s.spatial_grad = g.grad * f.inverse();  // grad_x N = F^-T grad_X N, as rows
    }
    if (!ok) return false;
    j_node->assign(mesh_.num_nodes(), 0.0);
    for (int e = 0; e < ne; ++e) {
      for (int a : mesh_.tets[e]) (*j_node)[a] += (*states)[e].volume / 4;
    }
    for (int a = 0; a < mesh_.num_nodes(); ++a) {
      if (nodal_volume_[a] > 0) (*j_node)[a] /= nodal_volume_[a];
    }
    return true;
  }

  // p_a = U'(J_a); adds sum V_a U(J_a) to `energy`.
  std::vector<double> NodalPressure(const std::vector<double>& j_node, double* energy) const {
    std::vector<double> pressure(j_node.size(), 0.0);
    for (std::size_t a = 0; a < j_node.size(); ++a) {
      if (nodal_volume_[a] == 0) continue;
      const ScalarDerivatives u = material_.Volumetric(j_node[a]);
      pressure[a] = u.first;
      *energy += nodal_volume_[a] * u.value;
    }
    return pressure;
  }

  double MeanPressure(int e, const std::vector<double>& pressure) const {
    double p = 0;
    for (int a : mesh_.tets[e]) p += pressure[a];
    return p / 4;
  }

  static Vector12d VolumeGradient(const ElementState& s) {
    Vector12d g;
    for (int b = 0; b < 4; ++b) g.segment<3>(3 * b) = s.volume * s.spatial_grad.row(b).transpose();
    return g;
  }

  static double& Coefficient(SparseMatrix* k, int row, int col) {
    const int* begin = k->innerIndexPtr() + k->outerIndexPtr()[col];
    const int* end = k->innerIndexPtr() + k->outerIndexPtr()[col + 1];
    const int* at = std::lower_bound(begin, end, row);
    return k->valuePtr()[at - k->innerIndexPtr()];
  }

  // The pattern of K_ff: free dofs of nodes that share some node's patch.
  void PreparePattern(const DofMap& dofs) const {
    std::vector<int> free(dofs.num_dofs());
    for (int d = 0; d < dofs.num_dofs(); ++d) free[d] = dofs.free_index(d);
    if (free == pattern_free_ && pattern_.rows() == dofs.num_free()) return;
    const int n = mesh_.num_nodes();
    std::vector<std::vector<int>> neighbours(n);  // nodes of the patch
    for (int a = 0; a < n; ++a) {
      for (int e : patch_[a]) {
        for (int b : mesh_.tets[e]) neighbours[a].push_back(b);
      }
      std::sort(neighbours[a].begin(), neighbours[a].end());
      neighbours[a].erase(std::unique(neighbours[a].begin(), neighbours[a].end()),
                          neighbours[a].end());
    }
    std::vector<std::vector<int>> coupled(n);
    for (int a = 0; a < n; ++a) {
      for (int b : neighbours[a]) {
        coupled[b].insert(coupled[b].end(), neighbours[a].begin(), neighbours[a].end());
      }
    }
    std::vector<Eigen::Triplet<double, int>> entries;
    for (int b = 0; b < n; ++b) {
      std::sort(coupled[b].begin(), coupled[b].end());
      coupled[b].erase(std::unique(coupled[b].begin(), coupled[b].end()), coupled[b].end());
      for (int c : coupled[b]) {
        for (int r = 0; r < 3; ++r) {
          const int i = free[3 * b + r];
          if (i < 0) continue;
          for (int q = 0; q < 3; ++q) {
            const int j = free[3 * c + q];
            if (j >= 0) entries.emplace_back(i, j, 0.0);
          }
        }
      }
    }
    pattern_.resize(dofs.num_free(), dofs.num_free());
    pattern_.setFromTriplets(entries.begin(), entries.end());
    pattern_.makeCompressed();
    pattern_free_ = std::move(free);
  }

  const Mesh& mesh_;
  const HyperelasticMaterial& material_;
  std::vector<Tet4Geometry> geometry_;
  std::vector<double> nodal_volume_;     // V_a
  std::vector<std::vector<int>> patch_;  // elements around each node
  mutable SparseMatrix pattern_;
  mutable std::vector<int> pattern_free_;
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(
    const Mesh& mesh, const HyperelasticMaterial& material) {
  return std::make_unique<AverageNodalPressureModel>(mesh, material);
}

}  // namespace pba
