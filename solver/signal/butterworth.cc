#include "signal/butterworth.h"

#include <algorithm>
#include <cmath>
#include <complex>

namespace pba {
namespace {

// One pass through every section, each starting in the steady state of
// the first sample (direct form II transposed).
std::vector<double> Pass(const std::vector<ButterworthSection>& sections, std::vector<double> x) {
  for (const ButterworthSection& s : sections) {
    // For a constant input c the output is c (unit DC gain), so the states
    // are z1 = c - b0 c and z2 = b2 c - a2 c.
    const double c = x.front();
    double z1 = c - s.b0 * c, z2 = s.b2 * c - s.a2 * c;
    for (double& value : x) {
      const double in = value;
      const double out = s.b0 * in + z1;
      z1 = s.b1 * in - s.a1 * out + z2;
      z2 = s.b2 * in - s.a2 * out;
      value = out;
    }
  }
  return x;
}

}  // namespace

Status ButterworthLowPass::Design(int order, double cutoff_hz, double sample_rate_hz,
                                  ButterworthLowPass* filter) {
  if (order < 1 || order > 10) {
    return Status::InvalidArgument("order", "must lie in 1..10, got " + std::to_string(order));
  }
  if (!(sample_rate_hz > 0) || !std::isfinite(sample_rate_hz)) {
    return Status::InvalidArgument("sample_rate_hz", "must be a positive number");
  }
  if (!(cutoff_hz > 0) || !(cutoff_hz < sample_rate_hz / 2)) {
    return Status::InvalidArgument("cutoff_hz", "must lie between 0 and half the sample rate (" +
                                                    std::to_string(sample_rate_hz / 2) +
                                                    " Hz), got " + std::to_string(cutoff_hz));
  }
  filter->sections.clear();
  const double k = 2 * sample_rate_hz;  // bilinear s = k (z - 1)/(z + 1)
  const double omega = k * std::tan(M_PI * cutoff_hz / sample_rate_hz);  // pre-warped cutoff
  // The analog poles in the left half-plane, s_m = omega exp(i pi (2m +
  // order + 1) / (2 order)); conjugate pairs make one section each.
  for (int m = 0; m < order / 2; ++m) {
    const std::complex<double> s =
        omega * std::exp(std::complex<double>(0, M_PI * (2 * m + order + 1) / (2.0 * order)));
    const std::complex<double> z = (k + s) / (k - s);
    ButterworthSection section;
    section.a1 = -2 * z.real();
    section.a2 = std::norm(z);
    // Both zeros at z = -1: numerator g (1 + 2 z^-1 + z^-2), unit DC gain.
    const double g = (1 + section.a1 + section.a2) / 4;
    section.b0 = g;
    section.b1 = 2 * g;
    section.b2 = g;
    filter->sections.push_back(section);
  }
  if (order % 2 == 1) {
    // The real pole s = -omega: a first-order section.
    const double z = (k - omega) / (k + omega);
    ButterworthSection section;
    section.a1 = -z;
    const double g = (1 - z) / 2;
    section.b0 = g;
    section.b1 = g;
    filter->sections.push_back(section);
  }
  return Status::Ok();
}

double ButterworthLowPass::Magnitude(double f_hz, double sample_rate_hz) const {
  const std::complex<double> z1 =
      std::exp(std::complex<double>(0, -2 * M_PI * f_hz / sample_rate_hz));
  const std::complex<double> z2 = z1 * z1;
  std::complex<double> h = 1;
  for (const ButterworthSection& s : sections) {
    h *= (s.b0 + s.b1 * z1 + s.b2 * z2) / (1.0 + s.a1 * z1 + s.a2 * z2);
  }
  return std::abs(h);
}

std::vector<double> ButterworthLowPass::FilterZeroPhase(const std::vector<double>& signal) const {
  const std::size_t n = signal.size();
  if (n < 2) return signal;
  // Odd reflection about each end, three samples per pole (as is
  // customary), but no longer than the signal allows.
  const std::size_t pad = std::min<std::size_t>(n - 1, 3 * (2 * sections.size() + 1));
  std::vector<double> x;
  x.reserve(n + 2 * pad);
  for (std::size_t i = pad; i >= 1; --i) x.push_back(2 * signal.front() - signal[i]);
  x.insert(x.end(), signal.begin(), signal.end());
  for (std::size_t i = 1; i <= pad; ++i) x.push_back(2 * signal.back() - signal[n - 1 - i]);
  x = Pass(sections, std::move(x));
  std::reverse(x.begin(), x.end());
  x = Pass(sections, std::move(x));
  std::reverse(x.begin(), x.end());
  return std::vector<double>(x.begin() + pad, x.begin() + pad + n);
}

}  // namespace pba
