// The convergence arithmetic of `pba study convergence` against the worked
// example of Celik et al. 2008 (J. Fluids Eng. 130:078001, Table 1) and
// against a series whose answer is known exactly.

#include "study_math.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace pba::cli::study {
namespace {

// Celik's grids are two-dimensional: h = (area / cells)^(1/2), so the
// representative sizes go as cells^(-1/2) (18000, 8000, 4500 cells for the
// first column of Table 1; 18000, 4500, 980 for the others).
double Size2d(double cells) { return 1 / std::sqrt(cells); }

ThreeGrid Analyse(double h1, double f1, double h2, double f2, double h3, double f3) {
  ThreeGrid g;
  std::string error;
  EXPECT_TRUE(AnalyseThreeGrids(h1, f1, h2, f2, h3, f3, &g, &error)) << error;
  return g;
}

// Table 1, first column: the dimensionless reattachment length. The table
// gives r21 = 1.5, r32 = 1.333, p = 1.53, phi_ext = 6.1685, e_a = 1.5 %,
// e_ext = 1.7 %, GCI_fine = 2.2 % (printed rounded, so compared to within
// their last digit).
TEST(StudyMathTest, CelikTable1ReattachmentLength) {
  const ThreeGrid g = Analyse(Size2d(18000), 6.063, Size2d(8000), 5.972, Size2d(4500), 5.863);
  EXPECT_EQ(g.behaviour, Behaviour::kMonotone);
  EXPECT_NEAR(g.r21, 1.5, 1e-12);
  EXPECT_NEAR(g.r32, 1.333, 5e-4);
  ASSERT_TRUE(g.order);
  EXPECT_NEAR(*g.order, 1.53, 0.005);
  ASSERT_TRUE(g.extrapolated);
  EXPECT_NEAR(*g.extrapolated, 6.1685, 5e-4);
  EXPECT_NEAR(*g.relative_change_21, 0.015, 0.0005);
  EXPECT_NEAR(*g.extrapolated_error, 0.017, 0.0005);
  ASSERT_TRUE(g.gci_fine);
  EXPECT_NEAR(*g.gci_fine, 0.022, 0.0005);
}

// Table 1, second column: axial velocity at x/H = 8, y = 0.0526: r21 = 2,
// r32 = 2.143, p = 0.75, phi_ext = 10.8801, e_a = 0.6 %, GCI_fine = 1.1 %.
// e_ext is compared with the value the tabulated phi_ext implies,
// (10.8801 - 10.7880) / 10.8801 = 0.85 %.
TEST(StudyMathTest, CelikTable1AxialVelocity) {
  const ThreeGrid g = Analyse(Size2d(18000), 10.7880, Size2d(4500), 10.7250, Size2d(980), 10.6050);
  EXPECT_EQ(g.behaviour, Behaviour::kMonotone);
  EXPECT_NEAR(g.r21, 2.0, 1e-12);
  EXPECT_NEAR(g.r32, 2.143, 5e-4);
  ASSERT_TRUE(g.order);
  EXPECT_NEAR(*g.order, 0.75, 0.005);
  EXPECT_NEAR(*g.extrapolated, 10.8801, 5e-4);
  EXPECT_NEAR(*g.relative_change_21, 0.006, 0.0005);
  EXPECT_NEAR(*g.extrapolated_error, (10.8801 - 10.7880) / 10.8801, 0.0001);
  EXPECT_NEAR(*g.gci_fine, 0.011, 0.0005);
}

// Table 1, third column (y = 0.8): 6.0042, 5.9624, 6.0909 swing about
// their limit. Reported as oscillatory, with no order and no extrapolate;
// the uncertainty is half the swing.
TEST(StudyMathTest, CelikTable1OscillatoryColumn) {
  const ThreeGrid g = Analyse(Size2d(18000), 6.0042, Size2d(4500), 5.9624, Size2d(980), 6.0909);
  EXPECT_EQ(g.behaviour, Behaviour::kOscillatory);
  EXPECT_EQ(BehaviourName(g.behaviour), "oscillatory");
  EXPECT_FALSE(g.order);
  EXPECT_FALSE(g.extrapolated);
  EXPECT_FALSE(g.gci_fine);
  ASSERT_TRUE(g.oscillation_half_range);
  EXPECT_NEAR(*g.oscillation_half_range, 0.5 * (6.0909 - 5.9624) / 6.0042, 1e-12);
}

// f(h) = 1 + 0.3 h^2: p = 2 and f_ext = 1 exactly, with a constant ratio
// and with ratios that differ (which needs the iteration of Celik eq. 3).
TEST(StudyMathTest, QuadraticSeriesGivesOrderTwoAndItsLimit) {
  const auto f = [](double h) { return 1 + 0.3 * h * h; };
  for (const auto& h : {std::array<double, 3>{1, 2, 4}, std::array<double, 3>{4, 5.6, 8},
                        std::array<double, 3>{1, 1.3, 2.1}}) {
    const ThreeGrid g = Analyse(h[0], f(h[0]), h[1], f(h[1]), h[2], f(h[2]));
    EXPECT_EQ(g.behaviour, Behaviour::kMonotone);
    ASSERT_TRUE(g.order);
    EXPECT_NEAR(*g.order, 2.0, 1e-9) << h[0] << " " << h[1] << " " << h[2];
    EXPECT_NEAR(*g.extrapolated, 1.0, 1e-9);
    // The error of the finest result, and the GCI its 1.25-fold bound.
    const double error = (f(h[0]) - 1) / f(h[0]);
    EXPECT_NEAR(*g.gci_fine, 1.25 * error, 1e-9);
    // Exact power law: GCI_coarse / (r21^p GCI_fine) = f1 / f2.
    EXPECT_NEAR(*g.asymptotic_ratio, f(h[0]) / f(h[1]), 1e-9);
  }
}

TEST(StudyMathTest, ObservedOrderOfConstantRatioIsClosedForm) {
  EXPECT_NEAR(*ObservedOrder(1.41, 1.41, std::pow(1.41, 1.7)), 1.7, 1e-12);
  // A change that grows on refinement has no positive order.
  EXPECT_FALSE(ObservedOrder(2, 2, 0.5));
  EXPECT_FALSE(ObservedOrder(1.5, 1.8, 0.3));
}

TEST(StudyMathTest, UnchangedDivergingAndIndeterminateAreNamed) {
  ThreeGrid g = Analyse(1, 1.5, 1.41, 1.5, 2, 1.5);
  EXPECT_EQ(g.behaviour, Behaviour::kUnchanged);
  EXPECT_EQ(*g.extrapolated, 1.5);
  EXPECT_EQ(*g.gci_fine, 0);
  EXPECT_FALSE(g.order);

  g = Analyse(1, 1.0, 2, 1.2, 4, 1.25);  // the change grows on refinement
  EXPECT_EQ(g.behaviour, Behaviour::kDiverging);
  EXPECT_FALSE(g.extrapolated);

  g = Analyse(1, 1.0, 2, 1.0, 4, 1.25);
  EXPECT_EQ(g.behaviour, Behaviour::kIndeterminate);
  EXPECT_FALSE(g.extrapolated);
}

TEST(StudyMathTest, BadInputIsRefused) {
  ThreeGrid g;
  std::string error;
  EXPECT_FALSE(AnalyseThreeGrids(2, 1, 1, 1, 4, 1, &g, &error));
  EXPECT_NE(error.find("finest first"), std::string::npos) << error;
  EXPECT_FALSE(AnalyseThreeGrids(1, NAN, 2, 1, 4, 1, &g, &error));
}

TEST(StudyMathTest, RelativeChangeIsOfTheFinerResult) {
  EXPECT_NEAR(*RelativeChange(1.1, 1.0), -0.1, 1e-15);
  EXPECT_NEAR(*RelativeChange(-1.1, -1.0), 0.1, 1e-15);
  EXPECT_FALSE(RelativeChange(1.0, 0.0));
}

}  // namespace
}  // namespace pba::cli::study
