// What a QUASI_STATIC analysis records at every converged step (history.csv)
// and how its steps are bounded; the structure displacements every
// analysis reports.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "analysis/finite_strain_model.h"
#include "analysis/newton_static.h"
#include "analysis/rigid_contact.h"
#include "material/material_field.h"
#include "pba/solve.h"
#include "scene/problem.h"
#include "scene/time_curve.h"

namespace pba {

// Step controls of a time-dependent Newton solve (load factor = t / T):
// the first step, the smallest and largest, and a bound from every
// converged time that keeps a step from crossing a corner of the curve and,
// while a(t) changes, from exceeding the shortest active relaxation time
// (one between a thousandth of the shortest loading segment and T: faster
// terms follow the load with a lag the exact exponential update gives at
// any step, slower ones hardly relax). Sets `options` and returns a note
// for the summary.
std::string SetTimeSteps(const TimeOptions& time, const TimeCurve& curve,
                         const MaterialField& field, NewtonOptions* options);

// The nodes of each reported structure with their volume weights.
class StructureProbe {
 public:
  // `names` as in outputs.structure_displacements ("*": every region).
  StructureProbe(const std::vector<std::string>& names, const Mesh& mesh);
  std::size_t size() const { return names_.size(); }
  const std::string& name(std::size_t i) const { return names_[i]; }
  // Volume-weighted mean and largest nodal displacement of structure i [m].
  StructureDisplacement Measure(std::size_t i, const Eigen::VectorXd& u) const;

 private:
  std::vector<std::string> names_;
  std::vector<std::vector<std::pair<int, double>>> nodes_;  // (node, weight), weights sum to 1
};

// Rows of history.csv.
class HistoryRecorder {
 public:
  // `problem` and `contacts` (named as in problem.contacts) must outlive
  // the recorder.
  HistoryRecorder(const Problem& problem, double duration_s,
                  std::vector<std::pair<std::string, const RigidContact*>> contacts = {});
  // Appends the row of a converged step at load factor `load` (t = load T)
  // to solution->history, setting solution->history_columns on the first.
  // The reactions are the internal force less the loads (`loads`, may be
  // null) at that amplitude.
  void Record(const FiniteStrainModel& model, const ExternalLoads* loads, double load,
              double amplitude, const Eigen::VectorXd& u, Solution* solution) const;

 private:
  const Mesh& mesh_;
  double duration_s_;
  std::vector<std::string> reaction_sets_;
  StructureProbe structures_;
  std::vector<std::pair<std::string, const RigidContact*>> contacts_;
  std::vector<std::string> columns_;
};

}  // namespace pba
