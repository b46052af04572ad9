// Zero-phase Butterworth low-pass filtering of sampled signals, e.g. the
// pressure histories of an impact, which the reference study filtered at
// 10 kHz before reading their peaks (DOMAIN.md section 3).
//
// The digital filter is the bilinear transform of the analog Butterworth
// prototype of `order` poles on a circle of radius 2 fs tan(pi fc / fs)
// (pre-warped, so the digital -3 dB point is exactly fc), factored into
// second-order sections (one first-order section for an odd order), each
// with unit gain at zero frequency; see Oppenheim and Schafer,
// Discrete-Time Signal Processing, 3rd ed., sections 7.1-7.3. Filtering is
// forward then backward (Gustafsson's forward-backward scheme): the phase
// cancels, the magnitude response is squared, |H(f)|^2 = 1 / (1 + (tan(pi
// f / fs) / tan(pi fc / fs))^(2 order)), a half at fc. The ends are
// extended by odd reflection (three samples per pole) and every section
// starts in its steady state for the first value, so a constant passes
// unchanged; within the filter's settling time, about order / (2 pi fc),
// of either end the output carries a start-up transient (a ramp there is
// off by a fraction of its rise over that time).
#pragma once

#include <vector>

#include "pba/status.h"

namespace pba {

struct ButterworthSection {
  // y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2]
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

struct ButterworthLowPass {
  std::vector<ButterworthSection> sections;

  // `order` 1..10, 0 < cutoff_hz < sample_rate_hz / 2; kInvalidArgument
  // naming "order", "cutoff_hz" or "sample_rate_hz" otherwise.
  static Status Design(int order, double cutoff_hz, double sample_rate_hz,
                       ButterworthLowPass* filter);

  // |H(f)| of one (forward) pass at frequency f [Hz].
  double Magnitude(double f_hz, double sample_rate_hz) const;

  // The zero-phase (forward-backward) filtered signal; a signal shorter
  // than two samples is returned as it is.
  std::vector<double> FilterZeroPhase(const std::vector<double>& signal) const;
};

}  // namespace pba
