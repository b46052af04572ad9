// What a stepping integrator does after each step besides stepping, in one
// place for all of them (the central difference of explicit dynamics,
// dynamic relaxation, Newton's converged increments through
// NewtonOptions::observers): progress and cancellation, history rows on a
// schedule, checkpoints (analysis/checkpoint.h), and the throughput of the
// loop. An integrator tells a StepObservers list after every step and stops
// with the first observer's refusal (a cancelled job, a checkpoint that
// could not be written).
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/phase_clock.h"
#include "pba/status.h"

namespace pba {

// Where a run stands after a step.
struct StepState {
  int64_t step = 0;                    // steps taken so far
  double time_s = 0;                   // the time reached (the step count for a pseudo-time,
                                       // the load factor for Newton's increments)
  double fraction = 0;                 // of the run done, 0..1, for the progress bar
  bool last = false;                   // the run's final step
  double next_step = 0;                // the length of the step to be tried next
  const Eigen::VectorXd* u = nullptr;  // the displacement reached, when given [m]
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  // After a step; an error stops the run with it.
  virtual Status AfterStep(const StepState& state) = 0;
};

// Every `every` steps: the phase clock's fraction and a line from
// `describe`; a cancelled job stops the run with kCancelled, "cancelled
// during <what>".
class ProgressObserver final : public StepObserver {
 public:
  ProgressObserver(PhaseClock* clock, int64_t every, std::string what,
                   std::function<std::string(const StepState&)> describe);
  Status AfterStep(const StepState& state) override;

 private:
  PhaseClock* clock_;
  int64_t every_;
  std::string what_;
  std::function<std::string(const StepState&)> describe_;
};

// A row of the run's history (Solution::history) from `row`, every
// `every_steps` steps when > 0, else whenever the time has reached the
// next multiple of `interval_s` (within a thousandth of `tolerance_s`,
// the step, so that rounding does not skip a row), and at the last step.
class HistoryObserver final : public StepObserver {
 public:
  HistoryObserver(std::vector<std::vector<double>>* history, int64_t every_steps, double interval_s,
                  std::function<std::vector<double>(const StepState&)> row);
  // The step length, for the time schedule's tolerance.
  void SetStep(double dt_s) { tolerance_s_ = 1e-3 * dt_s; }
  // Whether the step about to be reported will write a row.
  bool Due(const StepState& state) const;
  Status AfterStep(const StepState& state) override;

 private:
  std::vector<std::vector<double>>* history_;
  int64_t every_steps_;
  double interval_s_;
  double next_s_ = 0, tolerance_s_ = 0;
  std::function<std::vector<double>(const StepState&)> row_;
};

// The observers of one run, told in the order they were added.
class StepObservers {
 public:
  void Add(StepObserver* observer) { observers_.push_back(observer); }
  Status AfterStep(const StepState& state);

 private:
  std::vector<StepObserver*> observers_;
};

// Element updates per second of a loop: started at construction.
class LoopThroughput {
 public:
  LoopThroughput() : start_(std::chrono::steady_clock::now()) {}
  double Seconds() const;
  // steps x elements / seconds; 0 for a loop too quick to time.
  double UpdatesPerSecond(int64_t steps, int elements) const;

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace pba
