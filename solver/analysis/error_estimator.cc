#include "analysis/error_estimator.h"

#include <cmath>

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

}  // namespace pba
