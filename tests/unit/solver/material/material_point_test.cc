// The material-point kernel both engines share (material/material_point.h):
// the neo-Hookean closed form against the general path through
// HyperelasticMaterial::Isochoric, the Prony state's two readings (the
// implicit alpha S_iso + offset and the explicit Relax) against each other
// and against the hereditary integral of a linear stress history, and the
// first Piola-Kirchhoff stress against the second through P = F S.

#include "material/material_point.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "material/polynomial.h"

namespace pba {
namespace {

// A deformation with shear, stretch and volume change (det F = 1.0316).
Eigen::Matrix<double, 3, 3, Eigen::RowMajor> SomeF() {
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> f;
  f << 1.08, 0.12, -0.03, 0.05, 0.94, 0.07, -0.02, 0.09, 1.03;
  return f;
}

PolynomialMaterial NeoHookean(double mu, double bulk) {
  return PolynomialMaterial(NeoHookeanCoefficients(mu, bulk));
}

TEST(MaterialPointTest, NeoHookeanClosedFormIsTheGeneralPath) {
  const PolynomialMaterial material = NeoHookean(1200, 6e5);
  const auto f = SomeF();
  double cof[9];
  Cofactor(f.data(), cof);
  const double j = Determinant(f.data());
  ASSERT_NEAR(j, f.determinant(), 1e-15);
  const double p = material.Volumetric(j).first;
  double closed[9], general[9];
  NeoHookeanFirstPiola(1200, p, f.data(), cof, j, std::cbrt(j), closed);
  FirstPiola(material, nullptr, nullptr, f.data(), cof, p, general);
  // And the total P = F S from the material's own second Piola-Kirchhoff
  // stress: the kernel's split (isochoric, then p cof F) adds up to it.
  const Eigen::Matrix3d fm = f;
  const Eigen::Matrix3d total = fm * VoigtToSymmetric(material.Stress(fm));
  for (int k = 0; k < 9; ++k) {
    EXPECT_NEAR(closed[k], general[k], 1e-9 * 1200) << k;
    EXPECT_NEAR(general[k], total(k / 3, k % 3), 1e-9 * 1200) << k;
  }
  // The closed form is not trivially the identity map: a sheared F has
  // off-diagonal stress.
  EXPECT_GT(std::abs(closed[1]), 10.0);
}

TEST(MaterialPointTest, RelaxAgreesWithTheIncrementalPotentialsOffset) {
  const PronySeries series{{0.45, 0.3}, {0.5, 20}};
  ASSERT_TRUE(series.Validate().ok());
  std::vector<double> state(PronyStateSize(2), 0.0);
  ASSERT_EQ(state.size(), 18u);
  for (int n = 1; n <= 6; ++n) {
    const double dt = 0.05 * n;
    const ViscousStep step = ViscousStep::Of(series, dt);
    Vector6d s_iso;
    s_iso << 100.0 * n, -40.0 * n, 3.0 * n * n, 7, -2.0 * n, 11;
    const Vector6d implicit = step.alpha * s_iso + step.Offset(state.data());
    const Vector6d relaxed = step.Relax(s_iso, state.data());
    for (int c = 0; c < 6; ++c) EXPECT_NEAR(relaxed(c), implicit(c), 1e-12 * 400) << n;
    // The state now holds the step's S_iso.
    for (int c = 0; c < 6; ++c) EXPECT_EQ(state[c], s_iso(c));
  }
}

TEST(MaterialPointTest, RelaxIsExactForALinearStressHistory) {
  // S_iso(t) = r t in one component; the hereditary integral is
  // S_visc(t) = r [g_inf t + sum_k g_k tau_k (1 - exp(-t / tau_k))].
  const PronySeries series{{0.5, 0.2}, {0.1, 3}};
  const double r = 250, dt = 0.01;
  std::vector<double> state(PronyStateSize(2), 0.0);
  const ViscousStep step = ViscousStep::Of(series, dt);
  double s_visc = 0;
  const int steps = 70;
  for (int n = 1; n <= steps; ++n) {
    Vector6d s_iso = Vector6d::Zero();
    s_iso(0) = r * n * dt;
    s_visc = step.Relax(s_iso, state.data())(0);
  }
  const double t = steps * dt;
  double exact = series.LongTermFactor() * t;
  for (std::size_t k = 0; k < series.g.size(); ++k) {
    exact += series.g[k] * series.tau_s[k] * -std::expm1(-t / series.tau_s[k]);
  }
  exact *= r;
  EXPECT_NEAR(s_visc, exact, 1e-10 * exact);
  // Relaxation took place: the viscous stress is well below the elastic one.
  EXPECT_LT(s_visc, 0.8 * r * t);
}

TEST(MaterialPointTest, FirstPiolaAdvancesTheStateOnlyWhenRelaxing) {
  const PolynomialMaterial material = NeoHookean(900, 4e5);
  const auto f = SomeF();
  double cof[9];
  Cofactor(f.data(), cof);
  const PronySeries series{{0.6}, {0.2}};
  const ViscousStep step = ViscousStep::Of(series, 0.01);
  std::vector<double> state(PronyStateSize(1), 0.0);
  double elastic[9], viscous[9];
  FirstPiola(material, nullptr, state.data(), f.data(), cof, 0, elastic);
  for (double v : state) EXPECT_EQ(v, 0.0);
  FirstPiola(material, &step, state.data(), f.data(), cof, 0, viscous);
  Vector6d s_iso;
  material.Isochoric(Eigen::Matrix3d(f), nullptr, &s_iso, nullptr);
  for (int c = 0; c < 6; ++c) EXPECT_EQ(state[c], s_iso(c));
  // A sudden step of dt << tau: the viscous stress is almost the elastic
  // one (alpha -> 1), never more.
  for (int k = 0; k < 9; ++k) {
    EXPECT_NEAR(viscous[k], elastic[k], 0.02 * std::abs(elastic[k]) + 1e-9) << k;
  }
  EXPECT_LT(std::abs(viscous[0]), std::abs(elastic[0]));
}

}  // namespace
}  // namespace pba
