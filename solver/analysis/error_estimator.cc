#include "analysis/error_estimator.h"

#include <cmath>

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
                                    const std::vector<double>& volume, const Matrix6d& compliance) {
  const int n = mesh.num_nodes();
  const int ne = mesh.num_elements();
  // Volume-weighted nodal averages. Serial: a scatter, and cheap next to the solve.
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> nodal =
      Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>::Zero(n, 6);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < ne; ++e) {
    const Eigen::Map<const Vector6d> s(&stress[6 * e]);
    for (int a : mesh.tets[e]) {
      nodal.row(a) += volume[e] * s.transpose();
      weight(a) += volume[e];
    }
  }
  for (int a = 0; a < n; ++a) {
    if (weight(a) > 0) nodal.row(a) /= weight(a);
  }

  // 4-point rule on the tetrahedron, degree 2 (barycentric alpha, beta).
  constexpr double kAlpha = 0.5854101966249685, kBeta = 0.1381966011250105;
  std::vector<double> eta2(ne, 0.0), u2(ne, 0.0);
  double error2 = 0, energy2 = 0;
#pragma omp parallel for reduction(+ : error2, energy2) schedule(static)
  for (int e = 0; e < ne; ++e) {
    const Eigen::Map<const Vector6d> sh(&stress[6 * e]);
    double sum = 0;
    for (int q = 0; q < 4; ++q) {
      Vector6d recovered = Vector6d::Zero();
      for (int a = 0; a < 4; ++a) {
        recovered += (a == q ? kAlpha : kBeta) * nodal.row(mesh.tets[e][a]).transpose();
      }
      const Vector6d diff = recovered - sh;
      sum += 0.25 * volume[e] * diff.dot(compliance * diff);
    }
    eta2[e] = sum;
    u2[e] = volume[e] * sh.dot(compliance * sh);
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
                                        const Matrix6d& compliance) {
  constexpr int kN = Element::kNodes;
  const int n = mesh.num_nodes(), ne = mesh.num_elements();
  // The stresses each element gives at its nodes, computed in parallel, then
  // averaged node by node, weighted by element volume (a serial scatter,
  // cheap next to the solve).
  std::vector<Eigen::Matrix<double, kN, 6>> at_nodes(ne);
  std::vector<double> volume(ne, 0.0);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < ne; ++e) {
    for (const auto& q : Element::Rule()) volume[e] += q.weight * Element::Jacobian(mesh, e, q.xi);
    for (int a = 0; a < kN; ++a) at_nodes[e].row(a) = stress(e, Element::NodeXi(a)).transpose();
  }
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> nodal =
      Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>::Zero(n, 6);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < ne; ++e) {
    const auto nodes = Element::Nodes(mesh, e);
    for (int a = 0; a < kN; ++a) {
      nodal.row(nodes[a]) += volume[e] * at_nodes[e].row(a);
      weight(nodes[a]) += volume[e];
    }
  }
  for (int a = 0; a < n; ++a) {
    if (weight(a) > 0) nodal.row(a) /= weight(a);
  }

  std::vector<double> eta2(ne, 0.0), u2(ne, 0.0);
  double error2 = 0, energy2 = 0;
#pragma omp parallel for reduction(+ : error2, energy2) schedule(static)
  for (int e = 0; e < ne; ++e) {
    const auto nodes = Element::Nodes(mesh, e);
    double sum = 0, energy = 0;
    for (const auto& q : Element::Rule()) {
      const double dv = q.weight * Element::Jacobian(mesh, e, q.xi);
      const auto shape = Element::Shape(q.xi);
      Vector6d recovered = Vector6d::Zero();
      for (int a = 0; a < kN; ++a) recovered += shape(a) * nodal.row(nodes[a]).transpose();
      const Vector6d sh = stress(e, q.xi);
      const Vector6d diff = recovered - sh;
      sum += dv * diff.dot(compliance * diff);
      energy += dv * sh.dot(compliance * sh);
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
                                         const Matrix6d& compliance) {
  return EstimateZzRecovered<Tet10Traits>(mesh, stress, compliance);
}

ErrorEstimateResult EstimateZzErrorHex8(const Mesh& mesh, const ElementStress& stress,
                                        const Matrix6d& compliance) {
  return EstimateZzRecovered<Hex8Traits>(mesh, stress, compliance);
}

}  // namespace pba
