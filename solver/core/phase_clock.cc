#include "core/phase_clock.h"

#include <algorithm>

namespace pba {

void PhaseClock::Begin(const std::string& phase, double begin, double end,
                       const std::string& message) {
  End();
  phase_ = phase;
  message_ = message;
  begin_ = begin;
  end_ = end;
  phase_start_ = Clock::now();
  Emit(begin, message);
}

void PhaseClock::Update(double f, const std::string& message) {
  const double fraction = begin_ + std::clamp(f, 0.0, 1.0) * (end_ - begin_);
  // About fifty events per run at most, and one every few seconds when the
  // fraction creeps (the first steps of a long hold, Newton iterations on a
  // big mesh), so a reader sees the run is alive.
  if (fraction - last_reported_ < 0.02 && Seconds(last_emitted_) < kQuietSeconds) return;
  Emit(fraction, message.empty() ? message_ : message);
}

void PhaseClock::End() {
  if (phase_.empty()) return;
  times_->push_back({phase_, Seconds(phase_start_)});
  phase_.clear();
}

void PhaseClock::Emit(double fraction, const std::string& message) {
  fraction = std::max(fraction, last_reported_);
  last_reported_ = fraction;
  last_emitted_ = Clock::now();
  if (options_.progress) options_.progress({phase_, fraction, message});
}

}  // namespace pba
