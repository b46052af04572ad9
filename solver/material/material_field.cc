#include "material/material_field.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {

Vector6d GreenLagrangeVoigt(const Eigen::Matrix3d& f) {
  Vector6d e = SymmetricToVoigt(0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity()));
  e.tail<3>() *= 2;
  return e;
}

Vector6d AlmansiVoigt(const Eigen::Matrix3d& f) {
  Vector6d e =
      SymmetricToVoigt(0.5 * (Eigen::Matrix3d::Identity() - (f * f.transpose()).inverse()));
  e.tail<3>() *= 2;
  return e;
}

void ElementResponse::Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                                Matrix6d* tangent) const {
  const double scale = alpha_ * volume_factor_;
  double w = 0;
  base_.Isochoric(f, energy ? &w : nullptr, stress, tangent);
  if (energy) {
    *energy = scale * w + (offset_.isZero(0) ? 0.0 : offset_.dot(GreenLagrangeVoigt(f)));
  }
  if (stress) *stress = scale * *stress + offset_;
  if (tangent) *tangent *= scale;
}

ScalarDerivatives ElementResponse::Volumetric(double j) const {
  if (volume_factor_ == 1) return base_.Volumetric(j);
  const ScalarDerivatives u = base_.Volumetric(j / volume_factor_);
  return {volume_factor_ * u.value, u.first, u.second / volume_factor_};
}

double ElementResponse::Energy(const Eigen::Matrix3d& f) const {
  const double j = f.determinant();
  if (!(j > 0) || !f.allFinite()) return std::numeric_limits<double>::infinity();
  double w = 0;
  Isochoric(f, &w, nullptr, nullptr);
  return w + Volumetric(j).value;
}

Vector6d ElementResponse::Stress(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "ElementResponse::Stress");
  Vector6d iso, vol;
  Isochoric(f, nullptr, &iso, nullptr);
  // The volumetric part through the invariant chain rule with a zero
  // isochoric energy: S_vol = J U'(J) C^-1.
  const InvariantState invariants = ComputeInvariants(f);
  InvariantResponse(invariants, IsochoricInvariantEnergy{}, Volumetric(invariants.j), &vol,
                    nullptr);
  return iso + vol;
}

Matrix6d ElementResponse::Tangent(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "ElementResponse::Tangent");
  Matrix6d iso, vol;
  Isochoric(f, nullptr, nullptr, &iso);
  const InvariantState invariants = ComputeInvariants(f);
  Vector6d unused;
  InvariantResponse(invariants, IsochoricInvariantEnergy{}, Volumetric(invariants.j), &unused,
                    &vol);
  return iso + vol;
}

MaterialField::MaterialField(std::vector<Entry> entries, std::vector<int> of_element,
                             const ThreadContext& threads)
    : entries_(std::move(entries)), of_element_(std::move(of_element)), threads_(threads) {
  for (const Entry& entry : entries_) {
    viscous_ = viscous_ || !entry.relaxation.g.empty();
    grows_ = grows_ || entry.growth_strain != 0;
  }
  steps_.assign(entries_.size(), ViscousStep());
  volume_factor_.assign(entries_.size(), 1.0);
  if (viscous_) {
    s_iso_.assign(of_element_.size(), Vector6d::Zero());
    h_.resize(of_element_.size());
    offset_.assign(of_element_.size(), Vector6d::Zero());
  }
}

std::unique_ptr<MaterialField> MaterialField::Uniform(const HyperelasticMaterial& material,
                                                      int elements) {
  Entry entry;
  // Not owned: the caller keeps the material alive.
  entry.material =
      std::shared_ptr<const HyperelasticMaterial>(&material, [](const HyperelasticMaterial*) {});
  std::vector<Entry> entries;
  entries.push_back(std::move(entry));
  return std::make_unique<MaterialField>(std::move(entries), std::vector<int>(elements, 0));
}

PronySeries ReduceRelaxation(const PronySeries& series, double relaxed_below_s,
                             double frozen_above_s, double* scale) {
  *scale = 1;
  PronySeries kept;
  for (std::size_t k = 0; k < series.g.size(); ++k) {
    if (series.tau_s[k] < relaxed_below_s) {
      *scale *= 1 - series.g[k];
    } else if (frozen_above_s <= 0 || series.tau_s[k] <= frozen_above_s) {
      kept.g.push_back(series.g[k]);
      kept.tau_s.push_back(series.tau_s[k]);
    }
  }
  for (double& g : kept.g) g /= *scale;
  return kept;
}

ElementResponse MaterialField::At(int e) const {
  const int k = of_element_[e];
  return ElementResponse(*entries_[k].material, steps_[k].alpha * entries_[k].isochoric_scale,
                         volume_factor_[k], viscous_ ? offset_[e] : Vector6d::Zero());
}

void MaterialField::BeginStep(double dt_s, double amplitude) {
  for (std::size_t k = 0; k < entries_.size(); ++k) {
    const Entry& entry = entries_[k];
    // dt = 0: the instantaneous response, nothing relaxes within the step.
    steps_[k] = dt_s > 0 && !entry.relaxation.g.empty() ? ViscousStep::Of(entry.relaxation, dt_s)
                                                        : ViscousStep();
    const double theta = 1 + entry.growth_strain * amplitude;
    volume_factor_[k] = theta * theta * theta;
  }
  if (!viscous_) return;
  const int ne = num_elements();
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (threads_.Parallel(ne))
  for (int e = 0; e < ne; ++e) offset_[e] = steps_[of_element_[e]].Offset(s_iso_[e], h_[e]);
}

void MaterialField::Commit(const std::vector<Eigen::Matrix3d>& f) {
  if (!viscous_) return;
  const int ne = num_elements();
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (threads_.Parallel(ne))
  for (int e = 0; e < ne; ++e) {
    const int k = of_element_[e];
    if (steps_[k].weight.empty()) continue;  // elastic, or an instantaneous step
    Vector6d s_iso;
    entries_[k].material->Isochoric(f[e], nullptr, &s_iso, nullptr);
    s_iso *= volume_factor_[k] * entries_[k].isochoric_scale;
    steps_[k].Advance(s_iso_[e], s_iso, &h_[e]);
    s_iso_[e] = s_iso;
  }
}

std::vector<double> MaterialField::SaveHistory() const {
  std::vector<double> values;
  for (std::size_t e = 0; e < s_iso_.size(); ++e) {
    values.insert(values.end(), s_iso_[e].data(), s_iso_[e].data() + 6);
    const std::size_t terms = entries_[of_element_[e]].relaxation.g.size();
    for (std::size_t k = 0; k < terms; ++k) {
      const Vector6d h = k < h_[e].size() ? h_[e][k] : Vector6d::Zero();
      values.insert(values.end(), h.data(), h.data() + 6);
    }
  }
  return values;
}

Status MaterialField::RestoreHistory(const std::vector<double>& values) {
  std::size_t expected = 0;
  for (std::size_t e = 0; e < s_iso_.size(); ++e) {
    expected += 6 * (1 + entries_[of_element_[e]].relaxation.g.size());
  }
  if (values.size() != expected) {
    return Status::InvalidArgument(
        "history", "holds " + std::to_string(values.size()) + " numbers where this model keeps " +
                       std::to_string(expected) + " (a different mesh or material?)");
  }
  std::size_t at = 0;
  for (std::size_t e = 0; e < s_iso_.size(); ++e) {
    s_iso_[e] = Eigen::Map<const Vector6d>(&values[at]);
    at += 6;
    h_[e].resize(entries_[of_element_[e]].relaxation.g.size());
    for (Vector6d& h : h_[e]) {
      h = Eigen::Map<const Vector6d>(&values[at]);
      at += 6;
    }
  }
  return Status::Ok();
}

double MaterialField::ShortestRelaxationTime() const {
  double shortest = std::numeric_limits<double>::infinity();
  for (const Entry& entry : entries_) {
    for (double tau : entry.relaxation.tau_s) shortest = std::min(shortest, tau);
  }
  return shortest;
}

}  // namespace pba
