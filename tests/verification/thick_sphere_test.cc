// The thick-walled sphere under internal pressure (VALIDATION.md), solved on
// one octant with symmetry planes:
//   - small strain against the Lame solution, converging under refinement,
//     with the Zienkiewicz-Zhu estimate checked against the true error in the
//     energy norm (effectivity index within 0.5 .. 2);
//   - finite strain, nearly incompressible neo-Hookean under a follower
//     pressure, against the incompressible pressure-stretch curve.
#include "common/thick_sphere.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "common/scene_builders.h"
#include "fem/hex8.h"
#include "fem/tet10.h"
#include "material/hyperelastic.h"
#include "material/linear_elastic.h"
#include "mesh/quadratic.h"
#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

constexpr double kA = testing::kSphereInnerMm, kB = testing::kSphereOuterMm;
using testing::IncompressiblePressure;
using testing::MeanRadialDisplacement;
using testing::PressurisedShell;

// Lame: u(r) = p a^3 / (E (b^3 - a^3)) [(1 - 2 nu) r + (1 + nu) b^3 / (2 r^2)],
// sigma_rr = p a^3 / (b^3 - a^3) (1 - b^3 / r^3),
// sigma_tt = p a^3 / (b^3 - a^3) (1 + b^3 / (2 r^3)).
struct Lame {
  double p, e, nu;
  double U(double r) const { return testing::LameDisplacement(p, e, nu, r); }
  Eigen::Matrix3d Stress(const Eigen::Vector3d& x) const {
    const double r = x.norm(), c = p * kA * kA * kA / (kB * kB * kB - kA * kA * kA);
    const double b3r3 = kB * kB * kB / (r * r * r);
    const double srr = c * (1 - b3r3), stt = c * (1 + 0.5 * b3r3);
    const Eigen::Vector3d n = x / r;
    return stt * Eigen::Matrix3d::Identity() + (srr - stt) * n * n.transpose();
  }
};

// sigma : C^-1 : sigma for isotropic compliance, per unit volume [Pa].
double EnergyDensity2(const Eigen::Matrix3d& s, double e, double nu) {
  const double tr = s.trace();
  return ((1 + nu) * (s.array() * s.array()).sum() - nu * tr * tr) / e;
}

struct EnergyErrors {
  double exact_error = 0;  // ||sigma - sigma_h||_E, true [sqrt(Pa) m^1.5 up to units]
  double estimated_error = 0;
};

// True energy-norm error by the 4-point rule per element, beside the ZZ
// estimate recovered from the summary's relative figure
// eta = sqrt(E*^2 / (E*^2 + U_h^2)), U_h^2 = integral sigma_h : C^-1 : sigma_h.
EnergyErrors EnergyNormErrors(const Solution& solution, const Lame& lame) {
  constexpr double kAlpha = 0.5854101966249685, kBeta = 0.1381966011250105;
  double error2 = 0, energy2 = 0;
  const std::size_t ne = solution.tets.size() / 4;
  for (std::size_t e = 0; e < ne; ++e) {
    Eigen::Matrix<double, 4, 3> x;
    for (int a = 0; a < 4; ++a)
      x.row(a) = Eigen::RowVector3d(&solution.nodes_mm[3 * solution.tets[4 * e + a]]);
    const double volume =
        std::abs((x.row(1) - x.row(0)).cross(x.row(2) - x.row(0)).dot(x.row(3) - x.row(0))) / 6;
    const double* s = &solution.stress_pa[6 * e];
    Eigen::Matrix3d sh;
    sh << s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2];
    energy2 += volume * EnergyDensity2(sh, lame.e, lame.nu);
    for (int q = 0; q < 4; ++q) {
      Eigen::Vector3d point = Eigen::Vector3d::Zero();
      for (int a = 0; a < 4; ++a) point += (a == q ? kAlpha : kBeta) * x.row(a).transpose();
      error2 += 0.25 * volume * EnergyDensity2(lame.Stress(point) - sh, lame.e, lame.nu);
    }
  }
  const double eta = solution.summary.error.relative_error;
  return {std::sqrt(error2), std::sqrt(eta * eta * energy2 / (1 - eta * eta))};
}

// The same for 10-node tetrahedra and bricks, whose stress varies within
// the element: the model is rebuilt (meshing is deterministic) and the
// finite-element strain evaluated at the points of a rule finer than the
// element's own (14-point degree 5; 3 x 3 x 3 Gauss), all in mm and Pa.
EnergyErrors EnergyNormErrorsHigher(const SceneSpec& scene, const Solution& solution,
                                    const Lame& lame) {
  Model model;
  const Status built = BuildModel(scene, &model);
  EXPECT_TRUE(built.ok()) << built.ToString();
  const Mesh& mesh = model.mesh;
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int i = 0; i < u.size(); ++i) u(i) = solution.displacement_mm[i] * 1e-3;
  const Matrix6d d = IsotropicElasticity(lame.e, lame.nu);
  double error2 = 0, energy2 = 0;
  const auto add = [&](const Eigen::Vector3d& x_m, const Vector6d& strain, double dv_m3) {
    const Vector6d stress = d * strain;
    const Eigen::Matrix3d sh = VoigtToSymmetric(stress);
    const double dv = dv_m3 * 1e9;  // mm^3, as EnergyNormErrors
    energy2 += dv * EnergyDensity2(sh, lame.e, lame.nu);
    error2 += dv * EnergyDensity2(lame.Stress(x_m * 1e3) - sh, lame.e, lame.nu);
  };
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (mesh.quadratic()) {
      const Tet10Nodes x = Tet10Coordinates(mesh, e);
      const Vector30d ue = GatherElementTet10(mesh, e, u);
      for (const QuadraturePoint& q : Tet10MassRule()) {
        Tet10Nodes grad;
        const double det = Tet10Gradients(x, q.xi, &grad);
        add(x.transpose() * Tet10ShapeFunctions(q.xi), Tet10Strain(x, ue, q.xi), q.weight * det);
      }
    } else {
      const Hex8Nodes x = Hex8Coordinates(mesh, e);
      const Vector24d ue = GatherElementHex8(mesh, e, u);
      const double g[3] = {-std::sqrt(0.6), 0, std::sqrt(0.6)}, w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d xi(g[i], g[j], g[k]);
            Hex8Nodes grad;
            const double det = Hex8Gradients(x, xi, &grad);
            add(x.transpose() * Hex8ShapeFunctions(xi), Hex8Strain(x, ue, xi),
                w[i] * w[j] * w[k] * det);
          }
        }
      }
    }
  }
  const double eta = solution.summary.error.relative_error;
  return {std::sqrt(error2), std::sqrt(eta * eta * energy2 / (1 - eta * eta))};
}

TEST(ThickSphere, LinearMatchesLameAndTheErrorEstimateIsEffective) {
  const Lame lame{100, 3000, 0.49};
  MaterialSpec material;
  material.kind = MaterialSpec::Kind::kLinearElastic;
  material.linear_elastic = {lame.e, lame.nu};
  ASSERT_NEAR(lame.U(kA), 0.284762, 1e-6);  // the reference values
  ASSERT_NEAR(lame.U(kB), 0.072857, 1e-6);
  double previous_error = INFINITY;
  for (double h : {2.5, 1.25}) {
    Solution solution;
    const Status status = SolveScene(PressurisedShell(material, lame.p, h), {}, &solution);
    ASSERT_TRUE(status.ok()) << status.message();
    const double ua = MeanRadialDisplacement(solution, kA);
    const double ub = MeanRadialDisplacement(solution, kB);
    const EnergyErrors errors = EnergyNormErrors(solution, lame);
    const double effectivity = errors.estimated_error / errors.exact_error;
    std::printf(
        "h = %4.2f mm, %d elements: u(a) = %.6f mm (Lame %.6f, %+.2f %%), u(b) = %.6f mm "
        "(%+.2f %%); energy-norm error estimated %.4g, true %.4g, effectivity %.3f; %.2f s\n",
        h, static_cast<int>(solution.summary.elements), ua, lame.U(kA), 100 * (ua / lame.U(kA) - 1),
        ub, 100 * (ub / lame.U(kB) - 1), errors.estimated_error, errors.exact_error, effectivity,
        solution.summary.wall_time_s);
    // Plain linear tetrahedra at nu = 0.49 (K / mu = 50) are too stiff and
    // converge at first order: halving h must halve the error.
    const double error = std::abs(ua / lame.U(kA) - 1) + std::abs(ub / lame.U(kB) - 1);
    EXPECT_LT(error, 0.6 * previous_error);
    previous_error = error;
    EXPECT_GT(effectivity, 0.5);
    EXPECT_LT(effectivity, 2.0);
  }
}

// 10-node elements: quadratic displacement, curved faces on the spheres. The
// stress recovery for the estimate is the quadratic one (error_estimator.h),
// and the true error is integrated with the element's own 4-point rule on
// its mean stress, so only the displacements are compared tightly here.
TEST(ThickSphere, HigherElementsMatchLameOnCoarseMeshes) {
  const Lame lame{100, 3000, 0.49};
  MaterialSpec material;
  material.kind = MaterialSpec::Kind::kLinearElastic;
  material.linear_elastic = {lame.e, lame.nu};
  for (const ElementType element : {ElementType::kTet10, ElementType::kHex8}) {
    const bool tet10 = element == ElementType::kTet10;
    double previous_error = INFINITY;
    for (double h : {5.0, 2.5}) {
      SceneSpec scene = PressurisedShell(material, lame.p, h);
      scene.mesh.element = element;
      Solution solution;
      const Status status = SolveScene(scene, {}, &solution);
      ASSERT_TRUE(status.ok()) << status.message();
      EXPECT_EQ(solution.nodes_per_element, tet10 ? 10 : 8);
      const double ua = MeanRadialDisplacement(solution, kA);
      const double ub = MeanRadialDisplacement(solution, kB);
      const EnergyErrors errors = EnergyNormErrorsHigher(scene, solution, lame);
      const double effectivity = errors.estimated_error / errors.exact_error;
      EXPECT_GT(effectivity, 0.5);
      EXPECT_LT(effectivity, 2.0);
      std::printf(
          "%s, h = %4.2f mm, %d elements, %d unknowns: u(a) = %.6f mm (%+.3f %%), u(b) = %.6f mm "
          "(%+.3f %%), estimated error %.2f %%, effectivity %.3f; %.2f s\n",
          tet10 ? "TET10" : "HEX8", h, static_cast<int>(solution.summary.elements),
          static_cast<int>(solution.summary.dofs), ua, 100 * (ua / lame.U(kA) - 1), ub,
          100 * (ub / lame.U(kB) - 1), 100 * solution.summary.error.relative_error, effectivity,
          solution.summary.wall_time_s);
      const double error = std::abs(ua / lame.U(kA) - 1) + std::abs(ub / lame.U(kB) - 1);
      EXPECT_LT(error, 0.5 * previous_error);
      previous_error = error;
    }
    // Both converge at second order here; the quadratic tetrahedron has 7
    // times the unknowns of the brick on the same grid.
    EXPECT_LT(previous_error, tet10 ? 0.01 : 0.04);
  }
}

// A radial line profile (outputs.profiles) read against Lame: the stress
// along a radius is sigma_rr, the displacement along it u(r). Elements carry
// one (mean) stress each, so a single sample is the stress of the element
// that holds it, whose centre may lie half an element away (sigma_rr
// changes by 7 Pa/mm at mid-thickness, -19.6 Pa): the profile is read as one
// would, by its mean over the samples within 1.5 mm of mid-thickness,
// against Lame's mean at the same points. One line runs in a general
// direction, one along the octant's diagonal, where the mesh's faces and
// edges lie on the line and the samples take the mean of the elements
// sharing them.
TEST(ThickSphere, RadialProfileMatchesLame) {
  struct Case {
    const char* name;
    ElementType element;
    double nu, h_mm;
    bool diagonal;
    double u_tolerance;  // on u_r at mid-thickness, fraction
  };
  const double p = 100, e = 3000;
  for (const Case& c : {Case{"TET4", ElementType::kTet4, 0.3, 1.25, false, 0.02},
                        Case{"TET10", ElementType::kTet10, 0.45, 2.5, false, 0.01},
                        Case{"HEX8", ElementType::kHex8, 0.45, 2.5, false, 0.04},
                        Case{"HEX8", ElementType::kHex8, 0.45, 2.5, true, 0.04}}) {
    MaterialSpec material;
    material.kind = MaterialSpec::Kind::kLinearElastic;
    material.linear_elastic = {e, c.nu};
    SceneSpec scene = PressurisedShell(material, p, c.h_mm, c.element);
    const Eigen::Vector3d t =
        (c.diagonal ? Eigen::Vector3d(1, 1, 1) : Eigen::Vector3d(0.5, 0.6, 0.62)).normalized();
    ProfileSpec radial;
    radial.name = "radial";
    radial.from_mm = {kA * t.x(), kA * t.y(), kA * t.z()};
    radial.to_mm = {kB * t.x(), kB * t.y(), kB * t.z()};
    radial.points = 81;
    scene.outputs.profiles = {radial};
    Solution solution;
    const Status status = SolveScene(scene, {}, &solution);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(solution.profiles.size(), 1u);
    const double lame_c = p * kA * kA * kA / (kB * kB * kB - kA * kA * kA);
    const auto srr = [&](double r) { return lame_c * (1 - kB * kB * kB / (r * r * r)); };
    const double mid = 0.5 * (kA + kB);
    double sampled = 0, lame = 0, u_mid = NAN, at_mid = NAN;
    int window = 0;
    for (const auto& row : solution.profiles[0].rows) {
      const double r = kA + row[0];
      if (std::isnan(row[7])) continue;
      if (std::abs(r - mid) < 1e-9) {
        at_mid = row[7];
        u_mid = Eigen::Vector3d(row[4], row[5], row[6]).dot(t);
      }
      if (std::abs(r - mid) > 1.5 + 1e-9) continue;
      sampled += row[7], lame += srr(r), ++window;
    }
    sampled /= window, lame /= window;
    const double lame_u = testing::LameDisplacement(p, e, c.nu, mid);
    const ProfileSummary& summary = solution.summary.profiles[0];
    std::printf(
        "%s%s, h = %g mm, nu = %g, %d elements: %d of %d points inside; sigma_rr at r = 15 mm "
        "%.3f Pa (Lame %.3f), mean over r = 13.5..16.5 mm %.3f Pa (Lame %.3f, %+.2f %%); u_r(15) "
        "%.5f mm (Lame %.5f, %+.2f %%); largest |stress along| %.2f Pa at r = %.3f mm\n",
        c.name, c.diagonal ? " (diagonal)" : "", c.h_mm, c.nu,
        static_cast<int>(solution.summary.elements), summary.inside, summary.points, at_mid,
        srr(mid), sampled, lame, 100 * (sampled / lame - 1), u_mid, lame_u,
        100 * (u_mid / lame_u - 1), summary.max_stress_along_pa, kA + summary.at_distance_mm);
    // The faceted outer surface may leave the last point (r = 20 mm) out.
    EXPECT_GE(summary.inside, 80) << c.name;
    EXPECT_NEAR(sampled, lame, 0.03 * std::abs(lame)) << c.name;
    EXPECT_NEAR(u_mid, lame_u, c.u_tolerance * lame_u) << c.name;
    // The largest compression is next to the cavity wall.
    EXPECT_LT(summary.max_stress_along_pa, 0) << c.name;
    EXPECT_LT(summary.at_distance_mm, 2.5) << c.name;
  }
}

TEST(ThickSphere, FiniteStrainFollowsTheIncompressiblePressureStretchCurve) {
  ASSERT_NEAR(IncompressiblePressure(1.25), 0.551869, 1e-6);
  ASSERT_NEAR(IncompressiblePressure(1.5), 0.755433, 1e-6);
  const double mu = 1000;
  MaterialSpec material;
  material.kind = MaterialSpec::Kind::kNeoHookean;
  material.neo_hookean = {mu, 1e4 * mu};
  // The curve peaks near la = 1.8 (p / mu = 0.81): pressure control reaches
  // the rising branch. The faceted inner surface and the linear elements
  // converge at second order in h.
  for (double stretch : {1.25, 1.5}) {
    double previous_error = INFINITY;
    for (double h : {2.5, 1.25}) {
      SceneSpec scene = PressurisedShell(material, IncompressiblePressure(stretch) * mu, h);
      scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
      Solution solution;
      const Status status = SolveScene(scene, {}, &solution);
      ASSERT_TRUE(status.ok()) << status.message();
      const double la = 1 + MeanRadialDisplacement(solution, kA) / kA;
      const double error = std::abs(la / stretch - 1);
      std::printf(
          "p / mu = %.6f, h = %4.2f mm: inner stretch %.5f (incompressible %.2f, %+.2f %%), %zu "
          "increments, %d Newton iterations, %.2f s\n",
          IncompressiblePressure(stretch), h, la, stretch, 100 * (la / stretch - 1),
          solution.summary.increments.size(), solution.summary.newton_iterations,
          solution.summary.wall_time_s);
      EXPECT_LT(error, previous_error / 3) << "h = " << h;
      previous_error = error;
    }
    EXPECT_LT(previous_error, 0.01);
  }
  // Bricks, and 10-node elements (plain and mean-dilatation) on a coarse mesh
  // with curved faces.
  struct Coarse {
    const char* name;
    ElementType element;
    double h_mm;
  };
  for (const Coarse& c :
       {Coarse{"HEX8", ElementType::kHex8, 2.5}, Coarse{"TET10", ElementType::kTet10, 3.0},
        Coarse{"TET10_MD", ElementType::kTet10Md, 3.0}}) {
    for (double stretch : {1.25, 1.5}) {
      SceneSpec scene = PressurisedShell(material, IncompressiblePressure(stretch) * mu, c.h_mm);
      scene.analysis.type = AnalysisSpec::Type::kNonlinearStatic;
      scene.mesh.element = c.element;
      Solution solution;
      const Status status = SolveScene(scene, {}, &solution);
      ASSERT_TRUE(status.ok()) << status.message();
      const double la = 1 + MeanRadialDisplacement(solution, kA) / kA;
      std::printf(
          "%s, p / mu = %.6f, h = %g mm: inner stretch %.5f (%+.2f %%), %d Newton iterations, "
          "%.2f s\n",
          c.name, IncompressiblePressure(stretch), c.h_mm, la, 100 * (la / stretch - 1),
          solution.summary.newton_iterations, solution.summary.wall_time_s);
      EXPECT_NEAR(la, stretch, 0.01 * stretch) << c.name;
    }
  }
}

}  // namespace
}  // namespace pba
