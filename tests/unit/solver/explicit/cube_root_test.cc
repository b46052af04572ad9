// CubeRoot against long double's cbrtl: within one ulp over 60 decades and
// densely over the volume ratios of tissue, and std::cbrt outside its range.
#include "explicit/cube_root.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace pba {
namespace {

double UlpError(double x) {
  const long double exact = cbrtl(static_cast<long double>(x));
  const double rounded = static_cast<double>(exact);
  const double ulp = std::nextafter(rounded, std::numeric_limits<double>::infinity()) - rounded;
  return static_cast<double>(fabsl(CubeRoot(x) - exact)) / ulp;
}

TEST(CubeRoot, WithinOneUlpOverSixtyDecades) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exponent(-69, 69);  // e^69 ~ 1e30
  double worst = 0;
  for (int i = 0; i < 200000; ++i) worst = std::max(worst, UlpError(std::exp(exponent(rng))));
  EXPECT_LE(worst, 1.0);
}

TEST(CubeRoot, WithinOneUlpForVolumeRatios) {
  double worst = 0;
  for (double j = 0.2; j < 5; j += 1.3e-5) worst = std::max(worst, UlpError(j));
  EXPECT_LE(worst, 1.0);
  EXPECT_EQ(CubeRoot(1.0), 1.0);
  EXPECT_EQ(CubeRoot(8.0), 2.0);
  EXPECT_EQ(CubeRoot(0.125), 0.5);
}

TEST(CubeRoot, OutsideItsRangeIsStdCbrt) {
  for (double x : {0.0, -8.0, 1e-300, 1e300, std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(CubeRoot(x), std::cbrt(x)) << x;
  }
  EXPECT_TRUE(std::isnan(CubeRoot(std::numeric_limits<double>::quiet_NaN())));
}

}  // namespace
}  // namespace pba
