#include "study_math.h"

#include <algorithm>
#include <cmath>

namespace pba::cli::study {
namespace {

// r^p - 1, accurate for small p.
double PowerMinusOne(double r, double p) { return std::expm1(p * std::log(r)); }

// Celik eq. 3 as G(p) = 0: ln(e32/e21) = p ln(r21) + ln((r32^p - 1) / (r21^p - 1)).
double OrderResidual(double r21, double r32, double log_ratio, double p) {
  return p * std::log(r21) + std::log(PowerMinusOne(r32, p) / PowerMinusOne(r21, p)) - log_ratio;
}

std::optional<double> Fraction(double numerator, double denominator) {
  if (denominator == 0) return std::nullopt;
  return std::abs(numerator / denominator);
}

}  // namespace

std::string BehaviourName(Behaviour behaviour) {
  switch (behaviour) {
    case Behaviour::kMonotone:
      return "monotone";
    case Behaviour::kOscillatory:
      return "oscillatory";
    case Behaviour::kDiverging:
      return "diverging";
    case Behaviour::kUnchanged:
      return "unchanged";
    case Behaviour::kIndeterminate:
      return "indeterminate";
  }
  return "indeterminate";
}

std::optional<double> ObservedOrder(double r21, double r32, double ratio) {
  if (!(r21 > 1) || !(r32 > 1) || !(ratio > 0) || !std::isfinite(ratio)) return std::nullopt;
  const double log_ratio = std::log(ratio);
  if (r21 == r32) {
    const double p = log_ratio / std::log(r21);
    if (p > 0 && p <= 100) return p;
    return std::nullopt;
  }
  // G(p) tends to ln(ln r32 / ln r21) - ln(ratio) as p -> 0 and grows like
  // p ln(r32) for large p. Scan for the first change of sign, then bisect:
  // slower than Celik's fixed-point iteration but it cannot wander off.
  constexpr double kLowest = 1e-6, kHighest = 100, kStep = 0.01;
  double a = kLowest;
  double ga = OrderResidual(r21, r32, log_ratio, a);
  if (ga == 0) return a;
  for (double b = kStep; b <= kHighest + kStep / 2; b += kStep) {
    double gb = OrderResidual(r21, r32, log_ratio, b);
    if (gb == 0) return b;
    if ((ga < 0) != (gb < 0)) {
      for (int i = 0; i < 200 && b - a > 1e-15 * b; ++i) {
        const double m = 0.5 * (a + b);
        const double gm = OrderResidual(r21, r32, log_ratio, m);
        if ((gm < 0) == (ga < 0)) {
          a = m;
          ga = gm;
        } else {
          b = m;
          gb = gm;
        }
      }
      return 0.5 * (a + b);
    }
    a = b;
    ga = gb;
  }
  return std::nullopt;
}

std::optional<double> RelativeChange(double previous, double current) {
  if (current == 0) return std::nullopt;
  return (current - previous) / std::abs(current);
}

bool AnalyseThreeGrids(double h1, double f1, double h2, double f2, double h3, double f3,
                       ThreeGrid* result, std::string* error) {
  if (!(h1 > 0 && h2 > h1 && h3 > h2 && std::isfinite(h3))) {
    *error = "the meshes must be ordered finest first, each coarser than the one before";
    return false;
  }
  if (!std::isfinite(f1) || !std::isfinite(f2) || !std::isfinite(f3)) {
    *error = "a result is not a finite number";
    return false;
  }
  ThreeGrid g;
  g.r21 = h2 / h1;
  g.r32 = h3 / h2;
  g.e21 = f2 - f1;
  g.e32 = f3 - f2;
  g.relative_change_21 = Fraction(f1 - f2, f1);
  g.relative_change_32 = Fraction(f2 - f3, f2);
  // Differences within rounding of the results count as none.
  const double tiny = 1e-12 * std::max({std::abs(f1), std::abs(f2), std::abs(f3)});
  const bool none21 = std::abs(g.e21) <= tiny, none32 = std::abs(g.e32) <= tiny;
  if (none21 && none32) {
    g.behaviour = Behaviour::kUnchanged;
    g.extrapolated = f1;
    g.extrapolated_error = 0.0;
    g.gci_fine = 0.0;
    g.gci_coarse = 0.0;
  } else if (none21 || none32) {
    g.behaviour = Behaviour::kIndeterminate;
  } else if (g.e32 / g.e21 < 0) {
    g.behaviour = Behaviour::kOscillatory;
    const double range = std::max({f1, f2, f3}) - std::min({f1, f2, f3});
    if (f1 != 0) g.oscillation_half_range = 0.5 * range / std::abs(f1);
  } else if (const auto p = ObservedOrder(g.r21, g.r32, g.e32 / g.e21); p) {
    g.behaviour = Behaviour::kMonotone;
    g.order = *p;
    const double d21 = PowerMinusOne(g.r21, *p), d32 = PowerMinusOne(g.r32, *p);
    // f_ext = (r21^p f1 - f2) / (r21^p - 1) = f1 + (f1 - f2) / (r21^p - 1).
    g.extrapolated = f1 + (f1 - f2) / d21;
    g.extrapolated_error = Fraction(*g.extrapolated - f1, *g.extrapolated);
    if (g.relative_change_21) g.gci_fine = 1.25 * *g.relative_change_21 / d21;
    if (g.relative_change_32) g.gci_coarse = 1.25 * *g.relative_change_32 / d32;
    if (g.gci_fine && g.gci_coarse && *g.gci_fine > 0)
      g.asymptotic_ratio = *g.gci_coarse / ((d21 + 1) * *g.gci_fine);
  } else {
    g.behaviour = Behaviour::kDiverging;
  }
  *result = g;
  return true;
}

}  // namespace pba::cli::study
