// Zienkiewicz-Zhu a-posteriori error estimate for linear tetrahedra.
//
// The element stresses sigma_h (constant per tet) are smoothed into a
// continuous field sigma* by volume-weighted nodal averaging; the error of
// element e is estimated in the energy norm,
//   eta_e^2 = integral over e of (sigma* - sigma_h) : C : (sigma* - sigma_h) dV
// (C the compliance), by a 4-point rule exact for the quadratic integrand;
// the relative error is eta = sqrt(sum eta_e^2 / (sum eta_e^2 + ||u||_E^2)),
// ||u||_E^2 = integral sigma_h : C : sigma_h dV = 2 x strain energy
// (Zienkiewicz & Zhu 1987, Int. J. Numer. Meth. Eng. 24:337).
#pragma once

#include <vector>

#include "fem/tet4.h"
#include "mesh/mesh.h"

namespace pba {

struct ErrorEstimateResult {
  double relative_error = 0;          // eta, a fraction
  std::vector<double> element_share;  // eta_e^2 / sum eta_e^2, per element
};

// `stress` is elements x 6 (Voigt), `volume` per element [m^3].
ErrorEstimateResult EstimateZzError(const Mesh& mesh, const std::vector<double>& stress,
                                    const std::vector<double>& volume, const Matrix6d& compliance);

}  // namespace pba
