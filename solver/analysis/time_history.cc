#include "analysis/time_history.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/format.h"
#include "fem/tet4.h"

namespace pba {

constexpr double kMm = 1e-3;

std::string SetTimeSteps(const TimeOptions& time, const TimeCurve& curve,
                         const MaterialField& field, NewtonOptions* options) {
  const double duration = curve.end_s();
  const double initial = time.initial_step_s;
  const double smallest = time.min_step_s;
  const double largest = time.max_step_s;
  // A term a thousand times faster than the loading follows it with a lag
  // of tau times the rate, which the exact exponential update gives at any
  // step; one slower than the analysis hardly moves. The others are
  // resolved (formulation AUTO folds terms 100 times faster than the
  // loading, and steps over them).
  const double fastest_active = curve.ShortestLoading() / 1000;
  double active = std::numeric_limits<double>::infinity();
  for (const MaterialField::Entry& entry : field.entries()) {
    for (double tau : entry.relaxation.tau_s) {
      if (tau >= fastest_active && tau <= duration) active = std::min(active, tau);
    }
  }
  options->initial_increments = std::max(1, static_cast<int>(std::ceil(duration / initial - 1e-9)));
  options->min_increment = smallest / duration;
  options->max_increment = largest / duration;
  options->max_increment_at = [&curve, duration, largest, active](double load) {
    const double t = load * duration;
    double bound = std::min(largest, curve.NextCorner(t) - t);
    if (std::isfinite(active) && curve.Changes(t, t + bound)) bound = std::min(bound, active);
    return bound / duration;
  };
  return Format("time steps: first %g s, between %g and %g s", initial, smallest, largest) +
         (std::isfinite(active)
              ? Format(", at most %g s (the shortest active relaxation time) while loading", active)
              : std::string());
}

namespace {

// |volume| of element e's corners [m^3]: of a brick, or of a tetrahedron's
// corners (for a 10-node one the straight-sided tetrahedron).
double CornerVolume(const Mesh& mesh, int e) {
  switch (mesh.shape()) {
    case ElementShape::kTet4:
    case ElementShape::kTet10:
      return std::abs(ComputeTet4Geometry(TetCorners(mesh, e)).volume);
    case ElementShape::kHex8:
      return std::abs(HexVolume(mesh, e));
  }
  return 0;
}

}  // namespace

StructureProbe::StructureProbe(const std::vector<std::string>& names, const Mesh& mesh) {
  std::vector<std::string> wanted = names;
  if (std::find(names.begin(), names.end(), "*") != names.end()) wanted = mesh.region_names;
  for (const std::string& name : wanted) {
    const auto it = std::find(mesh.region_names.begin(), mesh.region_names.end(), name);
    if (it == mesh.region_names.end()) continue;  // CheckStructureNames refuses it
    const int region = static_cast<int>(it - mesh.region_names.begin());
    std::vector<double> weight(mesh.num_nodes(), 0.0);
    double total = 0;
    for (int e = 0; e < mesh.num_elements(); ++e) {
      if (mesh.element_region[e] != region) continue;
      // The element's volume shared equally among its corners.
      const NodeList corners = mesh.ElementCorners(e);
      const double v = CornerVolume(mesh, e) / corners.size();
      for (int a : corners) weight[a] += v;
      total += corners.size() * v;
    }
    std::vector<std::pair<int, double>> nodes;
    for (int a = 0; a < mesh.num_nodes(); ++a) {
      if (weight[a] > 0) nodes.emplace_back(a, weight[a] / total);
    }
    names_.push_back(name);
    nodes_.push_back(std::move(nodes));
  }
}

StructureDisplacement StructureProbe::Measure(std::size_t i, const Eigen::VectorXd& u) const {
  StructureDisplacement out;
  out.name = names_[i];
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& [node, weight] : nodes_[i]) {
    const Eigen::Vector3d d = u.segment<3>(3 * node);
    mean += weight * d;
    out.max_mm = std::max(out.max_mm, d.norm() / kMm);
  }
  for (int c = 0; c < 3; ++c) out.mean_mm[c] = mean(c) / kMm;
  return out;
}

HistoryRecorder::HistoryRecorder(const Problem& problem, double duration_s,
                                 std::vector<std::pair<std::string, const RigidContact*>> contacts)
    : mesh_(problem.model.mesh),
      duration_s_(duration_s),
      reaction_sets_(problem.outputs.reaction_sets),
      structures_(problem.outputs.structure_displacements, problem.model.mesh),
      contacts_(std::move(contacts)) {
  columns_ = {"time_s", "amplitude"};
  for (const std::string& set : reaction_sets_) {
    for (const char* axis : {"x", "y", "z"}) {
      columns_.push_back("reaction " + set + " " + axis + " [N]");
    }
  }
  // A contact's force on its body, how far the body has moved along its
  // motion, the area in contact and the deepest penetration.
  for (const auto& [name, contact] : contacts_) {
    for (const char* axis : {"x", "y", "z"}) {
      columns_.push_back("contact " + name + " " + axis + " [N]");
    }
    columns_.push_back("contact " + name + " travel [mm]");
    columns_.push_back("contact " + name + " area [mm^2]");
    columns_.push_back("contact " + name + " penetration [mm]");
  }
  for (std::size_t i = 0; i < structures_.size(); ++i) {
    for (const char* axis : {"x", "y", "z"}) {
      columns_.push_back(structures_.name(i) + " mean u" + axis + " [mm]");
    }
    columns_.push_back(structures_.name(i) + " max |u| [mm]");
  }
}

void HistoryRecorder::Record(const FiniteStrainModel& model, const ExternalLoads* loads,
                             double load, double amplitude, const Eigen::VectorXd& u,
                             Solution* solution) const {
  if (solution->history_columns.empty()) solution->history_columns = columns_;
  std::vector<double> row = {load * duration_s_, amplitude};
  if (!reaction_sets_.empty()) {
    Eigen::VectorXd force;
    const bool ok = model.InternalForce(u, &force, nullptr);
    if (ok && loads != nullptr && !loads->empty()) force -= amplitude * loads->Force(u);
    for (const std::string& set : reaction_sets_) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      if (ok) {
        for (int node : mesh_.face_sets.at(set).nodes) sum += force.segment<3>(3 * node);
      }
      for (int c = 0; c < 3; ++c) row.push_back(ok ? sum(c) : NAN);
    }
  }
  for (const auto& [name, contact] : contacts_) {
    const ContactMeasure m = contact->Measure(u);
    row.insert(row.end(), {m.force.x(), m.force.y(), m.force.z(),
                           amplitude * contact->body().motion.norm() / kMm, m.area / (kMm * kMm),
                           m.penetration / kMm});
  }
  for (std::size_t i = 0; i < structures_.size(); ++i) {
    const StructureDisplacement d = structures_.Measure(i, u);
    row.insert(row.end(), d.mean_mm.begin(), d.mean_mm.end());
    row.push_back(d.max_mm);
  }
  solution->history.push_back(std::move(row));
}

}  // namespace pba
