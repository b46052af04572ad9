// The energy balance of an explicit run,
//   kinetic + internal + hourglass + contact + damping + eroded
//     = external work + the kinetic energy given at t = 0 + mass scaling,
// each work a trapezoidal sum over the steps: W^n = W^(n-1) +
// (f^(n-1) + f^n) . du^(n-1/2) / 2, kept as the part through t^n plus the
// half that waits for the next force.
#pragma once

#include <algorithm>
#include <cmath>

#include "explicit/central_difference.h"

namespace pba {

// One running work [J].
struct Work {
  double total = 0, carry = 0;
  // At step n: a = f^n . du^(n-1/2) / 2, b = f^n . du^(n+1/2) / 2.
  void Step(double a, double b) {
    total += carry + a;
    carry = b;
  }
};

// The energies of a run [J].
struct Energies {
  Work internal, external, damping, contact_nodes;
  double kinetic = 0, hourglass = 0, eroded_elements = 0, orphan_kinetic = 0;
  double initial_kinetic = 0;  // of the velocities given at t = 0
  double mass_scaling = 0;     // kinetic energy change by mass added during the run (<= 0)
  double body_work = 0;        // impactors' work on the tissue

  // The works of one central-difference step.
  void Add(const StepWork& w) {
    internal.Step(w.internal_before, w.internal_after);
    external.Step(w.external_before, w.external_after);
    damping.Step(w.damping_before, w.damping_after);
    contact_nodes.Step(w.contact_before, w.contact_after);
    kinetic = w.kinetic;
  }
  double Internal() const { return internal.total - hourglass - eroded_elements; }
  double Contact() const { return body_work - contact_nodes.total; }
  double External() const { return external.total + body_work; }
  double Eroded() const { return eroded_elements + orphan_kinetic; }
  // How far the balance is off [J].
  double Error() const {
    return std::abs(kinetic + Internal() + hourglass + Contact() + damping.total + Eroded() -
                    External() - initial_kinetic - mass_scaling);
  }
  // The size of the energies, against which the error is judged [J].
  double Scale() const {
    return std::max({std::abs(External()), kinetic, std::abs(internal.total)});
  }
};

}  // namespace pba
