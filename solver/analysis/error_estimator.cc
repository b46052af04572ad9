#include "analysis/error_estimator.h"

#include <cmath>

#include "fem/tet10.h"
#include "mesh/quadratic.h"

namespace pba {

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
  std::vector<double> eta2(ne, 0.0);
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
    error2 += sum;
    energy2 += volume[e] * sh.dot(compliance * sh);
  }
  ErrorEstimateResult result;
  result.relative_error = error2 + energy2 > 0 ? std::sqrt(error2 / (error2 + energy2)) : 0.0;
  result.element_share.resize(ne);
  for (int e = 0; e < ne; ++e) result.element_share[e] = error2 > 0 ? eta2[e] / error2 : 0.0;
  return result;
}

ErrorEstimateResult EstimateZzErrorTet10(const Mesh& mesh, const ElementStress& stress,
                                         const Matrix6d& compliance) {
  const int n = mesh.num_nodes(), ne = mesh.num_elements();
  // Natural coordinates of the ten nodes (fem/tet10.h).
  std::array<Eigen::Vector3d, 10> node_xi;
  const Eigen::Vector3d corner[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                     Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (int a = 0; a < 4; ++a) node_xi[a] = corner[a];
  for (int k = 0; k < 6; ++k) {
    node_xi[4 + k] = 0.5 * (corner[kTet10Edges[k][0]] + corner[kTet10Edges[k][1]]);
  }
  // The stresses each element gives at its nodes, computed in parallel, then
  // averaged node by node (a serial scatter, cheap next to the solve).
  std::vector<Eigen::Matrix<double, 10, 6>> at_nodes(ne);
  std::vector<double> volume(ne);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < ne; ++e) {
    volume[e] = Tet10Volume(Tet10Coordinates(mesh, e));
    for (int a = 0; a < 10; ++a) at_nodes[e].row(a) = stress(e, node_xi[a]).transpose();
  }
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> nodal =
      Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>::Zero(n, 6);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(n);
  for (int e = 0; e < ne; ++e) {
    const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
    for (int a = 0; a < 10; ++a) {
      nodal.row(nodes[a]) += volume[e] * at_nodes[e].row(a);
      weight(nodes[a]) += volume[e];
    }
  }
  for (int a = 0; a < n; ++a) {
    if (weight(a) > 0) nodal.row(a) /= weight(a);
  }

  const std::vector<QuadraturePoint>& rule = Tet10MassRule();
  std::vector<double> eta2(ne, 0.0);
  double error2 = 0, energy2 = 0;
#pragma omp parallel for reduction(+ : error2, energy2) schedule(static)
  for (int e = 0; e < ne; ++e) {
    const Tet10Nodes x = Tet10Coordinates(mesh, e);
    const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
    Tet10Nodes grad;
    double sum = 0, energy = 0;
    for (const QuadraturePoint& q : rule) {
      const double dv = q.weight * Tet10Gradients(x, q.xi, &grad);
      const Tet10Vector shape = Tet10ShapeFunctions(q.xi);
      Vector6d recovered = Vector6d::Zero();
      for (int a = 0; a < 10; ++a) recovered += shape(a) * nodal.row(nodes[a]).transpose();
      const Vector6d sh = stress(e, q.xi);
      const Vector6d diff = recovered - sh;
      sum += dv * diff.dot(compliance * diff);
      energy += dv * sh.dot(compliance * sh);
    }
    eta2[e] = sum;
    error2 += sum;
    energy2 += energy;
  }
  ErrorEstimateResult result;
  result.relative_error = error2 + energy2 > 0 ? std::sqrt(error2 / (error2 + energy2)) : 0.0;
  result.element_share.resize(ne);
  for (int e = 0; e < ne; ++e) result.element_share[e] = error2 > 0 ? eta2[e] / error2 : 0.0;
  return result;
}

}  // namespace pba
