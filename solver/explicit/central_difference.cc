#include "explicit/central_difference.h"

#include <cmath>

namespace pba {

CentralDifference::CentralDifference(const Eigen::VectorXd& node_mass,
                                     const std::vector<PrescribedDof>& prescribed, double damping,
                                     const ThreadContext& threads)
    : node_mass_(node_mass), prescribed_(prescribed), damping_(damping), threads_(threads) {}

StepWork CentralDifference::Advance(const StepForces& forces, const StepTimes& times,
                                    const std::vector<char>& orphan, Eigen::VectorXd* u_out,
                                    Eigen::VectorXd* v_out) const {
  const Eigen::VectorXd& f_int = *forces.internal;
  const Eigen::VectorXd& f_ext = *forces.external;
  const Eigen::VectorXd& f_contact = *forces.contact;
  Eigen::VectorXd& u = *u_out;
  Eigen::VectorXd& v = *v_out;
  const double dt_prev = times.dt_prev, dt_next = times.dt_next;
  const double dt_mid = 0.5 * (dt_prev + dt_next);
  const double a_half = times.amplitude_half, a_next = times.amplitude_next;
  const double alpha = damping_;
  const int n_dofs = static_cast<int>(u.size());
  double w_int_a = 0, w_int_b = 0, w_ext_a = 0, w_ext_b = 0, w_damp_a = 0, w_damp_b = 0, w_c_a = 0,
         w_c_b = 0, kinetic = 0;
  bool finite = true;
#pragma omp parallel for schedule(static) reduction(+ : w_int_a, w_int_b, w_ext_a, w_ext_b, \
                                                        w_damp_a, w_damp_b, w_c_a, w_c_b, kinetic) \
    reduction(&& : finite) num_threads(threads_.threads())
  for (int i = 0; i < n_dofs; ++i) {
    const double m = node_mass_(i / 3);
    const double v_old = v(i);
    double v_new;
    double reaction = 0;
    const PrescribedDof& p = prescribed_[i];
    if (p.kind == PrescribedDof::kVelocity) {
      v_new = p.value * a_half;
    } else if (p.kind == PrescribedDof::kDisplacement) {
      v_new = (p.value * a_next - u(i)) / dt_next;
    } else if (m > 0 && (orphan.empty() || !orphan[i / 3])) {
      const double acc = (f_ext(i) + f_contact(i) - f_int(i)) / m;
      const double h = 0.5 * alpha * dt_mid;
      v_new = ((1 - h) * v_old + dt_mid * acc) / (1 + h);
    } else {
      v_new = 0;
    }
    if (p.kind != PrescribedDof::kFree && dt_mid > 0) {
      // The force that holds the motion: M a + f_int - f_ext - f_contact.
      reaction = m * (v_new - v_old) / dt_mid + f_int(i) - f_ext(i) - f_contact(i);
    }
    const double du_prev = dt_prev * v_old, du_next = dt_next * v_new;
    const double v_mid = 0.5 * (v_old + v_new);
    w_int_a += 0.5 * f_int(i) * du_prev, w_int_b += 0.5 * f_int(i) * du_next;
    const double applied = f_ext(i) + reaction;
    w_ext_a += 0.5 * applied * du_prev, w_ext_b += 0.5 * applied * du_next;
    w_c_a += 0.5 * f_contact(i) * du_prev, w_c_b += 0.5 * f_contact(i) * du_next;
    if (p.kind == PrescribedDof::kFree && alpha > 0) {
      const double damping = alpha * m * v_mid;
      w_damp_a += 0.5 * damping * du_prev, w_damp_b += 0.5 * damping * du_next;
    }
    kinetic += 0.5 * m * v_mid * v_mid;
    v(i) = v_new;
    u(i) += du_next;
    finite = finite && std::isfinite(v_new);
  }
  StepWork work;
  work.internal_before = w_int_a, work.internal_after = w_int_b;
  work.external_before = w_ext_a, work.external_after = w_ext_b;
  work.damping_before = w_damp_a, work.damping_after = w_damp_b;
  work.contact_before = w_c_a, work.contact_after = w_c_b;
  work.kinetic = kinetic;
  work.finite = finite;
  return work;
}

}  // namespace pba
