// Zienkiewicz-Zhu a-posteriori error estimate, for every element shape.
//
// On linear tetrahedra the element stresses sigma_h (constant per tet) are smoothed into a
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

// The stress of element e at natural point xi [Pa], Voigt order: the
// finite-element stress the estimate recovers (called concurrently).
using ElementStress = std::function<Vector6d(int element, const Eigen::Vector3d& xi)>;

// The estimate, the recovery chosen by the mesh's element shape: 10-node
// tetrahedra and 8-node hexahedra sample `stress` at their nodes and
// integration points (EstimateZzErrorTet10, EstimateZzErrorHex8 below);
// 4-node tetrahedra, whose stress is constant, sample it once per element at
// the centroid xi = (1/4, 1/4, 1/4) and take the element volumes of
// fem/tet4.h (EstimateZzError with stresses and volumes). Each element's
// error and energy are measured with its own material's compliance,
// `elasticity.Compliance(e)`; the estimate runs on `threads` (the solve's).
// The one entry point of the analyses.
ErrorEstimateResult EstimateZzError(const Mesh& mesh, const ElementStress& stress,
                                    const ElasticityField& elasticity,
                                    const ThreadContext& threads);

// What the summary says of the estimate (Summary::error.method): of the
// small-strain stress, by the mesh's element shape, e.g. "Zienkiewicz-Zhu
// stress recovery (nodal averaging, quadratic)"; of the second
// Piola-Kirchhoff stress (the finite-strain analyses), one text for every
// shape.
enum class ZzStress { kSmallStrain, kSecondPiolaKirchhoff };
std::string ZzMethod(const Mesh& mesh, ZzStress stress = ZzStress::kSmallStrain);

// The per-shape estimates behind EstimateZzError.
//
// 4-node tetrahedra: `stress` is elements x 6 (Voigt), `volume` per element
// [m^3].
ErrorEstimateResult EstimateZzError(const Mesh& mesh, const std::vector<double>& stress,
                                    const std::vector<double>& volume,
                                    const ElasticityField& elasticity,
                                    const ThreadContext& threads);

// 10-node tetrahedra (a quadratic mesh), whose stress varies within the
// element: `stress(e, xi)` with xi the natural point of fem/tet10.h. The
// recovered field takes at each of the 10 nodes the volume-weighted average
// of the stresses the elements around it give there, and is interpolated
// with the quadratic shape functions; the integrals use the 14-point
// degree-5 rule.
ErrorEstimateResult EstimateZzErrorTet10(const Mesh& mesh, const ElementStress& stress,
                                         const ElasticityField& elasticity,
                                         const ThreadContext& threads);

// 8-node hexahedra (a hexahedral mesh): nodal averages at the 8 corners,
// trilinear interpolation, the 2 x 2 x 2 rule; `stress(e, xi)` with xi in
// [-1, 1]^3 (fem/hex8.h).
ErrorEstimateResult EstimateZzErrorHex8(const Mesh& mesh, const ElementStress& stress,
                                        const ElasticityField& elasticity,
                                        const ThreadContext& threads);

}  // namespace pba
