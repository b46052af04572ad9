#include "codec/summary_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace pba::codec {
namespace {

std::string Format(const char* format, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

// "(x, y, z)" of a three-component list, "-" when it is not one.
std::string Triple(const google::protobuf::RepeatedField<double>& v) {
  if (v.size() != 3) return "-";
  return Format("(%.4g, %.4g, %.4g)", v[0], v[1], v[2]);
}

double Norm(const google::protobuf::RepeatedField<double>& v) {
  double sum = 0;
  for (double x : v) sum += x * x;
  return std::sqrt(sum);
}

// The time steps of a quasi-static analysis in one line.
std::string TimeStepLine(const v1::Convergence& c) {
  if (c.time_steps().empty()) return "";
  int iterations = 0;
  for (const v1::TimeStep& step : c.time_steps()) iterations += step.iterations();
  const v1::TimeStep& first = c.time_steps(0);
  const v1::TimeStep& last = c.time_steps(c.time_steps_size() - 1);
  return Format(
      "  time               %d steps to %.4g s, step %.3g s first, %.3g s last; %d iterations\n",
      c.time_steps_size(), last.time_s(), first.step_s(), last.step_s(), iterations);
}

// Each rigid body's contact at the end.
std::string ContactTable(const v1::Results& r) {
  if (r.contacts().empty()) return "";
  std::string out = Format("  %-18s %-34s %10s %10s %16s\n", "contact", "force (x, y, z) N",
                           "peak N", "area mm^2", "penetration mm");
  for (const v1::ContactResult& c : r.contacts()) {
    out +=
        Format("    %-16s %-34s %10.4g %10.4g %16.3g\n", c.name().c_str(),
               Triple(c.force_n()).c_str(), c.peak_force_n(), c.area_mm2(), c.max_penetration_mm());
  }
  return out;
}

// The structures' displacements, the largest mean first; the first rows
// only when there are many.
std::string StructureTable(const v1::Results& r) {
  constexpr int kMaxRows = 15;
  if (r.structure_displacements().empty()) return "";
  std::vector<const v1::StructureDisplacement*> rows;
  for (const v1::StructureDisplacement& d : r.structure_displacements()) rows.push_back(&d);
  std::stable_sort(rows.begin(), rows.end(), [](const auto* a, const auto* b) {
    return Norm(a->mean_mm()) > Norm(b->mean_mm());
  });
  std::string out = Format("  %-30s %-34s %10s %10s\n", "structure", "mean displacement mm",
                           "|mean| mm", "max mm");
  const int shown = std::min<int>(kMaxRows, static_cast<int>(rows.size()));
  for (int i = 0; i < shown; ++i) {
    const v1::StructureDisplacement& d = *rows[i];
    out += Format("    %-28s %-34s %10.4g %10.4g\n", d.name().c_str(), Triple(d.mean_mm()).c_str(),
                  Norm(d.mean_mm()), d.max_mm());
  }
  if (static_cast<int>(rows.size()) > shown) {
    out += Format("    ... and %d more\n", static_cast<int>(rows.size()) - shown);
  }
  return out;
}

// One line per line profile: points in the body, the largest stress along
// the line and where it is.
std::string ProfileLines(const v1::Results& r) {
  std::string out;
  for (const v1::ProfileResult& p : r.profiles()) {
    out +=
        Format("  profile %-10s %d of %d points inside", p.name().c_str(), p.inside(), p.points());
    if (p.inside() > 0) {
      out += Format("; largest stress along the line %.4g Pa at %.4g mm %s",
                    p.max_stress_along_pa(), p.at_distance_mm(), Triple(p.at_mm()).c_str());
    }
    out += "\n";
  }
  return out;
}

// An explicit run: its steps, energies, erosion, impactor stiffness and
// speed; a dynamic relaxation's convergence.
std::string ExplicitRunLines(const v1::Results& r) {
  if (!r.has_explicit_run() || !r.explicit_run().ran()) return "";
  const v1::ExplicitRun& e = r.explicit_run();
  std::string out = Format(
      "  explicit           %lld steps to %.4g s, stable step %.3g s, first %.3g s, last %.3g s, "
      "%d reductions\n",
      static_cast<long long>(e.steps()), e.end_time_s(), e.stable_step_s(), e.first_step_s(),
      e.last_step_s(), e.step_reductions());
  if (!e.controlling_element().empty()) {
    out += "    controlling      " + e.controlling_element() + "\n";
  }
  out += Format(
      "    energy J         kinetic %.4g, internal %.4g, hourglass %.4g, contact %.4g, damping "
      "%.4g, eroded %.4g, external work %.4g\n",
      e.kinetic_j(), e.internal_j(), e.hourglass_j(), e.contact_j(), e.damping_j(), e.eroded_j(),
      e.external_work_j());
  out += Format("    energy balance   largest error %.2g %% of the largest energy\n",
                100.0 * e.max_energy_error());
  if (e.eroded_elements() > 0) {
    out += Format("    eroded           %d elements, %.4g kg\n", e.eroded_elements(),
                  e.eroded_mass_kg());
  }
  if (e.mass_scaled_elements() > 0) {
    out += Format("    mass scaling     %d elements, %.3g kg added to %.4g kg (%.3g %%)\n",
                  e.mass_scaled_elements(), e.added_mass_kg(), e.model_mass_kg(),
                  e.model_mass_kg() > 0 ? 100 * e.added_mass_kg() / e.model_mass_kg() : 0.0);
  }
  if (e.contact_stiffness_max_n_per_m() > 0) {
    out += Format("    impactor penalty %.3g .. %.3g N/m per node\n",
                  e.contact_stiffness_min_n_per_m(), e.contact_stiffness_max_n_per_m());
  }
  out += Format("    speed            %.3g element updates/s\n", e.element_updates_per_s());
  // Only dynamic relaxation converges (or leaves a residual).
  if (e.converged() || e.relative_residual() > 0) {
    out += Format("    relaxation       %s, out-of-balance force %.2e (relative)\n",
                  e.converged() ? "converged" : "NOT converged", e.relative_residual());
  }
  return out;
}

// Per sensor and quantity: the raw and the filtered peak and when.
std::string SensorPeakTable(const v1::Results& r) {
  if (r.sensor_peaks().empty()) return "";
  std::string out = Format("  %-18s %-14s %12s %12s %12s %12s\n", "sensor", "quantity", "peak raw",
                           "at s", "filtered", "at s");
  for (const v1::SensorPeak& p : r.sensor_peaks()) {
    out += Format("    %-16s %-14s %12.4g %12.4g %12.4g %12.4g\n", p.sensor().c_str(),
                  p.quantity().c_str(), p.peak_raw(), p.time_raw_s(), p.peak_filtered(),
                  p.time_filtered_s());
  }
  return out;
}

// mesh.adapt: the target, why the cycles ended, a line per cycle.
std::string AdaptationLines(const v1::Modelled& m) {
  if (!m.has_adaptation() || !m.adaptation().adapted()) return "";
  const v1::Adaptation& a = m.adaptation();
  std::string out =
      Format("Adapted      %s: %s\n", a.reached() ? "target reached" : "TARGET NOT REACHED",
             a.stop_reason().c_str());
  out += Format("  %5s %10s %10s %11s %9s %9s  %s\n", "cycle", "elements", "unknowns", "est. error",
                "wall [s]", "refined", "largest change from the cycle before");
  for (int i = 0; i < a.cycles_size(); ++i) {
    const v1::AdaptCycle& c = a.cycles(i);
    const std::string change =
        i == 0 ? "-" : Format("%.3g %% (%s)", 100 * c.change(), c.changed_quantity().c_str());
    out += Format("  %5d %10lld %10lld %9.3g %% %9.3g %9lld  %s\n", i + 1,
                  static_cast<long long>(c.elements()), static_cast<long long>(c.dofs()),
                  100 * c.relative_error(), c.wall_time_s(), static_cast<long long>(c.marked()),
                  change.c_str());
  }
  return out;
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
  out += "Analysis     " + m.analysis() +
         (m.linear_solver().empty() ? std::string() : ", " + m.linear_solver()) + "\n";
  for (const auto& note : m.notes()) out += "Note         " + note + "\n";
  if (!m.options().empty()) {
    // Sorted by field path, so the line reads the same on every run.
    std::vector<std::pair<std::string, std::string>> options(m.options().begin(),
                                                             m.options().end());
    std::sort(options.begin(), options.end());
    std::string line;
    for (const auto& [name, value] : options) {
      line += (line.empty() ? "" : ", ") + name + " = " + value;
    }
    out += "Options      " + line + "\n";
  }
  out += AdaptationLines(m);
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
  if (r.has_explicit_run() && r.explicit_run().ran()) {
    out += ExplicitRunLines(r);
  } else if (!r.has_convergence()) {
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
    out += TimeStepLine(c);
  }
  out += ContactTable(r);
  out += SensorPeakTable(r);
  out += StructureTable(r);
  out += ProfileLines(r);
  if (p.ranks() > 1) {
    out += Format("Wall time    %.3f s on %d MPI ranks of %d thread(s):", p.wall_time_s(),
                  p.ranks(), p.threads());
  } else {
    out += Format("Wall time    %.3f s on %d thread(s):", p.wall_time_s(), p.threads());
  }
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
