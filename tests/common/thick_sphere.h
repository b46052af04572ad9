// The thick-walled sphere under internal pressure (VALIDATION.md), shared by
// its verification test and the element benchmark: the scene (one octant on
// symmetry planes, radii 10 and 20 mm), the Lame solution and the
// incompressible neo-Hookean pressure-stretch curve.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "common/scene_builders.h"
#include "pba/solve.h"

namespace pba::testing {

inline constexpr double kSphereInnerMm = 10, kSphereOuterMm = 20;

inline SceneSpec PressurisedShell(const MaterialSpec& material, double pressure_pa, double h_mm,
                                  ElementType element = ElementType::kDefault) {
  using K = BoundaryConditionSpec::Kind;
  SceneSpec s;
  s.name = "thick sphere";
  s.geometry.kind = GeometrySpec::Kind::kSphericalShell;
  s.geometry.spherical_shell = {kSphereInnerMm, kSphereOuterMm};
  s.mesh.element_size_mm = h_mm;
  s.mesh.element = element;
  s.material = material;
  BoundaryConditionSpec pressure = Condition("inner", K::kPressure);
  pressure.pressure_pa = pressure_pa;
  s.boundary_conditions = {Condition("x0", K::kSymmetry), Condition("y0", K::kSymmetry),
                           Condition("z0", K::kSymmetry), pressure};
  return s;
}

// Mean radial displacement of the nodes on the sphere of radius r [mm].
inline double MeanRadialDisplacement(const Solution& solution, double r) {
  double sum = 0;
  int count = 0;
  for (std::size_t i = 0; i < solution.nodes_mm.size() / 3; ++i) {
    const Eigen::Vector3d x(&solution.nodes_mm[3 * i]);
    if (std::abs(x.norm() - r) > 1e-6 * r) continue;
    sum += Eigen::Vector3d(&solution.displacement_mm[3 * i]).dot(x.normalized());
    ++count;
  }
  return sum / count;
}

// Lame: u(r) = p a^3 / (E (b^3 - a^3)) [(1 - 2 nu) r + (1 + nu) b^3 / (2 r^2)] [mm].
inline double LameDisplacement(double p, double e, double nu, double r) {
  const double a = kSphereInnerMm, b = kSphereOuterMm;
  return p * a * a * a / (e * (b * b * b - a * a * a)) *
         ((1 - 2 * nu) * r + (1 + nu) * b * b * b / (2 * r * r));
}

// Incompressible neo-Hookean sphere, radii A and B = 2 A:
// p / mu = 2 (1 / lb - 1 / la) + (lb^-4 - la^-4) / 2,
// lb^3 = 1 + (A / B)^3 (la^3 - 1).
inline double IncompressiblePressure(double la) {
  const double lb = std::cbrt(1 + (la * la * la - 1) / 8);
  return 2 * (1 / lb - 1 / la) + (std::pow(lb, -4) - std::pow(la, -4)) / 2;
}

}  // namespace pba::testing
