// The material of every element of a finite-strain model: its hyperelastic
// material, the relaxation of its isochoric stress (material/viscoelastic.h)
// and its growth, with the history of its integration point through time.
//
// A model asks At(e) for the element's response in the current step, a
// HyperelasticMaterial whose isochoric part is the viscous stress of the
// step and whose volumetric part is measured from the grown volume:
//
//   W_iso,step(F) = alpha theta^3 W_iso(F) + offset_e . E,
//   U_step(J)     = theta^3 U(J / theta^3),
//
// with alpha and offset_e those of ViscousStep for the step's dt, and
// theta = 1 + growth_strain a(t) the isotropic growth stretch, F = F_e theta I
// (an isotropic growth leaves the isochoric part of F unchanged, so growth
// enters only through the volume: the element's stress-free volume becomes
// theta^3 times its own). Both are potentials within a step, so Newton's
// line search keeps an energy.
//
// History is kept per element: only one-point elements (TET4, TET4_ANP)
// may relax or grow; multi-point ones take per-element materials alone (the
// finite-strain analysis refuses relaxation or growth on them, naming the
// element).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/thread_context.h"
#include "material/hyperelastic.h"
#include "material/viscoelastic.h"
#include "pba/status.h"

namespace pba {

// One element's response in the current step (see the file comment).
class ElementResponse final : public HyperelasticMaterial {
 public:
  ElementResponse(const HyperelasticMaterial& base, double alpha, double volume_factor,
                  const Vector6d& offset)
      : base_(base), alpha_(alpha), volume_factor_(volume_factor), offset_(offset) {}

  double Energy(const Eigen::Matrix3d& f) const override;
  Vector6d Stress(const Eigen::Matrix3d& f) const override;
  Matrix6d Tangent(const Eigen::Matrix3d& f) const override;
  void Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                 Matrix6d* tangent) const override;
  ScalarDerivatives Volumetric(double j) const override;
  double ShearModulus() const override { return base_.ShearModulus(); }
  double BulkModulus() const override { return base_.BulkModulus(); }
  std::string Describe() const override { return base_.Describe(); }

 private:
  const HyperelasticMaterial& base_;
  double alpha_;          // viscous scale of the isochoric stress in this step
  double volume_factor_;  // theta^3
  Vector6d offset_;       // viscous offset of this step [Pa]
};

class MaterialField {
 public:
  // One distinct material: the model, its relaxation (no terms: elastic) and
  // its growth strain at amplitude 1.
  struct Entry {
    std::shared_ptr<const HyperelasticMaterial> material;
    PronySeries relaxation;
    double growth_strain = 0;
    std::string name;  // for messages and summaries, e.g. "Putamen"
    // A constant factor on the isochoric stress (relaxation terms taken as
    // already relaxed, see ReduceRelaxation).
    double isochoric_scale = 1;
  };

  // `entries[of_element[e]]` is element e's material; entries must be
  // validated (PronySeries::Validate) and of_element in range. BeginStep
  // and Commit run on `threads` (the solve's).
  MaterialField(std::vector<Entry> entries, std::vector<int> of_element,
                const ThreadContext& threads);
  // Every element the same elastic material, not owned (it must outlive
  // the field).
  static std::unique_ptr<MaterialField> Uniform(const HyperelasticMaterial& material, int elements);

  int num_elements() const { return static_cast<int>(of_element_.size()); }
  const std::vector<Entry>& entries() const { return entries_; }
  int entry_of(int e) const { return of_element_[e]; }
  const HyperelasticMaterial& Base(int e) const { return *entries_[of_element_[e]].material; }

  bool viscous() const { return viscous_; }
  bool grows() const { return grows_; }
  // True when one elastic material fills the body without growth.
  bool uniform() const { return entries_.size() == 1 && !viscous_ && !grows_; }

  // The response of element e in the current step.
  ElementResponse At(int e) const;
  // theta^3 of element e at the current amplitude.
  double VolumeFactor(int e) const { return volume_factor_[of_element_[e]]; }

  // Sets the step: its length dt_s (0: an instantaneous step, the elastic
  // response of a static analysis) and the growth amplitude a(t) at its end.
  // The committed history is not changed, so a step may be begun again with
  // another dt after a failed attempt.
  void BeginStep(double dt_s, double amplitude);
  // Accepts the end of the step: `f[e]` is element e's deformation gradient
  // there (one point per element). Parallel over elements.
  void Commit(const std::vector<Eigen::Matrix3d>& f);

  // The history as flat numbers (a restart file) and back; Restore fails on
  // a length that does not fit this field.
  std::vector<double> SaveHistory() const;
  Status RestoreHistory(const std::vector<double>& values);

  // The shortest relaxation time of any material [s]; +infinity when none relaxes.
  double ShortestRelaxationTime() const;

  // While one lives, At(e) is every element's fully relaxed response: its
  // isochoric part scaled by its series' long-term factor g_inf (1 without
  // relaxation), no history, the growth of the current step. A model's
  // energy is then Psi_inf = U + g_inf W_iso, the free energy a relaxing
  // body keeps once every term has relaxed: its stored energy less the
  // unrelaxed terms' share, so a lower bound of it, and equal to it when
  // relaxed. (Within a step At(e)'s energy is the step's incremental
  // potential, which is no stored energy and may be negative.) The step's
  // response is back when it ends.
  class LongTermResponse {
   public:
    explicit LongTermResponse(MaterialField* field);
    ~LongTermResponse();
    LongTermResponse(const LongTermResponse&) = delete;
    LongTermResponse& operator=(const LongTermResponse&) = delete;

   private:
    MaterialField* field_;
    std::vector<ViscousStep> steps_;
    std::vector<Vector6d> offset_;
  };

 private:
  std::vector<Entry> entries_;
  std::vector<int> of_element_;
  ThreadContext threads_;
  bool viscous_ = false;
  bool grows_ = false;
  // Per entry, for the current step.
  std::vector<ViscousStep> steps_;
  std::vector<double> volume_factor_;
  // Per element: the committed relaxation state (PronyStateSize of its
  // material's terms, from state_start_[e]; all of them in SaveHistory's
  // order) and the offset of the current step (all empty without
  // relaxation).
  std::vector<double> state_;
  std::vector<std::size_t> state_start_;
  std::vector<Vector6d> offset_;
};

// A series for loading that cannot resolve some of its terms: those with
// tau < relaxed_below_s have relaxed before anything is measured (each
// scales the modulus by 1 - g_k and the others' g by 1 / (1 - g_k):
// 1 - sum_j g_j (1 - e^{-t/tau_j}) with e^{-t/tau_k} = 0), those with tau >
// frozen_above_s (when > 0) never relax (e^{-t/tau_k} = 1: the term
// vanishes). Returns the remaining series and the scale.
PronySeries ReduceRelaxation(const PronySeries& series, double relaxed_below_s,
                             double frozen_above_s, double* scale);

// Green-Lagrange strain of F, Voigt with engineering shear.
Vector6d GreenLagrangeVoigt(const Eigen::Matrix3d& f);
// Euler-Almansi strain of F, (I - (F F^T)^-1) / 2, Voigt with engineering
// shear.
Vector6d AlmansiVoigt(const Eigen::Matrix3d& f);

}  // namespace pba
