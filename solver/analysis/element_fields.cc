#include "analysis/element_fields.h"

#include <Eigen/LU>
#include <algorithm>
#include <cstddef>

#include "material/hyperelastic.h"
#include "material/linear_elastic.h"
#include "material/material_field.h"

namespace pba {

ElementFields FieldsFromPk2(const Eigen::Matrix3d& f, const Vector6d& pk2) {
  ElementFields p;
  p.j = f.determinant();
  p.green = GreenLagrangeVoigt(f);
  p.almansi = AlmansiVoigt(f);
  p.pk2 = pk2;
  p.cauchy = SymmetricToVoigt(f * VoigtToSymmetric(p.pk2) * f.transpose() / p.j);
  return p;
}

ElementFields FieldsFromCauchy(const Eigen::Matrix3d& f, const Vector6d& cauchy) {
  ElementFields p;
  p.j = f.determinant();
  p.green = GreenLagrangeVoigt(f);
  p.almansi = AlmansiVoigt(f);
  p.cauchy = cauchy;
  const Eigen::Matrix3d finv = f.inverse();
  p.pk2 = SymmetricToVoigt(p.j * finv * VoigtToSymmetric(cauchy) * finv.transpose());
  return p;
}

void ElementFieldSum::Add(double weight, const ElementFields& point) {
  sum_.green += weight * point.green;
  sum_.almansi += weight * point.almansi;
  sum_.pk2 += weight * point.pk2;
  sum_.cauchy += weight * point.cauchy;
  sum_.j += weight * point.j;
  weight_ += weight;
  largest_ = std::max(largest_, point.green.cwiseAbs().maxCoeff());
  ++points_;
}

ElementFields ElementFieldSum::Mean() const {
  ElementFields mean;
  mean.green = sum_.green / weight_;
  mean.almansi = sum_.almansi / weight_;
  mean.pk2 = sum_.pk2 / weight_;
  mean.cauchy = sum_.cauchy / weight_;
  mean.j = sum_.j / weight_;
  return mean;
}

double ElementFieldSum::LargestStrain() const {
  // max |w E| / w: division by the positive weight keeps the order, so this
  // is the mean's largest component exactly.
  if (points_ == 1) return sum_.green.cwiseAbs().maxCoeff() / weight_;
  return largest_;
}

void StartSmallStrainFields(int elements, Solution* solution) {
  const std::size_t n = static_cast<std::size_t>(elements);
  solution->strain.assign(6 * n, 0.0);
  solution->stress_pa.assign(6 * n, 0.0);
  solution->von_mises_pa.assign(n, 0.0);
}

void StartFiniteStrainFields(int elements, Solution* solution) {
  StartSmallStrainFields(elements, solution);
  const std::size_t n = static_cast<std::size_t>(elements);
  solution->almansi_strain.assign(6 * n, 0.0);
  solution->pk2_stress_pa.assign(6 * n, 0.0);
  solution->jacobian.assign(n, 1.0);
}

void WriteSmallStrainFields(int e, const Vector6d& strain, const Vector6d& stress,
                            Solution* solution) {
  const std::size_t at = 6 * static_cast<std::size_t>(e);
  Eigen::Map<Vector6d>(&solution->strain[at]) = strain;
  Eigen::Map<Vector6d>(&solution->stress_pa[at]) = stress;
  solution->von_mises_pa[e] = VonMises(stress);
}

double WriteFiniteStrainFields(int e, const ElementFields& fields, Solution* solution) {
  WriteSmallStrainFields(e, fields.green, fields.cauchy, solution);
  const std::size_t at = 6 * static_cast<std::size_t>(e);
  Eigen::Map<Vector6d>(&solution->almansi_strain[at]) = fields.almansi;
  Eigen::Map<Vector6d>(&solution->pk2_stress_pa[at]) = fields.pk2;
  solution->jacobian[e] = fields.j;
  return fields.green.cwiseAbs().maxCoeff();
}

ElementFields FieldsAt(const HyperelasticMaterial& material, const Eigen::Matrix3d& f,
                       std::optional<double> pressure, double volume_ratio) {
  Vector6d pk2 = Vector6d::Zero();
  if (pressure) {
    double w;
    material.Isochoric(f, &w, &pk2, nullptr);
    pk2 += *pressure * f.determinant() * SymmetricToVoigt((f.transpose() * f).inverse());
  } else {
    pk2 = material.Stress(f);
  }
  ElementFields p = FieldsFromPk2(f, pk2);
  if (pressure) p.j = volume_ratio;
  return p;
}

double RecoverFiniteStrainFields(int elements, const ThreadContext& threads, Solution* solution,
                                 const std::function<void(int e, ElementFieldSum* sum)>& sample) {
  StartFiniteStrainFields(elements, solution);
  double max_strain = 0;
  // clang-format splits "max : max_strain" across the continuation.
  // clang-format off
#pragma omp parallel for schedule(static) reduction(max : max_strain) \
    num_threads(threads.threads()) if (threads.Parallel(elements))
  // clang-format on
  for (int e = 0; e < elements; ++e) {
    ElementFieldSum sum;
    sample(e, &sum);
    WriteFiniteStrainFields(e, sum.Mean(), solution);
    max_strain = std::max(max_strain, sum.LargestStrain());
  }
  return max_strain;
}

}  // namespace pba
