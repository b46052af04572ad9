// Quasi-linear viscoelasticity (QLV) at one material point: a Prony-series
// relaxation of the isochoric stress of any hyperelastic model, the
// volumetric response staying elastic (DOMAIN.md eq. 2.31,
// mu(t) = mu0 [1 - sum_k g_k (1 - exp(-t/tau_k))]).
//
// The viscous isochoric second Piola-Kirchhoff stress is the hereditary
// integral
//   S_visc(t) = int_0^t G(t - s) dS_iso/ds ds,
//   G(t) = g_inf + sum_k g_k exp(-t/tau_k),  g_inf = 1 - sum_k g_k,
// written with one internal variable per term (the part of the stress that
// has not yet relaxed, as in Simo and Hughes, Computational Inelasticity,
// section 10.3):
//   H_k(t) = g_k int_0^t exp(-(t - s)/tau_k) dS_iso/ds ds,
//   S_visc = g_inf S_iso + sum_k H_k = S_iso - sum_k (g_k S_iso - H_k).
// Over a step dt with S_iso linear in time the integral is exact:
//   H_k^{n+1} = exp(-dt/tau_k) H_k^n
//             + g_k (1 - exp(-dt/tau_k)) tau_k/dt (S_iso^{n+1} - S_iso^n),
// so the error of a ramp comes only from S_iso(t) not being linear within a
// step: second order in dt. The algorithmic tangent follows by
// differentiating the update with respect to S_iso^{n+1}:
//   C = C_vol + [g_inf + sum_k g_k (1 - exp(-dt/tau_k)) tau_k/dt] C_iso,
// which tends to the instantaneous C_vol + C_iso for dt << tau and to the
// long-term C_vol + g_inf C_iso for dt >> tau.
//
// Independent of the element code: the caller keeps one ViscoelasticPoint
// per quadrature point and commits it once a time step has converged.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "material/hyperelastic.h"
#include "material/voigt.h"
#include "pba/status.h"

namespace pba {

// Normalised Prony series: G(t)/G0 = 1 - sum_k g_k (1 - exp(-t/tau_k)).
struct PronySeries {
  std::vector<double> g;      // relative moduli g_k [-], each >= 0, sum < 1
  std::vector<double> tau_s;  // relaxation times tau_k [s], each > 0

  // Names bad fields as path + ".g[1]", ".tau_s[0]"; with an empty path the
  // field is "g[1]".
  Status Validate(const std::string& path = "") const;
  // g_inf = 1 - sum_k g_k = mu_inf / mu0.
  double LongTermFactor() const;
  // G(t)/G0 at time t >= 0 after a step [-].
  double Relaxation(double t_s) const;
};

// G(t) = G_inf + (G0 - G_inf) exp(-beta t) (DOMAIN.md, forms 1.5 and 2.2):
// one term with g = 1 - G_inf/G0 and tau = 1/beta.
PronySeries FromExponential(double g_inf_over_g0, double beta_per_s);

// G(t) = G_inf + sum_i G_i exp(-t/tau_i) with moduli in Pa (the rat-brain
// tables): G0 = G_inf + sum_i G_i and g_i = G_i/G0. Validate() the result; a
// size mismatch between g_i and tau_i is reported there.
PronySeries FromModuli(double g_inf, const std::vector<double>& g_i,
                       const std::vector<double>& tau_i);

// The relaxation state of one material point, flat: the committed S_iso^n,
// then H_1^n .. H_m^n, six numbers each (Voigt), 6 (m + 1) in all, zero
// at the start (unstressed, fully relaxed). Both engines keep it in this
// layout (MaterialField per element of the implicit analyses, TledModel per
// element of the explicit engine), and restart files store it as is.
inline std::size_t PronyStateSize(std::size_t terms) { return 6 * (terms + 1); }

// One step of dt for a series, independent of the point: within the step
// the viscous isochoric stress is affine in the end-of-step S_iso,
//   S_visc = alpha S_iso^{n+1} + offset^n,
//   alpha = g_inf + sum_k weight_k,  weight_k = g_k (1 - exp(-dt/tau_k)) tau_k/dt,
//   offset^n = sum_k (decay_k H_k^n - weight_k S_iso^n),  decay_k = exp(-dt/tau_k),
// so that alpha W_iso + offset^n . E is an incremental potential whose
// derivatives are S_visc and alpha C_iso (the elements' Newton iterations
// and line searches use it as an energy). This is the one place the
// relaxation is integrated: the implicit analyses take Offset within a step
// and Relax at its end, the explicit engine Relax at every evaluation (each
// is a step).
struct ViscousStep {
  double alpha = 1;
  double long_term = 1;  // g_inf
  std::vector<double> decay, weight;

  // `series` must have passed Validate(); dt_s > 0.
  static ViscousStep Of(const PronySeries& series, double dt_s);
  // offset^n of a point's state (PronyStateSize(terms) numbers).
  Vector6d Offset(const double* state) const;
  // Moves a point's state to the end of the step, given the step's final
  // S_iso: H_k^{n+1} = decay_k H_k^n + weight_k (S_iso^{n+1} - S_iso^n),
  // then S_iso^n <- S_iso^{n+1}. Returns the step's viscous stress
  // S_visc = g_inf S_iso^{n+1} + sum_k H_k^{n+1} (= alpha S_iso^{n+1} +
  // offset^n up to rounding).
  Vector6d Relax(const Vector6d& s_iso, double* state) const;
};

// History of one material point. Starts unstressed and fully relaxed
// (S_iso = 0 and H_k = 0 at t = 0, which holds at F = I for the uncoupled
// models).
class ViscoelasticPoint {
 public:
  // Trial update to deformation `f` at the end of a step of `dt_s` > 0 from
  // the committed state; the committed state is not changed, so a Newton
  // iteration may call it again. Returns the total second Piola-Kirchhoff
  // stress and the algorithmic tangent (either may be null). `series` must
  // have passed Validate() and be the same on every call.
  Status Update(const HyperelasticMaterial& material, const PronySeries& series,
                const Eigen::Matrix3d& f, double dt_s, Vector6d* stress, Matrix6d* tangent);
  // Accepts the last trial update as the state at the end of the step.
  void Commit();

 private:
  // Committed and trial states (PronyStateSize; empty before the first update).
  std::vector<double> state_, trial_state_;
  bool has_trial_ = false;
};

// Homogeneous uniaxial stress under a constant stretch rate, for
// verification: F = diag(lambda, l, l) with lambda = 1 +- rate t and the
// lateral stretch l found by Newton in every step so that the lateral stress
// vanishes; `steps` equal steps to `final_stretch`, then `hold_steps` equal
// steps at constant stretch for `hold_s` seconds (0 for none). Returns the
// nominal (first Piola-Kirchhoff) axial stress at the end [Pa].
Status UniaxialRamp(const HyperelasticMaterial& material, const PronySeries& series,
                    double stretch_rate_per_s, double final_stretch, int steps,
                    double* nominal_stress_pa);
Status UniaxialRampAndHold(const HyperelasticMaterial& material, const PronySeries& series,
                           double stretch_rate_per_s, double final_stretch, int steps,
                           double hold_s, int hold_steps, double* nominal_stress_pa);

}  // namespace pba
