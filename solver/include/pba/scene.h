// SceneSpec: the solver's own, protobuf-free description of one scene.
// It mirrors proto/pba/v1/scene.proto field by field (same names, same units),
// so a field path reported by ValidateScene() is the path in the YAML file.
// Units at this edge: lengths in mm, moduli and stresses in Pa.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "pba/status.h"

namespace pba {

struct BoxSpec {
  std::array<double, 3> size_mm{0, 0, 0};  // edge lengths along x, y, z [mm]
};

struct CylinderSpec {
  double radius_mm = 0;  // [mm]
  double height_mm = 0;  // [mm], axis along z, bottom centre at the origin
};

struct GeometrySpec {
  enum class Kind { kNone, kBox, kCylinder };
  Kind kind = Kind::kNone;
  BoxSpec box;
  CylinderSpec cylinder;
};

enum class ElementType {
  kDefault,  // TET4 for linear analyses, TET4_ANP for nonlinear ones
  kTet4,     // 4-node tetrahedron, one F per element (locks when nearly incompressible)
  kTet4Anp,  // 4-node tetrahedron with average nodal pressure (nonlinear analyses)
};

struct MeshSpec {
  ElementType element = ElementType::kDefault;
  // Target edge length of the structured grid [mm]; 0 picks a twentieth of the
  // body's largest dimension.
  double element_size_mm = 0;
};

// Isotropic small-strain elasticity (DOMAIN.md eq. 2.21).
struct LinearElasticParams {
  double youngs_modulus_pa = 0;  // E [Pa], > 0
  double poissons_ratio = 0;     // nu [-], -1 < nu < 0.5
  // Names the bad field as `path` + ".youngs_modulus_pa" or ".poissons_ratio".
  Status Validate(const std::string& path) const;
};

// Hyperelastic models, all with the uncoupled volumetric/deviatoric split
// W = W_iso(I1b, I2b or the isochoric stretches) + U(J) (DOMAIN.md eq. 2.32).
// The bulk modulus K = 2 / D1 sets U = (K / 2)(J - 1)^2.

// W = (mu / 2)(I1b - 3) + (K / 2)(J - 1)^2.
struct NeoHookeanParams {
  double shear_modulus_pa = 0;  // mu [Pa], > 0
  double bulk_modulus_pa = 0;   // K [Pa], > 0; brain tissue: 1e5..1e6 mu
};

// W = C10 (I1b - 3) + C01 (I2b - 3) + (K / 2)(J - 1)^2; mu0 = 2 (C10 + C01).
struct MooneyRivlinParams {
  double c10_pa = 0;  // [Pa]
  double c01_pa = 0;  // [Pa]; C10 + C01 > 0
  double bulk_modulus_pa = 0;  // K [Pa], > 0
};

// W = sum C_ij (I1b - 3)^i (I2b - 3)^j + sum_k (1 / D_k)(J - 1)^(2k), order
// N = max(i + j) <= 3, k = 1..N.
struct PolynomialTermSpec {
  int i = 0;  // power of (I1b - 3)
  int j = 0;  // power of (I2b - 3); 1 <= i + j <= 3
  double c_pa = 0;  // C_ij [Pa]
};
struct PolynomialParams {
  std::vector<PolynomialTermSpec> terms;
  std::vector<double> d_per_pa;  // D_1..D_N [1/Pa]; D_1 > 0, K = 2 / D_1
};

// W = sum_p (2 mu_p / alpha_p^2)(lb1^alpha_p + lb2^alpha_p + lb3^alpha_p - 3)
//     + (K / 2)(J - 1)^2, lb the isochoric principal stretches (Abaqus form).
struct OgdenTermSpec {
  double mu_pa = 0;  // [Pa]; sum of mu_p > 0
  double alpha = 0;  // [-], nonzero; brain: mu = 842 Pa, alpha = -4.7
};
struct OgdenParams {
  std::vector<OgdenTermSpec> terms;  // 1..3
  double bulk_modulus_pa = 0;        // K [Pa], > 0
};

struct MaterialSpec {
  enum class Kind { kNone, kLinearElastic, kNeoHookean, kMooneyRivlin, kPolynomial, kOgden };
  std::string name;
  Kind kind = Kind::kNone;
  LinearElasticParams linear_elastic;
  NeoHookeanParams neo_hookean;
  MooneyRivlinParams mooney_rivlin;
  PolynomialParams polynomial;
  OgdenParams ogden;

  bool hyperelastic() const { return kind != Kind::kNone && kind != Kind::kLinearElastic; }
};

struct BoundaryConditionSpec {
  // kSymmetry: the displacement normal to a planar face set is zero, the
  // others are free (a mirror plane of the model).
  enum class Kind { kNone, kFixed, kDisplacement, kSymmetry };
  std::string set;  // named face set of the geometry
  Kind kind = Kind::kNone;
  // kDisplacement: prescribed x, y, z components [mm]; nullopt = free.
  std::array<std::optional<double>, 3> displacement_mm;
};

// Load stepping and Newton-Raphson controls of a nonlinear static analysis;
// 0 (or unset) picks the default given.
struct NonlinearOptionsSpec {
  int increments = 0;       // initial number of load increments, default 5, <= 10000
  int max_iterations = 0;   // Newton iterations per increment, default 20, <= 1000
  double residual_tolerance = 0;      // relative force residual, default 1e-8, < 1
  double displacement_tolerance = 0;  // relative displacement correction, default 1e-8, < 1
  double min_increment = 0;  // smallest load-factor increment before giving up, default 1e-4
  bool line_search = true;
};

struct AnalysisSpec {
  enum class Type {
    kLinearStatic,     // small strain, K u = f; hyperelastic models use their initial moduli
    kNonlinearStatic,  // finite strain, total Lagrangian, Newton-Raphson; needs a hyperelastic model
  };
  enum class LinearSolver { kCholmod, kEigenLdlt };
  Type type = Type::kLinearStatic;
  LinearSolver linear_solver = LinearSolver::kCholmod;
  NonlinearOptionsSpec nonlinear;
};

struct OutputSpec {
  bool displacement = true;
  bool stress = true;
  bool von_mises = true;
  bool strain = true;  // small strain (linear) or Green-Lagrange strain (nonlinear)
  // Finite-strain fields, written by nonlinear analyses only.
  bool pk2_stress = true;      // second Piola-Kirchhoff stress
  bool almansi_strain = true;  // Euler-Almansi strain
  bool jacobian = true;        // J = det F
  // Sets whose total reaction goes into the summary; empty = every set that
  // carries a boundary condition.
  std::vector<std::string> reaction_sets;
};

struct SceneSpec {
  std::string name;
  std::string description;
  GeometrySpec geometry;
  MeshSpec mesh;
  MaterialSpec material;
  std::vector<BoundaryConditionSpec> boundary_conditions;
  AnalysisSpec analysis;
  OutputSpec outputs;
};

// Face set names a geometry defines (box: bottom top x_min x_max y_min y_max;
// cylinder: bottom top side).
std::vector<std::string> FaceSetNames(const GeometrySpec& geometry);

// The axis (0 = x, 1 = y, 2 = z) normal to a planar face set, or -1 when the
// set is curved (the cylinder's side) or unknown.
int PlaneNormalAxis(const GeometrySpec& geometry, const std::string& set);

// Checks everything that can be checked without meshing: a geometry and a
// material are given, sizes and moduli are in range, every boundary condition
// names an existing set, the body cannot move as a rigid body (some set is
// fixed or prescribed in every direction), the mesh would not be absurdly
// large. The returned Status names the field path, e.g.
// "boundary_conditions[1].set".
Status ValidateScene(const SceneSpec& scene);

}  // namespace pba
