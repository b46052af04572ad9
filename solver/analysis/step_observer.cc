#include "analysis/step_observer.h"

#include <utility>

namespace pba {

ProgressObserver::ProgressObserver(PhaseClock* clock, int64_t every, std::string what,
                                   std::function<std::string(const StepState&)> describe)
    : clock_(clock), every_(every), what_(std::move(what)), describe_(std::move(describe)) {}

Status ProgressObserver::AfterStep(const StepState& state) {
  if (every_ <= 0 || state.step % every_ != 0) return Status::Ok();
  clock_->Update(state.fraction, describe_(state));
  if (clock_->cancelled()) return Status::Cancelled("cancelled during " + what_);
  return Status::Ok();
}

HistoryObserver::HistoryObserver(std::vector<std::vector<double>>* history, int64_t every_steps,
                                 double interval_s,
                                 std::function<std::vector<double>(const StepState&)> row)
    : history_(history), every_steps_(every_steps), interval_s_(interval_s), row_(std::move(row)) {}

bool HistoryObserver::Due(const StepState& state) const {
  if (every_steps_ > 0) return state.step % every_steps_ == 0;
  return state.time_s >= next_s_ - tolerance_s_ || state.last;
}

Status HistoryObserver::AfterStep(const StepState& state) {
  if (!Due(state)) return Status::Ok();
  history_->push_back(row_(state));
  if (every_steps_ <= 0) next_s_ += interval_s_;
  return Status::Ok();
}

Status StepObservers::AfterStep(const StepState& state) {
  for (StepObserver* observer : observers_) PBA_RETURN_IF_ERROR(observer->AfterStep(state));
  return Status::Ok();
}

double LoopThroughput::Seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double LoopThroughput::UpdatesPerSecond(int64_t steps, int elements) const {
  const double s = Seconds();
  return s > 0 ? static_cast<double>(steps) * elements / s : 0;
}

}  // namespace pba
