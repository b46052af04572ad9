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
    state_start_.resize(of_element_.size() + 1, 0);
    for (std::size_t e = 0; e < of_element_.size(); ++e) {
      state_start_[e + 1] =
          state_start_[e] + PronyStateSize(entries_[of_element_[e]].relaxation.g.size());
    }
    state_.assign(state_start_.back(), 0.0);
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
  // Elastic and of one material: BeginStep and Commit have no pass to run
  // in parallel.
  return std::make_unique<MaterialField>(std::move(entries), std::vector<int>(elements, 0),
                                         ThreadContext(1));
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
  for (int e = 0; e < ne; ++e) offset_[e] = steps_[of_element_[e]].Offset(&state_[state_start_[e]]);
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
    steps_[k].Relax(s_iso, &state_[state_start_[e]]);
  }
}

std::vector<double> MaterialField::SaveHistory() const { return state_; }

Status MaterialField::RestoreHistory(const std::vector<double>& values) {
  if (values.size() != state_.size()) {
    return Status::InvalidArgument(
        "history", "holds " + std::to_string(values.size()) + " numbers where this model keeps " +
                       std::to_string(state_.size()) + " (a different mesh or material?)");
  }
  state_ = values;
  return Status::Ok();
}

double MaterialField::ShortestRelaxationTime() const {
  double shortest = std::numeric_limits<double>::infinity();
  for (const Entry& entry : entries_) {
    for (double tau : entry.relaxation.tau_s) shortest = std::min(shortest, tau);
  }
  return shortest;
}

MaterialField::LongTermResponse::LongTermResponse(MaterialField* field)
    : field_(field), steps_(field->steps_), offset_(field->offset_) {
  for (std::size_t k = 0; k < field_->entries_.size(); ++k) {
    ViscousStep relaxed;
    relaxed.alpha = relaxed.long_term = field_->entries_[k].relaxation.LongTermFactor();
    field_->steps_[k] = relaxed;
  }
  for (Vector6d& offset : field_->offset_) offset.setZero();
}

MaterialField::LongTermResponse::~LongTermResponse() {
  field_->steps_ = std::move(steps_);
  field_->offset_ = std::move(offset_);
}

}  // namespace pba
