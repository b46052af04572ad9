// Zienkiewicz-Zhu a-posteriori error estimate for linear tetrahedra.
//
// The element stresses sigma_h (constant per tet) are smoothed into a
// continuous field sigma* by volume-weighted nodal averaging; the error of
// element e is estimated in the energy norm,
//   eta_e^2 = integral over e of (sigma* - sigma_h) : C : (sigma* - sigma_h) dV
// (C the compliance of the element's own material), by a 4-point rule exact for the quadratic
// integrand; the relative error is eta = sqrt(sum eta_e^2 / (sum eta_e^2 + ||u||_E^2)),
// ||u||_E^2 = integral sigma_h : C : sigma_h dV = 2 x strain energy
// (Zienkiewicz & Zhu 1987, Int. J. Numer. Meth. Eng. 24:337).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/thread_context.h"
#include "fem/tet4.h"
#include "material/linear_elastic.h"
#include "mesh/mesh.h"

namespace pba {

struct ErrorEstimateResult {
  double relative_error = 0;            // eta, a fraction
  std::vector<double> element_share;    // eta_e^2 / sum eta_e^2, per element
  std::vector<double> element_error2;   // eta_e^2, per element
  std::vector<double> element_energy2;  // ||u_h||_E^2 on element e
};

// The estimate of each region of the mesh (Mesh::region_names; one region
// named `body` when the mesh has none): eta_r = sqrt(E_r^2 / (E_r^2 +
// U_r^2)) over the region's elements, and its share of the total E^2.
struct RegionError {
  std::string name;
  int64_t elements = 0;
  double relative_error = 0;
  double share = 0;
};
std::vector<RegionError> ErrorByRegion(const Mesh& mesh, const ErrorEstimateResult& estimate,
                                       const std::string& body);

// `stress` is elements x 6 (Voigt), `volume` per element [m^3]; each
// element's error and energy are measured with its own material's
// compliance, `elasticity.Compliance(e)`. The estimates run on `threads`
// (the solve's).
ErrorEstimateResult EstimateZzError(const Mesh& mesh, const std::vector<double>& stress,
                                    const std::vector<double>& volume,
                                    const ElasticityField& elasticity,
                                    const ThreadContext& threads = ThreadContext());

// The same estimate for 10-node tetrahedra (a quadratic mesh), whose stress
// varies within the element: `stress(e, xi)` is the finite-element stress
// of element e at natural point xi (fem/tet10.h). The recovered field takes
// at each of the 10 nodes the volume-weighted average of the stresses the
// elements around it give there, and is interpolated with the quadratic
// shape functions; the integrals use the 14-point degree-5 rule.
// `stress` is called concurrently.
using ElementStress = std::function<Vector6d(int element, const Eigen::Vector3d& xi)>;
ErrorEstimateResult EstimateZzErrorTet10(const Mesh& mesh, const ElementStress& stress,
                                         const ElasticityField& elasticity,
                                         const ThreadContext& threads = ThreadContext());

// The same for 8-node hexahedra (a hexahedral mesh): nodal averages at the
// 8 corners, trilinear interpolation, the 2 x 2 x 2 rule; `stress(e, xi)`
// with xi in [-1, 1]^3 (fem/hex8.h).
ErrorEstimateResult EstimateZzErrorHex8(const Mesh& mesh, const ElementStress& stress,
                                        const ElasticityField& elasticity,
                                        const ThreadContext& threads = ThreadContext());

}  // namespace pba
