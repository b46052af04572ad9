// The amplitude a(t) of an analysis through time (Problem::time) and
// the step bounds it implies.
#pragma once

#include <vector>

#include "scene/problem.h"

namespace pba {

class TimeCurve {
 public:
  // `time` must be validated (end_s > 0, increasing curve times).
  explicit TimeCurve(const TimeOptions& time);

  double end_s() const { return end_s_; }
  // a(t): piecewise linear through the curve's points, the first value
  // before the first point, the last after the last; no points: t / end.
  double Amplitude(double t_s) const;
  // The first corner of the curve (a point where its slope may change)
  // strictly after t_s, or the end time.
  double NextCorner(double t_s) const;
  // True when a(t) changes anywhere within [t0, t1].
  bool Changes(double t0_s, double t1_s) const;
  // The shortest stretch between two points of the curve over which the
  // amplitude changes [s]: the loading's time scale (no curve: the ramp's
  // whole length).
  double ShortestLoading() const;

 private:
  double end_s_;
  std::vector<double> t_, a_;  // the points, a ramp (0, 0), (end, 1) by default
};

}  // namespace pba
