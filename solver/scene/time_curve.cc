#include "scene/time_curve.h"

#include <algorithm>

namespace pba {

TimeCurve::TimeCurve(const TimeOptions& time) : end_s_(time.end_s) {
  if (time.curve.empty()) {
    t_ = {0, end_s_};
    a_ = {0, 1};
    return;
  }
  for (const auto& [t, a] : time.curve) {
    t_.push_back(t);
    a_.push_back(a);
  }
}

double TimeCurve::Amplitude(double t_s) const {
  if (t_s <= t_.front()) return a_.front();
  if (t_s >= t_.back()) return a_.back();
  const std::size_t i = std::upper_bound(t_.begin(), t_.end(), t_s) - t_.begin();
  const double w = (t_s - t_[i - 1]) / (t_[i] - t_[i - 1]);
  return (1 - w) * a_[i - 1] + w * a_[i];
}

double TimeCurve::NextCorner(double t_s) const {
  // A corner closer than a rounding error is the one just reached.
  const double eps = 1e-12 * end_s_;
  for (double t : t_) {
    if (t > t_s + eps && t < end_s_) return t;
  }
  return end_s_;
}

bool TimeCurve::Changes(double t0_s, double t1_s) const {
  if (Amplitude(t0_s) != Amplitude(t1_s)) return true;
  for (std::size_t i = 0; i + 1 < t_.size(); ++i) {
    // A segment that overlaps [t0, t1] and is not flat.
    if (t_[i + 1] > t0_s && t_[i] < t1_s && a_[i] != a_[i + 1]) return true;
  }
  return false;
}

double TimeCurve::ShortestLoading() const {
  double shortest = end_s_;
  for (std::size_t i = 0; i + 1 < t_.size(); ++i) {
    if (a_[i] != a_[i + 1]) shortest = std::min(shortest, t_[i + 1] - t_[i]);
  }
  return shortest;
}

}  // namespace pba
