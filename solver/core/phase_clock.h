// PhaseClock: times the phases of a solve and reports progress.
// Each phase has a share of the whole run; progress within a phase is mapped
// onto its share so the reported fraction only grows.
#pragma once

#include <atomic>
#include <chrono>
#include <string>
#include <vector>

#include "pba/solve.h"

namespace pba {

class PhaseClock {
 public:
  PhaseClock(const SolveOptions& options, std::vector<PhaseTime>* times)
      : options_(options), times_(times), start_(Clock::now()) {}

  // Ends the current phase (recording its time) and starts `phase`, which
  // covers the fractions [begin, end] of the whole run.
  void Begin(const std::string& phase, double begin, double end, const std::string& message);
  // Reports progress `f` (0..1) within the current phase; rate-limited to
  // steps of 2 % of the run, or kQuietSeconds since the last report.
  void Update(double f, const std::string& message = "");
  // Ends the current phase.
  void End();
  bool cancelled() const { return options_.cancel != nullptr && options_.cancel->load(); }
  double elapsed_s() const { return Seconds(start_); }
  const SolveOptions& options() const { return options_; }

 private:
  using Clock = std::chrono::steady_clock;
  static double Seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
  }
  void Emit(double fraction, const std::string& message);

  const SolveOptions& options_;
  std::vector<PhaseTime>* times_;
  Clock::time_point start_;
  Clock::time_point phase_start_;
  std::string phase_;
  std::string message_;
  double begin_ = 0, end_ = 0, last_reported_ = -1;
  Clock::time_point last_emitted_ = Clock::now();
  static constexpr double kQuietSeconds = 5;
};

}  // namespace pba
