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

enum class ElementType { kTet4 };

struct MeshSpec {
  ElementType element = ElementType::kTet4;
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

struct MaterialSpec {
  enum class Kind { kNone, kLinearElastic };
  std::string name;
  Kind kind = Kind::kNone;
  LinearElasticParams linear_elastic;
};

struct BoundaryConditionSpec {
  enum class Kind { kNone, kFixed, kDisplacement };
  std::string set;  // named face set of the geometry
  Kind kind = Kind::kNone;
  // kDisplacement: prescribed x, y, z components [mm]; nullopt = free.
  std::array<std::optional<double>, 3> displacement_mm;
};

struct AnalysisSpec {
  enum class Type { kLinearStatic };
  enum class LinearSolver { kCholmod, kEigenLdlt };
  Type type = Type::kLinearStatic;
  LinearSolver linear_solver = LinearSolver::kCholmod;
};

struct OutputSpec {
  bool displacement = true;
  bool stress = true;
  bool von_mises = true;
  bool strain = true;
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

// Checks everything that can be checked without meshing: a geometry and a
// material are given, sizes and moduli are in range, every boundary condition
// names an existing set, the body cannot move as a rigid body (some set is
// fixed or prescribed in every direction), the mesh would not be absurdly
// large. The returned Status names the field path, e.g.
// "boundary_conditions[1].set".
Status ValidateScene(const SceneSpec& scene);

}  // namespace pba
