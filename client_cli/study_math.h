// Mesh-convergence arithmetic of `pba study convergence`: the three-grid
// procedure of Celik, Ghia, Roache, Freitas, Coleman and Raad, "Procedure
// for estimation and reporting of uncertainty due to discretization in CFD
// applications", J. Fluids Eng. 130 (2008) 078001 (observed order,
// Richardson extrapolation, Roache's grid convergence index), and the
// relative change of a result from one mesh to the next. Pure functions: no
// I/O, no server.
#pragma once

#include <optional>
#include <string>

namespace pba::cli::study {

// How the three results behave as the mesh is refined, judged by
// e32 / e21 (e21 = f2 - f1 between the two finest meshes, e32 = f3 - f2
// between the two coarsest).
enum class Behaviour {
  kMonotone,       // e32 / e21 > 0 and an observed order p > 0 exists
  kOscillatory,    // e32 / e21 < 0: the result swings about its limit
  kDiverging,      // e32 / e21 > 0 but no p > 0 fits: the change grows on refinement
  kUnchanged,      // f1 = f2 = f3 (to rounding): nothing to extrapolate
  kIndeterminate,  // exactly one difference is zero: the order is unbounded or zero
};

// "monotone", "oscillatory", ...
std::string BehaviourName(Behaviour behaviour);

// The three-grid analysis. Mesh 1 is the finest, 3 the coarsest; h is each
// mesh's representative element size in any one unit (only ratios matter;
// Celik eq. 1: h = (volume / elements)^(1/3) in 3-D).
struct ThreeGrid {
  Behaviour behaviour = Behaviour::kIndeterminate;
  double r21 = 0, r32 = 0;  // refinement ratios h2/h1, h3/h2 (> 1)
  double e21 = 0, e32 = 0;  // f2 - f1, f3 - f2
  // |f1 - f2| / |f1| and |f2 - f3| / |f2| (Celik eq. 5a), fractions; unset
  // when the finer result is 0.
  std::optional<double> relative_change_21, relative_change_32;
  // Set when monotone (the Richardson extrapolate, Celik eq. 4; and for
  // unchanged results f1 itself):
  std::optional<double> order;               // observed order p (Celik eq. 3)
  std::optional<double> extrapolated;        // f_ext^21 = (r21^p f1 - f2) / (r21^p - 1)
  std::optional<double> extrapolated_error;  // |f_ext - f1| / |f_ext| (Celik eq. 5b), fraction
  std::optional<double> gci_fine;            // 1.25 e_a^21 / (r21^p - 1) (Celik eq. 5c), fraction
  std::optional<double> gci_coarse;          // 1.25 e_a^32 / (r32^p - 1), fraction
  // GCI_coarse / (r21^p GCI_fine): about 1 when the three meshes are in the
  // asymptotic range (Roache, Verification and Validation in Computational
  // Science and Engineering, 1998, section 5.9).
  std::optional<double> asymptotic_ratio;
  // Oscillatory: half the range of the three results relative to |f1|, the
  // uncertainty Stern, Wilson, Coleman and Paterson (J. Fluids Eng. 123
  // (2001) 793) take for oscillatory convergence; a fraction.
  std::optional<double> oscillation_half_range;
};

// The analysis of (h1, f1) finest, (h2, f2), (h3, f3) coarsest. Requires
// 0 < h1 < h2 < h3 and finite f; false (with *error) otherwise.
bool AnalyseThreeGrids(double h1, double f1, double h2, double f2, double h3, double f3,
                       ThreeGrid* result, std::string* error);

// The observed order p > 0 that solves Celik eq. 3 for the ratios r21, r32
// (> 1) and e32 / e21 = `ratio` > 0:
//   p = [ln(ratio) + q(p)] / ln(r21),  q(p) = ln((r21^p - 1) / (r32^p - 1)),
// i.e. ratio = r21^p (r32^p - 1) / (r21^p - 1), exact for f = f0 + C h^p.
// For r21 = r32 = r it is ln(ratio) / ln(r). Unset when no p in (0, 100]
// fits (the change does not shrink on refinement).
std::optional<double> ObservedOrder(double r21, double r32, double ratio);

// (current - previous) / |current|: the change of a result from the
// previous (coarser) mesh, as a fraction of the current one; unset when
// current is 0.
std::optional<double> RelativeChange(double previous, double current);

}  // namespace pba::cli::study
