// Explicit dynamics (EXPLICIT_DYNAMIC): the central-difference time loop
// over the TLED elements (explicit/tled_model.h),
//
//   M a^n = f_ext(t^n) + f_contact(u^n, t^n) - f_int(u^n, v^(n-1/2)),
//   v^(n+1/2) = [(1 - alpha dt^n / 2) v^(n-1/2) + dt^n a^n] / (1 + alpha dt^n / 2),
//   u^(n+1) = u^n + dt^(n+1/2) v^(n+1/2),
//
// with lumped (diagonal) M, mass-proportional damping alpha, dt^n the mean
// of the half steps around t^n (Belytschko, Liu and Moran, Nonlinear Finite
// Elements for Continua and Structures, 2000, box 6.1). Prescribed
// velocities and displacements follow a(t); impactors push the tissue
// (explicit/impactor.h); sensors sample (explicit/sensors.h).
//
// The step is time_step_factor times the smallest stable step over the
// elements; every few steps the current one is recomputed (elements shrink
// as they compress, and the bulk viscosity shortens it) and the step
// shrinks when it must. The energy balance
//   kinetic + internal + hourglass + contact + damping + eroded
//     = external work + the kinetic energy given at t = 0
// (each work by the trapezoidal rule over the steps) is written every
// output interval. The run stops with kNumerical, naming the step, the time
// and the element, when an element inverts or a value stops being finite,
// or when the balance error exceeds 10 % of the energies: the signs of an
// integration that has become unstable.
#pragma once

#include "analysis/static_analysis.h"
#include "core/phase_clock.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

Status SolveExplicitDynamic(const Problem& problem, PhaseClock* clock, Solution* solution,
                            StaticResult* result);

}  // namespace pba
