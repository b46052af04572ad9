// Dynamic relaxation (DYNAMIC_RELAXATION): the static answer of a
// finite-strain scene from the explicit engine, with no tangent matrix and
// no linear solve (Joldes, Wittek and Miller, Computation of
// intra-operative brain shift using dynamic relaxation, CMAME 198:3313,
// 2009; Underwood, in Computational Methods for Transient Analysis, 1983).
//
// The masses are fictitious: each element's density is chosen so that its
// stable step is the same, rho_e = (K + 4 mu / 3)(dt / (f l_e))^2 with
// dt = 1 and f the time_step_factor (0.9 unless given; the answer does not
// depend on the masses), which equalises the
// elements' frequencies. The loads and prescribed displacements are
// ramped to their full value over the first steps, then held; the motion
// is damped at c = 2 omega_min, omega_min^2 estimated every step by the
// Rayleigh quotient u.K_d u / u.M u with the diagonal stiffness K_d from
// the change of the internal force over the step (Underwood's adaptive
// damping), which is critical damping of the slowest mode.
//
// Convergence: the largest out-of-balance force on a free unknown below
// tol times the largest load or reaction, and the distance to the answer,
// estimated from the rate rho at which the displacement increments shrink
// (|u* - u^n| <= rho / (1 - rho) |u^n - u^(n-1)|), below tol times the
// largest displacement (Joldes et al. 2009's termination criterion).
#pragma once

#include "analysis/static_analysis.h"
#include "core/phase_clock.h"
#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

Status SolveDynamicRelaxation(const Problem& problem, PhaseClock* clock, Solution* solution,
                              StaticResult* result);

}  // namespace pba
