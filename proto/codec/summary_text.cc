#include "codec/summary_text.h"

#include <cstdio>
#include <string>

namespace pba::codec {
namespace {

std::string Format(const char* format, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

}  // namespace

std::string FormatSummary(const v1::Summary& summary) {
  const v1::Modelled& m = summary.modelled();
  const v1::Results& r = summary.results();
  const v1::Performance& p = summary.performance();
  const v1::ErrorEstimate& e = summary.error_estimate();
  std::string out;
  out += "Scene        " + summary.scene_name() + "\n";
  out += "Modelled     " + m.geometry() + ", " + m.element_type() +
         " mesh: " + std::to_string(m.nodes()) + " nodes, " + std::to_string(m.elements()) +
         " elements, " + std::to_string(m.dofs()) + " unknowns\n";
  out += "Material     " + m.material() + "\n";
  out += "Analysis     " + m.analysis() + ", " + m.linear_solver() + "\n";
  for (const auto& note : m.notes()) out += "Note         " + note + "\n";
  out += "Results\n";
  std::string at;
  if (r.max_displacement_at_mm_size() == 3) {
    at = Format(" at (%.3g, %.3g, %.3g) mm", r.max_displacement_at_mm(0),
                r.max_displacement_at_mm(1), r.max_displacement_at_mm(2));
  }
  out += Format("  max displacement   %.6g mm", r.max_displacement_mm()) + at + "\n";
  out += Format("  max von Mises      %.6g Pa\n", r.max_von_mises_pa());
  out += Format("  strain energy      %.6g J\n", r.strain_energy_j());
  for (const auto& reaction : r.reactions()) {
    if (reaction.force_n_size() != 3) continue;
    out += Format("  reaction %-9s (%.6g, %.6g, %.6g) N\n", reaction.set().c_str(),
                  reaction.force_n(0), reaction.force_n(1), reaction.force_n(2));
  }
  if (!r.has_convergence()) {
    out += Format("  linear residual    %.2e (relative)\n", r.relative_residual());
  } else {
    const v1::Convergence& c = r.convergence();
    out += Format(
        "  Newton             %d increments, %d iterations, %d cut back; final residual "
        "%.2e (relative)\n",
        c.increments_size(), c.newton_iterations(), c.increment_cuts(), r.relative_residual());
    out += Format("    time: assembly %.3f s, linear solves %.3f s, residuals %.3f s\n",
                  c.assembly_s(), c.linear_solve_s(), c.residual_s());
    // The path, unless it is long: then its first and last few increments.
    const int n = c.increments_size();
    for (int i = 0; i < n; ++i) {
      if (n > 10 && i == 3) {
        out += Format("    ... %d more increments ...\n", n - 6);
        i = n - 3;
      }
      const v1::Increment& inc = c.increments(i);
      out += Format(
          "    load %-8.4g %2d iterations, residual %.1e%s\n", inc.load_factor(), inc.iterations(),
          inc.relative_residual(),
          inc.negative_eigenvalues() > 0
              ? Format(", unstable (%d negative eigenvalues)", inc.negative_eigenvalues()).c_str()
              : "");
    }
  }
  out += Format("Wall time    %.3f s on %d thread(s):", p.wall_time_s(), p.threads());
  for (const auto& phase : p.phases()) {
    out += Format(" %s %.3f s,", phase.phase().c_str(), phase.seconds());
  }
  if (!p.phases().empty()) out.pop_back();
  out += "\n";
  if (e.estimated()) {
    out += Format("Error        about %.2g %% in the energy norm (%s)\n",
                  100.0 * e.relative_error(), e.method().c_str());
    // Per structure when there are several.
    if (e.regions_size() > 1) {
      for (const auto& r : e.regions()) {
        out += Format("    %-24s about %.2g %% (%.0f %% of the error, %lld elements)\n",
                      r.name().c_str(), 100.0 * r.relative_error(), 100.0 * r.share(),
                      static_cast<long long>(r.elements()));
      }
    }
  } else {
    out +=
        "Error        not estimated" + (e.note().empty() ? std::string() : ": " + e.note()) + "\n";
  }
  return out;
}

}  // namespace pba::codec
