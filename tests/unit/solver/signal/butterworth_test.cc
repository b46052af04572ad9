// The zero-phase Butterworth low-pass: its magnitude response against the
// closed form, -3 dB at the cutoff for one pass, no phase shift and squared
// attenuation forward-backward, constants unchanged, a noisy pulse cleaned
// with its peak in place, bad input named.
#include "signal/butterworth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pba {
namespace {

constexpr double kRate = 1e6;    // samples per second (1 us steps)
constexpr double kCutoff = 1e4;  // the reference study's 10 kHz

// The digital Butterworth magnitude of one pass (pre-warped bilinear).
double ClosedForm(int order, double f) {
  const double r = std::tan(M_PI * f / kRate) / std::tan(M_PI * kCutoff / kRate);
  return 1 / std::sqrt(1 + std::pow(r, 2 * order));
}

TEST(ButterworthTest, MagnitudeIsTheClosedFormForEveryOrder) {
  for (int order = 1; order <= 8; ++order) {
    ButterworthLowPass filter;
    ASSERT_TRUE(ButterworthLowPass::Design(order, kCutoff, kRate, &filter).ok());
    EXPECT_EQ(filter.sections.size(), static_cast<std::size_t>((order + 1) / 2));
    for (double f : {0.0, 1e3, 5e3, 1e4, 2e4, 5e4, 2e5}) {
      EXPECT_NEAR(filter.Magnitude(f, kRate), ClosedForm(order, f), 1e-9)
          << "order " << order << ", " << f << " Hz";
    }
    EXPECT_NEAR(filter.Magnitude(kCutoff, kRate), 1 / std::sqrt(2.0), 1e-9);
  }
}

std::vector<double> Sine(double f, double amplitude, int samples) {
  std::vector<double> x(samples);
  for (int i = 0; i < samples; ++i) x[i] = amplitude * std::sin(2 * M_PI * f * i / kRate);
  return x;
}

TEST(ButterworthTest, ForwardBackwardKeepsThePhaseAndSquaresTheGain) {
  ButterworthLowPass filter;
  ASSERT_TRUE(ButterworthLowPass::Design(4, kCutoff, kRate, &filter).ok());
  const int n = 4000;  // 4 ms: 8 periods at 2 kHz, 200 at 50 kHz
  for (double f : {2e3, 1e4, 5e4}) {
    const std::vector<double> in = Sine(f, 1, n), out = filter.FilterZeroPhase(in);
    // Away from the ends: amplitude |H|^2, and the peaks where the input's are.
    const double expected = std::pow(ClosedForm(4, f), 2);
    double peak = 0, shift = 0, weight = 0;
    for (int i = n / 4; i < 3 * n / 4; ++i) {
      peak = std::max(peak, std::abs(out[i]));
      shift += out[i] * in[i];
      weight += in[i] * in[i];
    }
    EXPECT_NEAR(peak, expected, 0.02 * expected + 1e-6) << f << " Hz";
    // In phase: the output is the input scaled (correlation / energy).
    EXPECT_NEAR(shift / weight, expected, 0.02 * expected + 1e-6) << f << " Hz";
  }
}

TEST(ButterworthTest, ConstantsPassUnchanged) {
  ButterworthLowPass filter;
  ASSERT_TRUE(ButterworthLowPass::Design(4, kCutoff, kRate, &filter).ok());
  const std::vector<double> c = filter.FilterZeroPhase(std::vector<double>(500, 3.5));
  for (int i = 0; i < 500; ++i) EXPECT_NEAR(c[i], 3.5, 1e-9) << i;
  EXPECT_EQ(filter.FilterZeroPhase({1.0}), std::vector<double>{1.0});
}

TEST(ButterworthTest, APulseKeepsItsPeakTimeAndLosesItsNoise) {
  // A 0.2 ms Gaussian pressure pulse with 100 kHz ripple: filtered at 10 kHz
  // the ripple goes, the peak stays where it was.
  ButterworthLowPass filter;
  ASSERT_TRUE(ButterworthLowPass::Design(4, kCutoff, kRate, &filter).ok());
  const int n = 2000;
  std::vector<double> clean(n), noisy(n);
  for (int i = 0; i < n; ++i) {
    const double t = (i - 1000) / kRate;
    clean[i] = std::exp(-0.5 * std::pow(t / 1e-4, 2));
    noisy[i] = clean[i] + 0.2 * std::sin(2 * M_PI * 1e5 * i / kRate);
  }
  const std::vector<double> out = filter.FilterZeroPhase(noisy);
  const auto peak = std::max_element(out.begin(), out.end()) - out.begin();
  EXPECT_NEAR(peak, 1000, 2);
  double worst = 0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(out[i] - clean[i]));
  EXPECT_LT(worst, 0.02);
}

TEST(ButterworthTest, BadInputIsNamed) {
  ButterworthLowPass filter;
  EXPECT_EQ(ButterworthLowPass::Design(0, kCutoff, kRate, &filter).field(), "order");
  EXPECT_EQ(ButterworthLowPass::Design(11, kCutoff, kRate, &filter).field(), "order");
  EXPECT_EQ(ButterworthLowPass::Design(4, 0, kRate, &filter).field(), "cutoff_hz");
  EXPECT_EQ(ButterworthLowPass::Design(4, kRate / 2, kRate, &filter).field(), "cutoff_hz");
  EXPECT_EQ(ButterworthLowPass::Design(4, kCutoff, -1, &filter).field(), "sample_rate_hz");
}

}  // namespace
}  // namespace pba
