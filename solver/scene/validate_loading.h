// Scene checks of the time of a QUASI_STATIC analysis, the rigid contacts,
// the inclusions, the buoyancy of gravity and the line profiles
// (validate_loading.cc), of the explicit analyses (validate_explicit.cc),
// and the helpers they share with the rest of
// ValidateScene (validate.cc). Internal to the scene checks; every failure
// names its field path.
#pragma once

#include <string>
#include <vector>

#include "core/number_format.h"
#include "pba/scene.h"
#include "pba/status.h"

namespace pba::scene_checks {

bool PositiveFinite(double value);
// "a, b, c"
std::string JoinNames(const std::vector<std::string>& names);
// "LINEAR_STATIC", "NONLINEAR_STATIC", "QUASI_STATIC", "EXPLICIT_DYNAMIC" or
// "DYNAMIC_RELAXATION", as a scene names it.
const char* AnalysisTypeName(AnalysisSpec::Type type);

// True for "surface:<structure>" and "interface:<a>|<b>" on an atlas.
bool IsAtlasSetName(const GeometrySpec& geometry, const std::string& name);
// The form and the structures of such a name (see validate.cc).
Status CheckAtlasSetName(const GeometrySpec& geometry, const std::string& name,
                         const std::string& path);

// True when `name` is a structure of the atlas geometry: one it keeps, the
// merged rest, or (synthetic atlas) one of its colour table.
bool IsAtlasStructureName(const GeometrySpec& geometry, const std::string& name);

// A face set the scene may name at `path`: one of FaceSetNames(geometry) or
// an atlas's structure set.
Status CheckFaceSet(const GeometrySpec& geometry, const std::string& set, const std::string& path);

// `material`, an extra material at `path` (a region's or an inclusion's),
// valid and of the scene material's family: hyperelastic or linear alike.
Status CheckExtraMaterial(const MaterialSpec& material, const MaterialSpec& scene_material,
                          const std::string& path);

// analysis.time: required and checked for QUASI_STATIC, end and curve only
// for EXPLICIT_DYNAMIC, refused elsewhere.
Status ValidateTime(const AnalysisSpec& analysis);
// gravity.fluid_density_kg_per_m3 and gravity.fluid_level_mm.
Status ValidateBuoyancy(const GravitySpec& gravity);
// inclusions[i]: names, balls, materials, growth.
Status ValidateInclusions(const SceneSpec& scene);
// contacts[i]: names, sets, shapes, rigid-body geometry, friction, penalty.
Status ValidateContacts(const SceneSpec& scene);
// outputs.profiles[i]: names (unique, fit for a file name), ends, points.
Status ValidateProfiles(const OutputSpec& outputs);

// The explicit analyses (validate_explicit.cc): analysis.explicit_dynamics
// (refused in an analysis that does not use a field), the elements and
// materials EXPLICIT_DYNAMIC and DYNAMIC_RELAXATION take, formulation, and
// outputs.sensors with their sampling and filter (EXPLICIT_DYNAMIC only).
Status ValidateExplicit(const SceneSpec& scene);
// boundary_conditions[i].velocity at `path` (the condition's): in an
// EXPLICIT_DYNAMIC analysis only, at least one component, each finite.
Status CheckVelocity(const BoundaryConditionSpec& bc, AnalysisSpec::Type type,
                     const std::string& path);

}  // namespace pba::scene_checks
