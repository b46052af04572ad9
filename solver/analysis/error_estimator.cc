#include "analysis/error_estimator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "assembly/assembler.h"
#include "fem/hex8.h"
#include "fem/tet10.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

ErrorEstimateResult Finish(std::vector<double> eta2, std::vector<double> u2, double error2,
                           double energy2) {
  ErrorEstimateResult result;
  result.relative_error = error2 + energy2 > 0 ? std::sqrt(error2 / (error2 + energy2)) : 0.0;
  result.element_share.resize(eta2.size());
  for (std::size_t e = 0; e < eta2.size(); ++e) {
    result.element_share[e] = error2 > 0 ? eta2[e] / error2 : 0.0;
  }
  result.element_error2 = std::move(eta2);
  result.element_energy2 = std::move(u2);
  return result;
}

// Where the recovered stress is kept: one slot per node within one material,
// so that the recovered field is continuous inside a material and free to
// jump across the interface between two, where only the traction is
// continuous (averaging across it would report the jump of the tangential
// stress as discretisation error). One material: the slot is the node.
class RecoverySlots {
 public:
  // `nodes(e)` gives element e's node indices.
  template <typename Nodes>
  RecoverySlots(const Mesh& mesh, const ElasticityField& elasticity, const Nodes& nodes)
      : materials_(elasticity.num_materials()), elasticity_(elasticity) {
    const int ne = mesh.num_elements();
    if (materials_ == 1) {
      size_ = mesh.num_nodes();
      return;
    }
    for (int e = 0; e < ne; ++e) {
      for (int a : nodes(e)) keys_.push_back(Key(a, elasticity.material_of(e)));
    }
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
    size_ = static_cast<int>(keys_.size());
  }

  int size() const { return size_; }
  // The slot of node `node` of element `e`.
  int Of(int node, int e) const {
    if (materials_ == 1) return node;
    const std::uint64_t key = Key(node, elasticity_.material_of(e));
    return static_cast<int>(std::lower_bound(keys_.begin(), keys_.end(), key) - keys_.begin());
  }

 private:
  std::uint64_t Key(int node, int material) const {
    return static_cast<std::uint64_t>(node) * static_cast<std::uint64_t>(materials_) +
           static_cast<std::uint64_t>(material);
  }
  int materials_;
  const ElasticityField& elasticity_;
  int size_ = 0;
  std::vector<std::uint64_t> keys_;  // sorted node * materials + material
};

using NodalStress = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;

}  // namespace

std::vector<RegionError> ErrorByRegion(const Mesh& mesh, const ErrorEstimateResult& estimate,
                                       const std::string& body) {
  const bool one = mesh.region_names.empty();
  const std::size_t n = one ? 1 : mesh.region_names.size();
  std::vector<double> error2(n, 0.0), energy2(n, 0.0);
  std::vector<RegionError> regions(n);
  double total = 0;
  for (std::size_t e = 0; e < estimate.element_error2.size(); ++e) {
    const int r = one ? 0 : mesh.element_region[e];
    error2[r] += estimate.element_error2[e];
    energy2[r] += estimate.element_energy2[e];
    ++regions[r].elements;
    total += estimate.element_error2[e];
  }
  for (std::size_t r = 0; r < n; ++r) {
    regions[r].name = one ? body : mesh.region_names[r];
    const double sum = error2[r] + energy2[r];
    regions[r].relative_error = sum > 0 ? std::sqrt(error2[r] / sum) : 0.0;
    regions[r].share = total > 0 ? error2[r] / total : 0.0;
  }
  return regions;
}

ErrorEstimateResult EstimateZzError(const Mesh& mesh, const std::vector<double>& stress,
                                    const std::vector<double>& volume,
                                    const ElasticityField& elasticity,
                                    const ThreadContext& threads) {
  const int ne = mesh.num_elements();
  // Volume-weighted averages at each node, within each material. Serial: a
  // scatter, and cheap next to the solve.
  const RecoverySlots slots(mesh, elasticity, [&](int e) { return mesh.tets[e]; });
  NodalStress nodal = NodalStress::Zero(slots.size(), 6);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(slots.size());
  for (int e = 0; e < ne; ++e) {
    const Eigen::Map<const Vector6d> s(&stress[6 * e]);
    for (int a : mesh.tets[e]) {
      const int slot = slots.Of(a, e);
      nodal.row(slot) += volume[e] * s.transpose();
      weight(slot) += volume[e];
    }
  }
  for (int a = 0; a < slots.size(); ++a) {
    if (weight(a) > 0) nodal.row(a) /= weight(a);
  }

  // 4-point rule on the tetrahedron, degree 2 (barycentric alpha, beta).
  constexpr double kAlpha = 0.5854101966249685, kBeta = 0.1381966011250105;
  std::vector<double> eta2(ne, 0.0), u2(ne, 0.0);
  double error2 = 0, energy2 = 0;
#pragma omp parallel for reduction(+ : error2, energy2) schedule(static) \
    num_threads(threads.threads()) if (threads.Parallel(ne))
  for (int e = 0; e < ne; ++e) {
    const Eigen::Map<const Vector6d> sh(&stress[6 * e]);
    double sum = 0;
    for (int q = 0; q < 4; ++q) {
      Vector6d recovered = Vector6d::Zero();
      for (int a = 0; a < 4; ++a) {
        recovered +=
            (a == q ? kAlpha : kBeta) * nodal.row(slots.Of(mesh.tets[e][a], e)).transpose();
      }
      const Vector6d diff = recovered - sh;
      sum += 0.25 * volume[e] * diff.dot(elasticity.Compliance(e) * diff);
    }
    eta2[e] = sum;
    u2[e] = volume[e] * sh.dot(elasticity.Compliance(e) * sh);
    error2 += sum;
    energy2 += u2[e];
  }
  return Finish(std::move(eta2), std::move(u2), error2, energy2);
}

namespace {

// ZZ with recovery at the element's own nodes, for elements whose stress
// varies within them (10-node tetrahedra, hexahedra). `Element` supplies:
//   kNodes; Nodes(mesh, e) -> node indices; NodeXi(a) -> natural point of
//   node a; Shape(xi) -> the N shape functions; Rule() -> points with
//   `xi` and `weight`; Jacobian(mesh, e, xi) -> det J.
template <typename Element>
ErrorEstimateResult EstimateZzRecovered(const Mesh& mesh, const ElementStress& stress,
                                        const ElasticityField& elasticity,
                                        const ThreadContext& threads) {
  constexpr int kN = Element::kNodes;
  const int ne = mesh.num_elements();
  // The stresses each element gives at its nodes, computed in parallel, then
  // averaged node by node within each material, weighted by element volume (a serial scatter,
  // cheap next to the solve).
  std::vector<Eigen::Matrix<double, kN, 6>> at_nodes(ne);
  std::vector<double> volume(ne, 0.0);
#pragma omp parallel for schedule(static) num_threads(threads.threads()) if (threads.Parallel(ne))
  for (int e = 0; e < ne; ++e) {
    for (const auto& q : Element::Rule()) volume[e] += q.weight * Element::Jacobian(mesh, e, q.xi);
    for (int a = 0; a < kN; ++a) at_nodes[e].row(a) = stress(e, Element::NodeXi(a)).transpose();
  }
  const RecoverySlots slots(mesh, elasticity, [&](int e) { return Element::Nodes(mesh, e); });
  NodalStress nodal = NodalStress::Zero(slots.size(), 6);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(slots.size());
  for (int e = 0; e < ne; ++e) {
    const auto nodes = Element::Nodes(mesh, e);
    for (int a = 0; a < kN; ++a) {
      const int slot = slots.Of(nodes[a], e);
      nodal.row(slot) += volume[e] * at_nodes[e].row(a);
      weight(slot) += volume[e];
    }
  }
  for (int a = 0; a < slots.size(); ++a) {
    if (weight(a) > 0) nodal.row(a) /= weight(a);
  }

  std::vector<double> eta2(ne, 0.0), u2(ne, 0.0);
  double error2 = 0, energy2 = 0;
#pragma omp parallel for reduction(+ : error2, energy2) schedule(static) \
    num_threads(threads.threads()) if (threads.Parallel(ne))
  for (int e = 0; e < ne; ++e) {
    const auto nodes = Element::Nodes(mesh, e);
    double sum = 0, energy = 0;
    for (const auto& q : Element::Rule()) {
      const double dv = q.weight * Element::Jacobian(mesh, e, q.xi);
      const auto shape = Element::Shape(q.xi);
      Vector6d recovered = Vector6d::Zero();
      for (int a = 0; a < kN; ++a) {
        recovered += shape(a) * nodal.row(slots.Of(nodes[a], e)).transpose();
      }
      const Vector6d sh = stress(e, q.xi);
      const Vector6d diff = recovered - sh;
      sum += dv * diff.dot(elasticity.Compliance(e) * diff);
      energy += dv * sh.dot(elasticity.Compliance(e) * sh);
    }
    eta2[e] = sum;
    u2[e] = energy;
    error2 += sum;
    energy2 += energy;
  }
  return Finish(std::move(eta2), std::move(u2), error2, energy2);
}

// The 10-node tetrahedron, integrated with the 14-point degree-5 rule.
struct Tet10Traits {
  static constexpr int kNodes = 10;
  static std::array<int, 10> Nodes(const Mesh& mesh, int e) { return Tet10NodeIndices(mesh, e); }
  static Eigen::Vector3d NodeXi(int a) {
    const Eigen::Vector3d corner[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                       Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    if (a < 4) return corner[a];
    return 0.5 * (corner[kTet10Edges[a - 4][0]] + corner[kTet10Edges[a - 4][1]]);
  }
  static Tet10Vector Shape(const Eigen::Vector3d& xi) { return Tet10ShapeFunctions(xi); }
  static const std::vector<QuadraturePoint>& Rule() { return Tet10MassRule(); }
  static double Jacobian(const Mesh& mesh, int e, const Eigen::Vector3d& xi) {
    Tet10Nodes grad;
    return Tet10Gradients(Tet10Coordinates(mesh, e), xi, &grad);
  }
};

// The 8-node hexahedron, integrated with the 2 x 2 x 2 rule (exact for the
// product of two trilinear fields on a parallelepiped).
struct Hex8Traits {
  static constexpr int kNodes = 8;
  static std::array<int, 8> Nodes(const Mesh& mesh, int e) { return mesh.hexes[e]; }
  static Eigen::Vector3d NodeXi(int a) {
    return Eigen::Vector3d(kHex8NodeNatural[a][0], kHex8NodeNatural[a][1], kHex8NodeNatural[a][2]);
  }
  static Hex8Vector Shape(const Eigen::Vector3d& xi) { return Hex8ShapeFunctions(xi); }
  static const std::array<Hex8QuadraturePoint, 8>& Rule() { return Hex8Rule(); }
  static double Jacobian(const Mesh& mesh, int e, const Eigen::Vector3d& xi) {
    Hex8Nodes grad;
    return Hex8Gradients(Hex8Coordinates(mesh, e), xi, &grad);
  }
};

}  // namespace

ErrorEstimateResult EstimateZzErrorTet10(const Mesh& mesh, const ElementStress& stress,
                                         const ElasticityField& elasticity,
                                         const ThreadContext& threads) {
  return EstimateZzRecovered<Tet10Traits>(mesh, stress, elasticity, threads);
}

ErrorEstimateResult EstimateZzErrorHex8(const Mesh& mesh, const ElementStress& stress,
                                        const ElasticityField& elasticity,
                                        const ThreadContext& threads) {
  return EstimateZzRecovered<Hex8Traits>(mesh, stress, elasticity, threads);
}

ErrorEstimateResult EstimateZzError(const Mesh& mesh, const ElementStress& stress,
                                    const ElasticityField& elasticity,
                                    const ThreadContext& threads) {
  switch (mesh.shape()) {
    case ElementShape::kTet10:
      return EstimateZzErrorTet10(mesh, stress, elasticity, threads);
    case ElementShape::kHex8:
      return EstimateZzErrorHex8(mesh, stress, elasticity, threads);
    case ElementShape::kTet4:
      break;
  }
  // The 4-node element's stress is constant: one sample each, at the
  // centroid, with the volume its recovery weighs it by.
  const int ne = mesh.num_elements();
  const Eigen::Vector3d centroid = Eigen::Vector3d::Constant(0.25);
  std::vector<double> sampled(6 * static_cast<std::size_t>(ne)), volume(ne);
#pragma omp parallel for schedule(static) num_threads(threads.threads()) if (threads.Parallel(ne))
  for (int e = 0; e < ne; ++e) {
    Vector6d::Map(&sampled[6 * static_cast<std::size_t>(e)]) = stress(e, centroid);
    volume[e] = ComputeTet4Geometry(TetCorners(mesh, e)).volume;
  }
  return EstimateZzError(mesh, sampled, volume, elasticity, threads);
}

std::string ZzMethod(const Mesh& mesh, ZzStress stress) {
  if (stress == ZzStress::kSecondPiolaKirchhoff) {
    return "Zienkiewicz-Zhu recovery of the second Piola-Kirchhoff stress (nodal averaging), "
           "measured with the initial compliance";
  }
  switch (mesh.shape()) {
    case ElementShape::kTet10:
      return "Zienkiewicz-Zhu stress recovery (nodal averaging, quadratic)";
    case ElementShape::kHex8:
      return "Zienkiewicz-Zhu stress recovery (nodal averaging, trilinear)";
    case ElementShape::kTet4:
      break;
  }
  return "Zienkiewicz-Zhu stress recovery (nodal averaging)";
}

}  // namespace pba
