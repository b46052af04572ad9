// The element fields written from samples: the finite-strain measures of a
// stretch against their closed forms, the volume-weighted means of two
// samples, and what the writer puts where.
#include "analysis/element_fields.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pba {
namespace {

constexpr double kTol = 1e-14;

// F = diag(l1, l2, l3): E = (l^2 - 1) / 2, e = (1 - l^-2) / 2, J = l1 l2 l3,
// sigma = F S F^T / J = l^2 S / J on the diagonal, no shear.
TEST(ElementFields, DiagonalStretchHasTheClosedForms) {
  const Eigen::Vector3d l(1.2, 0.9, 0.8);
  const Eigen::Matrix3d f = l.asDiagonal();
  Vector6d pk2;
  pk2 << 100, -50, 20, 0, 0, 0;
  const ElementFields p = FieldsFromPk2(f, pk2);
  EXPECT_NEAR(p.j, l.prod(), kTol);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(p.green(i), 0.5 * (l(i) * l(i) - 1), kTol);
    EXPECT_NEAR(p.almansi(i), 0.5 * (1 - 1 / (l(i) * l(i))), kTol);
    EXPECT_NEAR(p.cauchy(i), l(i) * l(i) * pk2(i) / l.prod(), 1e-12);
    EXPECT_EQ(p.green(i + 3), 0);
    EXPECT_EQ(p.almansi(i + 3), 0);
    EXPECT_EQ(p.cauchy(i + 3), 0);
  }
  EXPECT_EQ(p.pk2, pk2);
  // S = J F^-1 sigma F^-T takes it back.
  const ElementFields back = FieldsFromCauchy(f, p.cauchy);
  EXPECT_EQ(back.cauchy, p.cauchy);
  EXPECT_EQ(back.green, p.green);
  EXPECT_NEAR(back.j, p.j, kTol);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(back.pk2(i), pk2(i), 1e-12);
}

TEST(ElementFieldSum, MeansAreVolumeWeighted) {
  const ElementFields a =
      FieldsFromPk2(Eigen::Vector3d(1.1, 1.0, 0.95).asDiagonal(), Vector6d::Constant(10));
  const ElementFields b =
      FieldsFromPk2(Eigen::Vector3d(0.7, 1.3, 1.0).asDiagonal(), Vector6d::Constant(-30));
  const double wa = 1e-9, wb = 3e-9;  // volumes [m^3]
  ElementFieldSum sum;
  sum.Add(wa, a);
  sum.Add(wb, b);
  EXPECT_DOUBLE_EQ(sum.weight(), wa + wb);
  const ElementFields mean = sum.Mean();
  const auto expect = [&](double x, double y) { return (wa * x + wb * y) / (wa + wb); };
  EXPECT_NEAR(mean.j, expect(a.j, b.j), kTol);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(mean.green(i), expect(a.green(i), b.green(i)), kTol);
    EXPECT_NEAR(mean.almansi(i), expect(a.almansi(i), b.almansi(i)), kTol);
    EXPECT_NEAR(mean.pk2(i), expect(a.pk2(i), b.pk2(i)), 1e-12);
    EXPECT_NEAR(mean.cauchy(i), expect(a.cauchy(i), b.cauchy(i)), 1e-12);
  }
  // The largest strain is the points', not the mean's: (1.3^2 - 1) / 2 at b,
  // which the mean dilutes.
  EXPECT_NEAR(sum.LargestStrain(), 0.5 * (1.69 - 1), kTol);
  EXPECT_LT(mean.green.cwiseAbs().maxCoeff(), sum.LargestStrain());

  // One point: its own fields back, and its largest strain.
  ElementFieldSum one;
  one.Add(wb, b);
  EXPECT_NEAR(one.LargestStrain(), b.green.cwiseAbs().maxCoeff(), kTol);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(one.Mean().green(i), b.green(i), kTol);
  EXPECT_NEAR(one.Mean().j, b.j, kTol);
}

TEST(ElementFields, WriterFillsTheElementsSlots) {
  Solution solution;
  StartFiniteStrainFields(3, &solution);
  ASSERT_EQ(solution.strain.size(), 18u);
  ASSERT_EQ(solution.pk2_stress_pa.size(), 18u);
  ASSERT_EQ(solution.jacobian.size(), 3u);
  Vector6d pk2;
  pk2 << 100, -50, 20, 5, 0, 0;
  const ElementFields p = FieldsFromPk2(Eigen::Vector3d(1.2, 0.9, 0.8).asDiagonal(), pk2);
  EXPECT_EQ(WriteFiniteStrainFields(1, p, &solution), p.green.cwiseAbs().maxCoeff());
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(solution.strain[6 + i], p.green(i));
    EXPECT_EQ(solution.almansi_strain[6 + i], p.almansi(i));
    EXPECT_EQ(solution.pk2_stress_pa[6 + i], p.pk2(i));
    EXPECT_EQ(solution.stress_pa[6 + i], p.cauchy(i));
    EXPECT_EQ(solution.strain[i], 0);  // elements 0 and 2 untouched
    EXPECT_EQ(solution.stress_pa[12 + i], 0);
  }
  const Vector6d& s = p.cauchy;
  const double von_mises =
      std::sqrt(0.5 * ((s(0) - s(1)) * (s(0) - s(1)) + (s(1) - s(2)) * (s(1) - s(2)) +
                       (s(2) - s(0)) * (s(2) - s(0))) +
                3 * (s(3) * s(3) + s(4) * s(4) + s(5) * s(5)));
  EXPECT_NEAR(solution.von_mises_pa[1], von_mises, 1e-9);
  EXPECT_EQ(solution.jacobian[1], p.j);
  EXPECT_EQ(solution.jacobian[0], 1);  // unwritten: undeformed
  EXPECT_EQ(solution.von_mises_pa[2], 0);

  // The small-strain writer: strain, stress and von Mises only.
  Solution small;
  StartSmallStrainFields(2, &small);
  EXPECT_TRUE(small.pk2_stress_pa.empty());
  WriteSmallStrainFields(0, p.green, p.cauchy, &small);
  EXPECT_EQ(small.strain[2], p.green(2));
  EXPECT_EQ(small.stress_pa[3], p.cauchy(3));
  EXPECT_NEAR(small.von_mises_pa[0], von_mises, 1e-9);
  EXPECT_TRUE(small.jacobian.empty());
}

}  // namespace
}  // namespace pba
