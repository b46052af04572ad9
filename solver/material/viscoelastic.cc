#include "material/viscoelastic.h"

#include <cmath>

namespace pba {
namespace {

std::string Field(const std::string& path, const std::string& name, std::size_t index) {
  return (path.empty() ? "" : path + ".") + name + "[" + std::to_string(index) + "]";
}

// (1 - exp(-x))/x for x = dt/tau > 0: the weight of the step's stress
// increment in H_k. expm1 keeps it accurate when dt << tau, where the naive
// form loses all digits.
double StepWeight(double dt_s, double tau_s) {
  const double x = dt_s / tau_s;
  return -std::expm1(-x) / x;
}

}  // namespace

Status PronySeries::Validate(const std::string& path) const {
  const std::string prefix = path.empty() ? "" : path + ".";
  if (g.size() != tau_s.size()) {
    return Status::InvalidArgument(prefix + "tau_s", "needs one relaxation time per g, got " +
                                                         std::to_string(tau_s.size()) + " for " +
                                                         std::to_string(g.size()));
  }
  double sum = 0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    PBA_RETURN_IF_ERROR(RequireFinite(g[k], Field(path, "g", k)));
    if (g[k] < 0) {
      return Status::InvalidArgument(Field(path, "g", k), "must be >= 0, got " + ShortNumber(g[k]));
    }
    PBA_RETURN_IF_ERROR(RequirePositive(tau_s[k], Field(path, "tau_s", k)));
    sum += g[k];
  }
  // sum g = 1 would relax the shear stiffness to zero: no long-term
  // equilibrium under a held load.
  if (!(sum < 1)) {
    return Status::InvalidArgument(prefix + "g",
                                   "must sum to less than 1, got " + ShortNumber(sum));
  }
  return Status::Ok();
}

double PronySeries::LongTermFactor() const {
  double sum = 0;
  for (double gk : g) sum += gk;
  return 1 - sum;
}

double PronySeries::Relaxation(double t_s) const {
  double value = 1;
  for (std::size_t k = 0; k < g.size(); ++k) value += g[k] * std::expm1(-t_s / tau_s[k]);
  return value;
}

PronySeries FromExponential(double g_inf_over_g0, double beta_per_s) {
  PronySeries series;
  series.g = {1 - g_inf_over_g0};
  series.tau_s = {1 / beta_per_s};
  return series;
}

PronySeries FromModuli(double g_inf, const std::vector<double>& g_i,
                       const std::vector<double>& tau_i) {
  double g0 = g_inf;
  for (double gi : g_i) g0 += gi;
  PronySeries series;
  for (double gi : g_i) series.g.push_back(gi / g0);
  series.tau_s = tau_i;
  return series;
}

ViscousStep ViscousStep::Of(const PronySeries& series, double dt_s) {
  ViscousStep step;
  step.alpha = step.long_term = series.LongTermFactor();
  for (std::size_t k = 0; k < series.g.size(); ++k) {
    step.decay.push_back(std::exp(-dt_s / series.tau_s[k]));
    step.weight.push_back(series.g[k] * StepWeight(dt_s, series.tau_s[k]));
    step.alpha += step.weight.back();
  }
  return step;
}

Vector6d ViscousStep::Offset(const double* state) const {
  const Eigen::Map<const Vector6d> s_iso(state);
  Vector6d offset = Vector6d::Zero();
  for (std::size_t k = 0; k < weight.size(); ++k) {
    offset -= weight[k] * s_iso;
    offset += decay[k] * Eigen::Map<const Vector6d>(state + 6 * (k + 1));
  }
  return offset;
}

Vector6d ViscousStep::Relax(const Vector6d& s_iso, double* state) const {
  Eigen::Map<Vector6d> s_old(state);
  const Vector6d ds = s_iso - s_old;
  Vector6d s_visc = long_term * s_iso;
  for (std::size_t k = 0; k < weight.size(); ++k) {
    Eigen::Map<Vector6d> h(state + 6 * (k + 1));
    h = decay[k] * h + weight[k] * ds;
    s_visc += h;
  }
  s_old = s_iso;
  return s_visc;
}

Status ViscoelasticPoint::Update(const HyperelasticMaterial& material, const PronySeries& series,
                                 const Eigen::Matrix3d& f, double dt_s, Vector6d* stress,
                                 Matrix6d* tangent) {
  if (!(dt_s > 0) || !std::isfinite(dt_s)) {
    return Status::InvalidArgument("dt_s", "must be > 0, got " + ShortNumber(dt_s));
  }
  if (!IsAdmissible(f)) {
    return Status::Numerical("viscoelastic update: det F <= 0 or F not finite");
  }
  if (state_.size() != PronyStateSize(series.g.size())) {
    state_.assign(PronyStateSize(series.g.size()), 0.0);
  }

  Vector6d s_iso;
  Matrix6d c_iso;
  material.Isochoric(f, nullptr, &s_iso, tangent ? &c_iso : nullptr);
  // The volumetric part alone, through the invariant chain rule with a zero
  // isochoric energy: S_vol = J U'(J) C^-1 and its tangent.
  const InvariantState invariants = ComputeInvariants(f);
  Vector6d s_vol;
  Matrix6d c_vol;
  InvariantResponse(invariants, IsochoricInvariantEnergy{}, material.Volumetric(invariants.j),
                    &s_vol, tangent ? &c_vol : nullptr);

  const ViscousStep step = ViscousStep::Of(series, dt_s);
  const Vector6d s_visc = step.alpha * s_iso + step.Offset(state_.data());
  trial_state_ = state_;
  step.Relax(s_iso, trial_state_.data());
  has_trial_ = true;

  if (stress) *stress = s_vol + s_visc;
  if (tangent) *tangent = c_vol + step.alpha * c_iso;
  return Status::Ok();
}

void ViscoelasticPoint::Commit() {
  if (!has_trial_) return;
  state_ = trial_state_;
  has_trial_ = false;
}

Status UniaxialRamp(const HyperelasticMaterial& material, const PronySeries& series,
                    double stretch_rate_per_s, double final_stretch, int steps,
                    double* nominal_stress_pa) {
  return UniaxialRampAndHold(material, series, stretch_rate_per_s, final_stretch, steps, 0, 0,
                             nominal_stress_pa);
}

Status UniaxialRampAndHold(const HyperelasticMaterial& material, const PronySeries& series,
                           double stretch_rate_per_s, double final_stretch, int steps,
                           double hold_s, int hold_steps, double* nominal_stress_pa) {
  PBA_RETURN_IF_ERROR(series.Validate("series"));
  PBA_RETURN_IF_ERROR(RequirePositive(stretch_rate_per_s, "stretch_rate_per_s"));
  PBA_RETURN_IF_ERROR(RequirePositive(final_stretch, "final_stretch"));
  if (final_stretch == 1) {
    return Status::InvalidArgument("final_stretch", "must differ from 1");
  }
  if (steps < 1) return Status::InvalidArgument("steps", "must be >= 1");
  if (hold_steps < 0 || (hold_steps > 0 && !(hold_s > 0))) {
    return Status::InvalidArgument("hold_s", "a hold needs hold_s > 0 and hold_steps >= 1");
  }

  const double ramp_s = std::abs(final_stretch - 1) / stretch_rate_per_s;
  const double direction = final_stretch > 1 ? 1 : -1;
  ViscoelasticPoint point;
  double lateral = 1;
  double axial = 1;
  Vector6d stress = Vector6d::Zero();
  const int total = steps + hold_steps;
  for (int n = 1; n <= total; ++n) {
    double dt;
    if (n <= steps) {
      dt = ramp_s / steps;
      // From n, not by accumulation, so the last ramp step lands on
      // final_stretch exactly.
      axial = n == steps ? final_stretch : 1 + direction * stretch_rate_per_s * dt * n;
    } else {
      dt = hold_s / hold_steps;
    }
    // Newton on the lateral stretch l: S_yy(l) = 0, with
    // dS_yy/dl = (C_yy,yy + C_yy,zz) dE_yy/dl and dE_yy/dl = l. The
    // algorithmic tangent makes it quadratic.
    bool converged = false;
    for (int it = 0; it < 50; ++it) {
      Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
      f(0, 0) = axial;
      f(1, 1) = f(2, 2) = lateral;
      Matrix6d c;
      PBA_RETURN_IF_ERROR(point.Update(material, series, f, dt, &stress, &c));
      const double scale = std::abs(stress(0)) + material.ShearModulus();
      if (std::abs(stress(1)) <= 1e-10 * scale) {
        converged = true;
        break;
      }
      const double slope = (c(1, 1) + c(1, 2)) * lateral;
      if (!(slope > 0)) return Status::Numerical("uniaxial ramp: lateral tangent not positive");
      double next = lateral - stress(1) / slope;
      // Keep the stretch positive; halving towards zero is enough for the
      // monotone lateral response.
      if (!(next > 0)) next = 0.5 * lateral;
      lateral = next;
    }
    if (!converged) {
      return Status::Numerical("uniaxial ramp: lateral Newton did not converge in step " +
                               std::to_string(n));
    }
    point.Commit();
  }
  // P = F S; for a diagonal F the axial component is lambda S_xx.
  *nominal_stress_pa = axial * stress(0);
  return Status::Ok();
}

}  // namespace pba
