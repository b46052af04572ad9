// Scene checks that need no mesh; every failure names its field path.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "atlas/atlas_build.h"
#include "atlas/colour_table.h"
#include "atlas/label_algebra.h"
#include "core/format.h"
#include "core/number_format.h"
#include "fem/element_kind.h"
#include "linear/petsc_runtime.h"
#include "material/factory.h"
#include "material/tissue_library.h"
#include "mesh/primitive_mesher.h"
#include "mesh/region_faces.h"
#include "pba/scene.h"
#include "scene/formulation.h"
#include "scene/materials.h"
#include "scene/problem.h"
#include "scene/validate_loading.h"

namespace pba {
namespace {}  // namespace

namespace scene_checks {
namespace {

// Whether the scene's structure names are the synthetic atlas's: its
// source is the synthetic atlas and no other names were given.
bool SyntheticNames(const AtlasSpec& a) {
  return a.known_structures.empty() && (a.source.empty() || a.source == "synthetic");
}

// A structure (or a group, "Thalamus") of the atlas the scene is built
// from, where its names are known before meshing.
Status CheckKnownStructure(const AtlasSpec& a, const std::string& structure,
                           const std::string& context, const std::string& path) {
  if (SyntheticNames(a)) {
    if (ColourTable::Builtin().FindByName(structure) != nullptr) return Status::Ok();
    return Status::InvalidArgument(
        path, context + "the synthetic atlas has no structure \"" + structure + "\"");
  }
  const std::vector<std::string>& known = a.known_structures;
  if (known.empty()) return Status::Ok();  // known once the atlas is built
  for (const std::string& name : known) {
    if (name == structure || InStructureGroup(name, structure)) return Status::Ok();
  }
  // The names that share the most leading characters, as a hint.
  std::vector<std::pair<int, std::string>> near;
  for (const std::string& name : known) {
    int common = 0;
    while (common < static_cast<int>(std::min(name.size(), structure.size())) &&
           std::tolower(static_cast<unsigned char>(name[common])) ==
               std::tolower(static_cast<unsigned char>(structure[common]))) {
      ++common;
    }
    near.emplace_back(-common, name);
  }
  std::sort(near.begin(), near.end());
  std::string hint;
  for (std::size_t i = 0; i < near.size() && i < 4 && near[i].first < 0; ++i) {
    hint += (hint.empty() ? "" : ", ") + ("\"" + near[i].second + "\"");
  }
  return Status::InvalidArgument(
      path, context + Format("the atlas (%zu structures) has no structure \"%s\"%s", known.size(),
                             structure.c_str(),
                             hint.empty() ? "" : ("; nearest names: " + hint).c_str()));
}

}  // namespace

bool PositiveFinite(double value) { return std::isfinite(value) && value > 0; }

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

const char* AnalysisTypeName(AnalysisSpec::Type type) {
  switch (type) {
    case AnalysisSpec::Type::kLinearStatic:
      return "LINEAR_STATIC";
    case AnalysisSpec::Type::kNonlinearStatic:
      return "NONLINEAR_STATIC";
    case AnalysisSpec::Type::kQuasiStatic:
      return "QUASI_STATIC";
    case AnalysisSpec::Type::kExplicitDynamic:
      return "EXPLICIT_DYNAMIC";
    case AnalysisSpec::Type::kDynamicRelaxation:
      return "DYNAMIC_RELAXATION";
  }
  return "unknown";
}

}  // namespace scene_checks

namespace {

using scene_checks::JoinNames;
using scene_checks::PositiveFinite;

// A mesh beyond this would need more memory than the machines PBA targets.
constexpr int64_t kMaxElements = 4'000'000;

Status ValidateGeometry(const GeometrySpec& geometry) {
  switch (geometry.kind) {
    case GeometrySpec::Kind::kNone:
      return Status::InvalidArgument(
          "geometry",
          "no shape given: set geometry.box, geometry.cylinder, geometry.spherical_shell, "
          "geometry.ellipsoid or geometry.atlas");
    case GeometrySpec::Kind::kAtlas: {
      const AtlasSpec& a = geometry.atlas;
      const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0; };
      if (!non_negative(a.voxel_size_mm)) {
        return Status::InvalidArgument(
            "geometry.atlas.voxel_size_mm",
            "must be a positive number of mm (or 0 for 1.5), got " + ShortNumber(a.voxel_size_mm));
      }
      if (!non_negative(a.facet_size_mm)) {
        return Status::InvalidArgument(
            "geometry.atlas.facet_size_mm",
            "must be a positive number of mm (or 0 for half the element size), got " +
                ShortNumber(a.facet_size_mm));
      }
      if (!non_negative(a.roi_radius_mm)) {
        return Status::InvalidArgument(
            "geometry.atlas.roi_radius_mm",
            "must be a positive number of mm (or 0 for none), got " + ShortNumber(a.roi_radius_mm));
      }
      if (a.roi_radius_mm > 0 && !PositiveFinite(a.roi_element_size_mm)) {
        return Status::InvalidArgument("geometry.atlas.roi_element_size_mm",
                                       "a region of interest needs a positive element size in "
                                       "mm, got " +
                                           ShortNumber(a.roi_element_size_mm));
      }
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(a.roi_centre_mm[c])) {
          return Status::InvalidArgument("geometry.atlas.roi_centre_mm[" + std::to_string(c) + "]",
                                         "must be finite");
        }
      }
      if (!a.label_steps_json.empty()) {
        if (a.source.empty() || a.source == "synthetic") {
          return Status::InvalidArgument(
              "geometry.atlas.labels",
              "label algebra works on a label volume source (geometry.atlas.source with its "
              "colour_table), not the synthetic atlas or a snapshot");
        }
        std::vector<LabelStep> steps;
        PBA_RETURN_IF_ERROR(
            ParseLabelSteps(a.label_steps_json, "geometry.atlas.labels", {}, &steps));
      }
      for (std::size_t i = 0; i < a.structures.size(); ++i) {
        const std::string field = "geometry.atlas.structures[" + std::to_string(i) + "]";
        if (a.structures[i].empty()) return Status::InvalidArgument(field, "is empty");
        if (!a.known_structures.empty()) {
          PBA_RETURN_IF_ERROR(scene_checks::CheckKnownStructure(a, a.structures[i], "", field));
        }
      }
      return Status::Ok();
    }
    case GeometrySpec::Kind::kEllipsoid:
      for (int c = 0; c < 3; ++c) {
        const double a = geometry.ellipsoid.semi_axes_mm[c];
        if (!PositiveFinite(a)) {
          return Status::InvalidArgument(
              "geometry.ellipsoid.semi_axes_mm[" + std::to_string(c) + "]",
              "every semi-axis must be a positive number of mm, got " + ShortNumber(a));
        }
      }
      return Status::Ok();
    case GeometrySpec::Kind::kSphericalShell: {
      const SphericalShellSpec& s = geometry.spherical_shell;
      if (!PositiveFinite(s.inner_radius_mm)) {
        return Status::InvalidArgument(
            "geometry.spherical_shell.inner_radius_mm",
            "must be a positive number of mm, got " + ShortNumber(s.inner_radius_mm));
      }
      if (!std::isfinite(s.outer_radius_mm) || s.outer_radius_mm <= s.inner_radius_mm) {
        return Status::InvalidArgument("geometry.spherical_shell.outer_radius_mm",
                                       "must be a number of mm larger than the inner radius (" +
                                           ShortNumber(s.inner_radius_mm) + "), got " +
                                           ShortNumber(s.outer_radius_mm));
      }
      return Status::Ok();
    }
    case GeometrySpec::Kind::kBox:
      for (double size : geometry.box.size_mm) {
        if (!PositiveFinite(size)) {
          return Status::InvalidArgument(
              "geometry.box.size_mm",
              "every edge length must be a positive number of mm, got " + ShortNumber(size));
        }
      }
      return Status::Ok();
    case GeometrySpec::Kind::kCylinder:
      if (!PositiveFinite(geometry.cylinder.radius_mm)) {
        return Status::InvalidArgument(
            "geometry.cylinder.radius_mm",
            "must be a positive number of mm, got " + ShortNumber(geometry.cylinder.radius_mm));
      }
      if (!PositiveFinite(geometry.cylinder.height_mm)) {
        return Status::InvalidArgument(
            "geometry.cylinder.height_mm",
            "must be a positive number of mm, got " + ShortNumber(geometry.cylinder.height_mm));
      }
      return Status::Ok();
  }
  return Status::Internal("unhandled geometry kind");
}

}  // namespace

namespace scene_checks {
namespace {

// An atlas structure the mesh will have: kept by geometry.atlas.structures
// (by name, or in a group such as "Thalamus") and, for the synthetic atlas,
// in the built-in colour table. `context` opens each message (e.g. "'surface:X': ").
Status CheckStructure(const GeometrySpec& geometry, const std::string& structure,
                      const std::string& context, const std::string& path) {
  const AtlasSpec& a = geometry.atlas;
  if (structure == kSurroundingTissue) {
    if (a.merge_rest) return Status::Ok();
    return Status::InvalidArgument(path, context + "\"" + kSurroundingTissue +
                                             "\" exists only with geometry.atlas.merge_rest: true");
  }
  const auto kept = [&](const std::string& asked) {  // by name, or as a group ("Thalamus")
    return asked == structure || InStructureGroup(structure, asked);
  };
  if (!a.structures.empty() && std::none_of(a.structures.begin(), a.structures.end(), kept)) {
    return Status::InvalidArgument(
        path, context + "\"" + structure +
                  "\" is not among geometry.atlas.structures, so the mesh will not have it");
  }
  return CheckKnownStructure(a, structure, context, path);
}

}  // namespace

// A face set an atlas mesh will have, named before it exists:
// "surface:<structure>" (the whole boundary of a structure) or
// "interface:<a>|<b>" (between two structures). Which structures touch is
// known only after meshing (model_builder.cc checks it there); here the
// form, and for the synthetic atlas the structure names, against the
// built-in colour table and the scene's own list of structures.
bool IsAtlasSetName(const GeometrySpec& geometry, const std::string& name) {
  return geometry.kind == GeometrySpec::Kind::kAtlas &&
         (name.rfind("surface:", 0) == 0 || name.rfind("interface:", 0) == 0);
}

Status CheckAtlasSetName(const GeometrySpec& geometry, const std::string& name,
                         const std::string& path) {
  const auto check_structure = [&](const std::string& structure) -> Status {
    if (structure.empty()) {
      return Status::InvalidArgument(path, "'" + name + "' names no structure");
    }
    return CheckStructure(geometry, structure, "'" + name + "': ", path);
  };
  const std::optional<RegionSetName> parsed = ParseRegionSetName(name);
  if (!parsed) {
    return Status::InvalidArgument(
        path, "'" + name + "' is not of the form interface:<structure>|<structure>");
  }
  if (!parsed->interface) return check_structure(parsed->first);
  const std::string& first = parsed->first;
  const std::string& second = parsed->second;
  if (first == second) {
    return Status::InvalidArgument(path, "'" + name + "' names the same structure twice");
  }
  PBA_RETURN_IF_ERROR(check_structure(first));
  return check_structure(second);
}

bool IsAtlasStructureName(const GeometrySpec& geometry, const std::string& name) {
  if (geometry.kind != GeometrySpec::Kind::kAtlas) return false;
  const AtlasSpec& a = geometry.atlas;
  if (name == kSurroundingTissue) return true;
  if (std::find(a.structures.begin(), a.structures.end(), name) != a.structures.end()) return true;
  if (!a.known_structures.empty()) {
    return std::find(a.known_structures.begin(), a.known_structures.end(), name) !=
           a.known_structures.end();
  }
  return SyntheticNames(a) && ColourTable::Builtin().FindByName(name) != nullptr;
}

Status CheckFaceSet(const GeometrySpec& geometry, const std::string& set, const std::string& path) {
  if (IsAtlasSetName(geometry, set)) return CheckAtlasSetName(geometry, set, path);
  const std::vector<std::string> sets = FaceSetNames(geometry);
  if (std::find(sets.begin(), sets.end(), set) == sets.end()) {
    return Status::InvalidArgument(
        path, "unknown face set '" + set + "'; this geometry has: " + JoinNames(sets));
  }
  return Status::Ok();
}

Status CheckExtraMaterial(const MaterialSpec& material, const MaterialSpec& scene_material,
                          const std::string& path) {
  PBA_RETURN_IF_ERROR(ValidateMaterialSpec(material, path));
  const double density = material.density_kg_per_m3;
  if (!std::isfinite(density) || density < 0) {
    return Status::InvalidArgument(
        path + ".density_kg_per_m3",
        "must be a non-negative number of kg/m^3, got " + ShortNumber(density));
  }
  // One family per model: the analysis that suits the scene's material must
  // suit every other material as well.
  if (material.hyperelastic() != scene_material.hyperelastic()) {
    return Status::InvalidArgument(
        path, std::string("must be of the scene material's family: the scene's is ") +
                  (scene_material.hyperelastic() ? "hyperelastic" : "linear") + ", this one is " +
                  (material.hyperelastic() ? "hyperelastic" : "linear"));
  }
  return Status::Ok();
}

}  // namespace scene_checks

namespace {

using scene_checks::CheckAtlasSetName;
using scene_checks::CheckFaceSet;
using scene_checks::IsAtlasSetName;

// Names unique and new, parents among the geometry's own sets, a ball that
// can hold a face. Whether it does is known only after meshing (BuildModel).
Status ValidatePatches(const GeometrySpec& geometry) {
  GeometrySpec bare = geometry;
  bare.patches.clear();
  std::vector<std::string> names = FaceSetNames(bare);
  const std::vector<std::string> own = names;
  for (std::size_t i = 0; i < geometry.patches.size(); ++i) {
    const PatchSpec& p = geometry.patches[i];
    const std::string path = "geometry.patches[" + std::to_string(i) + "]";
    if (p.name.empty()) return Status::InvalidArgument(path + ".name", "a patch needs a name");
    if (std::find(names.begin(), names.end(), p.name) != names.end()) {
      return Status::InvalidArgument(path + ".name",
                                     "'" + p.name + "' is already a face set of this geometry");
    }
    if (IsAtlasSetName(geometry, p.set)) {
      PBA_RETURN_IF_ERROR(CheckAtlasSetName(geometry, p.set, path + ".set"));
    } else if (std::find(own.begin(), own.end(), p.set) == own.end()) {
      return Status::InvalidArgument(
          path + ".set",
          "unknown face set '" + p.set + "'; a patch is cut from one of: " + JoinNames(own));
    }
    if (!p.ball && !p.half_space) {
      return Status::InvalidArgument(
          path,
          "a patch needs a ball (centre_mm, radius_mm), a half-space (plane_point_mm, "
          "plane_normal), or both");
    }
    if (p.ball) {
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(p.centre_mm[c])) {
          return Status::InvalidArgument(
              path + ".centre_mm[" + std::to_string(c) + "]",
              "must be a finite number of mm, got " + ShortNumber(p.centre_mm[c]));
        }
      }
      if (!PositiveFinite(p.radius_mm)) {
        return Status::InvalidArgument(
            path + ".radius_mm",
            "must be a positive number of mm, got " + ShortNumber(p.radius_mm));
      }
    }
    if (p.half_space) {
      double length = 0;
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(p.plane_point_mm[c])) {
          return Status::InvalidArgument(
              path + ".plane_point_mm[" + std::to_string(c) + "]",
              "must be a finite number of mm, got " + ShortNumber(p.plane_point_mm[c]));
        }
        if (!std::isfinite(p.plane_normal[c])) {
          return Status::InvalidArgument(path + ".plane_normal[" + std::to_string(c) + "]",
                                         "must be finite, got " + ShortNumber(p.plane_normal[c]));
        }
        length += p.plane_normal[c] * p.plane_normal[c];
      }
      if (!(length > 0)) {
        return Status::InvalidArgument(path + ".plane_normal",
                                       "must not be zero: it points to the side kept");
      }
    }
    names.push_back(p.name);
  }
  return Status::Ok();
}

// material_library and region_materials: tissue per atlas structure.
Status ValidateRegionMaterials(const SceneSpec& scene) {
  const bool atlas = scene.geometry.kind == GeometrySpec::Kind::kAtlas;
  if (!scene.material_library.empty()) {
    if (!atlas) {
      return Status::InvalidArgument("material_library",
                                     "assigns tissue to atlas structures: it needs geometry.atlas");
    }
    PBA_RETURN_IF_ERROR(CheckLibraryName(scene.material_library));
  }
  if (scene.region_materials.empty()) return Status::Ok();
  if (!atlas) {
    return Status::InvalidArgument(
        "region_materials", "materials per structure need an atlas geometry (geometry.atlas)");
  }
  std::vector<std::pair<std::string, std::size_t>> seen;  // structure, its entry
  for (std::size_t i = 0; i < scene.region_materials.size(); ++i) {
    const RegionMaterialSpec& r = scene.region_materials[i];
    const std::string path = "region_materials[" + std::to_string(i) + "]";
    if (r.structures.empty()) {
      return Status::InvalidArgument(
          path + ".structures", "lists no structure: name the structures this material is for");
    }
    for (std::size_t j = 0; j < r.structures.size(); ++j) {
      const std::string& name = r.structures[j];
      const std::string field = path + ".structures[" + std::to_string(j) + "]";
      if (name.empty()) return Status::InvalidArgument(field, "is empty");
      const auto before = std::find_if(seen.begin(), seen.end(),
                                       [&](const auto& entry) { return entry.first == name; });
      if (before != seen.end()) {
        return Status::InvalidArgument(field, "'" + name + "' already has a material (in " +
                                                  "region_materials[" +
                                                  std::to_string(before->second) + "])");
      }
      PBA_RETURN_IF_ERROR(scene_checks::CheckStructure(scene.geometry, name, "", field));
      seen.emplace_back(name, i);
    }
    PBA_RETURN_IF_ERROR(
        scene_checks::CheckExtraMaterial(r.material, scene.material, path + ".material"));
  }
  return Status::Ok();
}

// outputs.structure_displacements: atlas structures, inclusions or "*".
Status ValidateStructureDisplacements(const SceneSpec& scene) {
  const bool atlas = scene.geometry.kind == GeometrySpec::Kind::kAtlas;
  for (std::size_t i = 0; i < scene.outputs.structure_displacements.size(); ++i) {
    const std::string& name = scene.outputs.structure_displacements[i];
    const std::string path = "outputs.structure_displacements[" + std::to_string(i) + "]";
    if (name.empty()) return Status::InvalidArgument(path, "is empty");
    const bool inclusion =
        std::any_of(scene.inclusions.begin(), scene.inclusions.end(),
                    [&](const InclusionSpec& inclusion) { return inclusion.name == name; });
    if (inclusion || (name == "*" && (atlas || !scene.inclusions.empty()))) continue;
    if (!atlas) {
      return Status::InvalidArgument(
          path, "'" + name +
                    "' is not an inclusion, and only an atlas geometry has structures to report");
    }
    PBA_RETURN_IF_ERROR(scene_checks::CheckStructure(scene.geometry, name, "", path));
  }
  return Status::Ok();
}

Status ValidateAnalysis(const AnalysisSpec& analysis, const MaterialSpec& material) {
  // Small-strain orthotropy has no finite-strain counterpart here (that would
  // be an anisotropic hyperelastic model), so only the linear solve takes it.
  if (material.kind == MaterialSpec::Kind::kOrthotropicElastic &&
      analysis.type != AnalysisSpec::Type::kLinearStatic) {
    return Status::InvalidArgument(
        "material",
        "orthotropic_elastic is small-strain linear elasticity, for LINEAR_STATIC only; a "
        "nonlinear static analysis needs a hyperelastic material (neo_hookean, mooney_rivlin, "
        "polynomial or ogden)");
  }
  PBA_RETURN_IF_ERROR(scene_checks::ValidateTime(analysis));
  PBA_RETURN_IF_ERROR(
      ValidateLinearSolverSettings(LinearSolverSettingsFromSpec(analysis.linear_solver_options)));
  if (analysis.type == AnalysisSpec::Type::kLinearStatic) return Status::Ok();
  // Every finite-strain analysis (Newton or explicit) on a hyperelastic model.
  if (!material.hyperelastic()) {
    return Status::InvalidArgument("material",
                                   std::string(scene_checks::AnalysisTypeName(analysis.type)) +
                                       " needs a hyperelastic material (neo_hookean, "
                                       "mooney_rivlin, polynomial or ogden); linear_elastic is for "
                                       "LINEAR_STATIC");
  }
  // The Newton controls as they will run, defaults applied (0 selects one).
  PBA_RETURN_IF_ERROR(NonlinearOptions::FromSpec(analysis.nonlinear).Validate());
  return Status::Ok();
}

// Relaxation through time and growth keep a history per element, which
// only the one-point 4-node tetrahedra (TET4, TET4_ANP) keep in the
// implicit analyses: a QUASI_STATIC scene with a relaxing material, or any
// scene with a growing inclusion, on another element is refused here, not
// minutes into the solve.
Status ValidateHistoryElements(const SceneSpec& scene) {
  const AnalysisSpec::Type type = scene.analysis.type;
  const ElementType element = ResolveElement(scene.mesh.element, type);
  if (KindOf(element).keeps_history || type == AnalysisSpec::Type::kExplicitDynamic ||
      type == AnalysisSpec::Type::kDynamicRelaxation) {
    return Status::Ok();
  }
  const auto refuse = [&](const std::string& what, const std::string& field) {
    return Status::InvalidArgument(
        field, what +
                   " is modelled on 4-node tetrahedra (TET4_ANP, TET4), whose one integration "
                   "point keeps the history; this scene's mesh.element is " +
                   ElementName(element));
  };
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    if (scene.inclusions[i].growth_strain != 0) {
      return refuse("growth", "inclusions[" + std::to_string(i) + "].growth_strain");
    }
  }
  if (type != AnalysisSpec::Type::kQuasiStatic) return Status::Ok();
  // A material relaxes in this analysis when a term survives the window
  // the analysis resolves (formulation AUTO may have folded or dropped some).
  const auto relaxes = [&](const MaterialSpec& m) {
    double scale = 1;
    return !ReduceRelaxation(RelaxationOf(m.viscoelastic), scene.analysis.relaxed_below_s,
                             scene.analysis.frozen_above_s, &scale)
                .g.empty();
  };
  if (relaxes(scene.material)) return refuse("viscoelastic relaxation", "material.viscoelastic");
  for (std::size_t i = 0; i < scene.region_materials.size(); ++i) {
    if (relaxes(scene.region_materials[i].material)) {
      return refuse("viscoelastic relaxation",
                    "region_materials[" + std::to_string(i) + "].material.viscoelastic");
    }
  }
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    if (relaxes(scene.inclusions[i].material)) {
      return refuse("viscoelastic relaxation",
                    "inclusions[" + std::to_string(i) + "].material.viscoelastic");
    }
  }
  if (!scene.material_library.empty()) {
    // Any structure of the built-in table the library gives a relaxing
    // material (whichever of them the atlas keeps).
    for (const ColourEntry& entry : ColourTable::Builtin().entries()) {
      MaterialSpec m;
      if (LibraryMaterial(scene.material_library, entry.name, &m, nullptr).ok() && relaxes(m)) {
        return refuse("viscoelastic relaxation (of the tissue library's " + entry.name + ")",
                      "material_library");
      }
    }
  }
  return Status::Ok();
}

}  // namespace

std::vector<std::string> FaceSetNames(const GeometrySpec& geometry) {
  std::vector<std::string> names;
  switch (geometry.kind) {
    case GeometrySpec::Kind::kBox:
      names = {"bottom", "top", "x_min", "x_max", "y_min", "y_max"};
      break;
    case GeometrySpec::Kind::kCylinder:
      names = {"bottom", "top", "side"};
      if (geometry.cylinder.half) names.push_back("cut");
      break;
    case GeometrySpec::Kind::kSphericalShell:
      names = {"inner", "outer", "x0", "y0", "z0"};
      break;
    case GeometrySpec::Kind::kEllipsoid:
    case GeometrySpec::Kind::kAtlas:
      names = {"surface"};
      break;
    case GeometrySpec::Kind::kNone:
      return {};
  }
  for (const PatchSpec& p : geometry.patches) names.push_back(p.name);
  return names;
}

int PlaneNormalAxis(const GeometrySpec& geometry, const std::string& set) {
  for (const PatchSpec& p : geometry.patches) {
    if (p.name == set) return p.set == set ? -1 : PlaneNormalAxis(geometry, p.set);
  }
  if (geometry.kind == GeometrySpec::Kind::kEllipsoid ||
      geometry.kind == GeometrySpec::Kind::kAtlas) {
    return -1;
  }
  if (geometry.kind == GeometrySpec::Kind::kSphericalShell) {
    if (set == "x0") return 0;
    if (set == "y0") return 1;
    if (set == "z0") return 2;
    return -1;
  }
  if (set == "bottom" || set == "top") return geometry.kind == GeometrySpec::Kind::kNone ? -1 : 2;
  if (geometry.kind == GeometrySpec::Kind::kCylinder && geometry.cylinder.half && set == "cut") {
    return 1;
  }
  if (geometry.kind != GeometrySpec::Kind::kBox) return -1;
  if (set == "x_min" || set == "x_max") return 0;
  if (set == "y_min" || set == "y_max") return 1;
  return -1;
}

namespace {

// mesh.adapt: bounds in range, on elements the refinement cuts and an
// analysis that estimates its error.
Status ValidateAdapt(const SceneSpec& scene) {
  const AdaptSpec& adapt = scene.mesh.adapt;
  if (!adapt.enabled()) {
    if (adapt.max_elements != 0 || adapt.max_cycles != 0 || adapt.refine_fraction != 0) {
      return Status::InvalidArgument("mesh.adapt.target_error_percent",
                                     "is needed with the other mesh.adapt fields: the estimated "
                                     "error to refine down to, in percent");
    }
    return Status::Ok();
  }
  if (!(adapt.target_error_percent > 0 && adapt.target_error_percent < 100)) {
    return Status::InvalidArgument(
        "mesh.adapt.target_error_percent",
        "must be a percentage between 0 and 100 (the estimated relative error in the energy "
        "norm to refine down to), got " +
            ShortNumber(adapt.target_error_percent));
  }
  if (adapt.max_elements < 0 || adapt.max_elements > kMaxElements) {
    return Status::InvalidArgument(
        "mesh.adapt.max_elements",
        Format("must be between 1 and %lld (or left out for %lld), got %lld",
               static_cast<long long>(kMaxElements),
               static_cast<long long>(kDefaultAdaptMaxElements),
               static_cast<long long>(adapt.max_elements)));
  }
  if (adapt.max_cycles < 0 || adapt.max_cycles > 20) {
    return Status::InvalidArgument(
        "mesh.adapt.max_cycles",
        Format("must be between 1 and 20 solves (or left out for %d), got %d", kDefaultAdaptCycles,
               adapt.max_cycles));
  }
  if (!(adapt.refine_fraction >= 0 && adapt.refine_fraction <= 1)) {
    return Status::InvalidArgument(
        "mesh.adapt.refine_fraction",
        "must be in (0, 1]: the share of the squared estimated error whose elements are "
        "refined each cycle (or left out for " +
            ShortNumber(kDefaultAdaptFraction) + "), got " + ShortNumber(adapt.refine_fraction));
  }
  if (IsHexahedral(scene.mesh.element)) {
    return Status::InvalidArgument("mesh.adapt",
                                   "refines tetrahedra (by bisection); a HEX8 mesh is a "
                                   "structured grid: choose a tetrahedral element, or compare "
                                   "element sizes with `pba study convergence`");
  }
  const AnalysisSpec::Type type = scene.analysis.type;
  if (type == AnalysisSpec::Type::kExplicitDynamic ||
      type == AnalysisSpec::Type::kDynamicRelaxation) {
    return Status::InvalidArgument("mesh.adapt",
                                   "needs an error estimate, which LINEAR_STATIC, "
                                   "NONLINEAR_STATIC and QUASI_STATIC give; the explicit "
                                   "engine's analyses (EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION) "
                                   "give none");
  }
  return Status::Ok();
}

// mesh: the element size, an element kind the geometry and the analysis
// can take, and a mesh that fits in memory.
Status ValidateMesh(const SceneSpec& scene) {
  if (!std::isfinite(scene.mesh.element_size_mm) || scene.mesh.element_size_mm < 0) {
    return Status::InvalidArgument(
        "mesh.element_size_mm",
        "must be a positive number of mm (or left out for the default), got " +
            ShortNumber(scene.mesh.element_size_mm));
  }
  if (scene.geometry.kind == GeometrySpec::Kind::kAtlas && IsHexahedral(scene.mesh.element)) {
    return Status::InvalidArgument("mesh.element",
                                   "an atlas is meshed with tetrahedra: choose TET4, TET4_ANP, "
                                   "TET10 or TET10_MD");
  }
  const int64_t elements = EstimateElementCount(scene.geometry, scene.mesh);
  if (elements > kMaxElements) {
    return Status::InvalidArgument(
        "mesh.element_size_mm", "this element size would give about " + std::to_string(elements) +
                                    " elements, more than the limit of " +
                                    std::to_string(kMaxElements) + "; choose a larger size");
  }

  PBA_RETURN_IF_ERROR(ValidateAdapt(scene));

  // The finite-strain elements serve both finite-strain analyses.
  const bool finite_strain = scene.analysis.type != AnalysisSpec::Type::kLinearStatic;
  const ElementType element = scene.mesh.element;
  if (element != ElementType::kDefault && !finite_strain && !KindOf(element).linear_static) {
    return Status::InvalidArgument(
        "mesh.element", element == ElementType::kTet4Anp
                            ? "TET4_ANP (average nodal pressure) is implemented for "
                              "NONLINEAR_STATIC; a linear analysis uses TET4"
                            : std::string(ElementName(element)) +
                                  " (10-node tetrahedron with mean dilatation) is implemented "
                                  "for NONLINEAR_STATIC; a linear analysis uses TET10 or HEX8");
  }
  return Status::Ok();
}

// The directions x, y, z a boundary condition holds the body in.
using HeldDirections = std::array<bool, 3>;

// boundary_conditions[i] (`path`): a face set of this geometry and a
// condition with finite values; marks in `held` the directions it holds.
Status CheckBoundaryCondition(const SceneSpec& scene, const BoundaryConditionSpec& bc,
                              const std::string& path, const std::vector<std::string>& sets,
                              HeldDirections* held) {
  if (IsAtlasSetName(scene.geometry, bc.set)) {
    PBA_RETURN_IF_ERROR(CheckAtlasSetName(scene.geometry, bc.set, path + ".set"));
  } else if (std::find(sets.begin(), sets.end(), bc.set) == sets.end()) {
    return Status::InvalidArgument(
        path + ".set", "unknown face set '" + bc.set + "'; this geometry has: " + JoinNames(sets));
  }
  switch (bc.kind) {
    case BoundaryConditionSpec::Kind::kNone:
      return Status::InvalidArgument(path,
                                     "no condition given: set fixed, displacement, symmetry, "
                                     "pressure, traction or velocity");
    case BoundaryConditionSpec::Kind::kPressure:
      if (!std::isfinite(bc.pressure_pa)) {
        return Status::InvalidArgument(
            path + ".pressure.pressure_pa",
            "must be a finite number of Pa, got " + ShortNumber(bc.pressure_pa));
      }
      break;
    case BoundaryConditionSpec::Kind::kTraction:
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(bc.traction_pa[c])) {
          return Status::InvalidArgument(
              path + ".traction.traction_pa[" + std::to_string(c) + "]",
              "must be a finite number of Pa, got " + ShortNumber(bc.traction_pa[c]));
        }
      }
      break;
    case BoundaryConditionSpec::Kind::kFixed:
      (*held)[0] = (*held)[1] = (*held)[2] = true;
      break;
    case BoundaryConditionSpec::Kind::kSymmetry: {
      const int axis = PlaneNormalAxis(scene.geometry, bc.set);
      if (axis < 0) {
        return Status::InvalidArgument(
            path + ".symmetry", "a symmetry condition needs a planar face set; '" + bc.set +
                                    "' is curved (hold it with displacement components instead)");
      }
      (*held)[axis] = true;
      break;
    }
    case BoundaryConditionSpec::Kind::kVelocity:
      PBA_RETURN_IF_ERROR(scene_checks::CheckVelocity(bc, scene.analysis.type, path));
      break;
    case BoundaryConditionSpec::Kind::kDisplacement: {
      bool any = false;
      static const char* kNames[3] = {"x_mm", "y_mm", "z_mm"};
      for (int c = 0; c < 3; ++c) {
        if (!bc.displacement_mm[c]) continue;
        if (!std::isfinite(*bc.displacement_mm[c])) {
          return Status::InvalidArgument(path + ".displacement." + kNames[c],
                                         "must be a finite number of mm");
        }
        any = (*held)[c] = true;
      }
      if (!any) {
        return Status::InvalidArgument(path + ".displacement",
                                       "no component given: set at least one of x_mm, y_mm, z_mm");
      }
      break;
    }
  }
  return Status::Ok();
}

// boundary_conditions: at least one (outside dynamics), each checked in turn;
// `held` gets the directions they hold together.
Status ValidateBoundaryConditions(const SceneSpec& scene, HeldDirections* held) {
  // In dynamics a free body is fine: its inertia holds it (an impactor may
  // strike a body held by nothing).
  const bool dynamic = scene.analysis.type == AnalysisSpec::Type::kExplicitDynamic;
  if (scene.boundary_conditions.empty() && !dynamic) {
    return Status::InvalidArgument("boundary_conditions",
                                   "no boundary conditions: the body is free to move; hold at "
                                   "least one face (for example {set: bottom, fixed: {}})");
  }
  const std::vector<std::string> sets = FaceSetNames(scene.geometry);
  for (std::size_t i = 0; i < scene.boundary_conditions.size(); ++i) {
    const std::string path = "boundary_conditions[" + std::to_string(i) + "]";
    PBA_RETURN_IF_ERROR(
        CheckBoundaryCondition(scene, scene.boundary_conditions[i], path, sets, held));
  }
  return Status::Ok();
}

// material.density_kg_per_m3 and gravity: a density gravity can act on.
Status ValidateDensityAndGravity(const SceneSpec& scene) {
  const double density = scene.material.density_kg_per_m3;
  if (!std::isfinite(density) || density < 0) {
    return Status::InvalidArgument(
        "material.density_kg_per_m3",
        "must be a non-negative number of kg/m^3, got " + ShortNumber(density));
  }
  if (scene.gravity.enabled) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(scene.gravity.acceleration_m_per_s2[c])) {
        return Status::InvalidArgument("gravity.acceleration_m_per_s2[" + std::to_string(c) + "]",
                                       "must be a finite number of m/s^2, got " +
                                           ShortNumber(scene.gravity.acceleration_m_per_s2[c]));
      }
    }
    if (density == 0) {
      return Status::InvalidArgument(
          "material.density_kg_per_m3",
          "gravity acts on the material's density, which is not given (brain tissue: about "
          "1040 kg/m^3)");
    }
  }
  return Status::Ok();
}

// Outside explicit dynamics the boundary conditions together must hold the
// body in every direction: a free direction leaves a static solve without a
// unique answer.
Status CheckBodyHeld(const SceneSpec& scene, const HeldDirections& held) {
  const bool dynamic = scene.analysis.type == AnalysisSpec::Type::kExplicitDynamic;
  std::string free;
  for (int c = 0; c < 3; ++c) {
    if (!held[c]) free += std::string(free.empty() ? "" : ", ") + "xyz"[c];
  }
  if (!free.empty() && !dynamic) {
    return Status::InvalidArgument("boundary_conditions",
                                   "no condition holds the body in direction " + free +
                                       ", so it could slide away; fix or prescribe that component "
                                       "on some face");
  }
  return Status::Ok();
}

// outputs.reaction_sets: face sets of this geometry.
Status ValidateReactionSets(const SceneSpec& scene) {
  const std::vector<std::string> sets = FaceSetNames(scene.geometry);
  for (std::size_t i = 0; i < scene.outputs.reaction_sets.size(); ++i) {
    const std::string& name = scene.outputs.reaction_sets[i];
    const std::string path = "outputs.reaction_sets[" + std::to_string(i) + "]";
    if (IsAtlasSetName(scene.geometry, name)) {
      PBA_RETURN_IF_ERROR(CheckAtlasSetName(scene.geometry, name, path));
    } else if (std::find(sets.begin(), sets.end(), name) == sets.end()) {
      return Status::InvalidArgument(
          path, "unknown face set '" + name + "'; this geometry has: " + JoinNames(sets));
    }
  }
  return Status::Ok();
}

}  // namespace

// Section by section, in an order that keeps the first error a scene reports
// stable (tests and users see that one).
Status ValidateScene(const SceneSpec& scene) {
  PBA_RETURN_IF_ERROR(ValidateGeometry(scene.geometry));
  PBA_RETURN_IF_ERROR(ValidatePatches(scene.geometry));
  PBA_RETURN_IF_ERROR(ValidateMesh(scene));
  PBA_RETURN_IF_ERROR(ValidateMaterialSpec(scene.material, "material"));
  PBA_RETURN_IF_ERROR(ValidateAnalysis(scene.analysis, scene.material));
  PBA_RETURN_IF_ERROR(ValidateRegionMaterials(scene));
  PBA_RETURN_IF_ERROR(scene_checks::ValidateInclusions(scene));
  PBA_RETURN_IF_ERROR(ValidateHistoryElements(scene));
  PBA_RETURN_IF_ERROR(scene_checks::ValidateExplicit(scene));
  PBA_RETURN_IF_ERROR(AutoFormulationOptions::FromScene(scene).Validate());
  HeldDirections held = {false, false, false};
  PBA_RETURN_IF_ERROR(ValidateBoundaryConditions(scene, &held));
  PBA_RETURN_IF_ERROR(ValidateDensityAndGravity(scene));
  PBA_RETURN_IF_ERROR(scene_checks::ValidateBuoyancy(scene.gravity));
  PBA_RETURN_IF_ERROR(CheckBodyHeld(scene, held));
  PBA_RETURN_IF_ERROR(scene_checks::ValidateContacts(scene));
  PBA_RETURN_IF_ERROR(ValidateReactionSets(scene));
  PBA_RETURN_IF_ERROR(scene_checks::ValidateProfiles(scene.outputs));
  PBA_RETURN_IF_ERROR(ValidateStructureDisplacements(scene));
  return ValidateSceneOnRanks(scene, CurrentRanks().size);
}

Status ValidateSceneOnRanks(const SceneSpec& scene, int ranks) {
  if (ranks < 1)
    return Status::InvalidArgument("ranks", Format("must be at least 1, got %d", ranks));
  if (ranks == 1) return Status::Ok();
  const AnalysisSpec& analysis = scene.analysis;
  if (analysis.type == AnalysisSpec::Type::kExplicitDynamic ||
      analysis.type == AnalysisSpec::Type::kDynamicRelaxation) {
    return Status::InvalidArgument(
        "analysis.type",
        Format("%s has no linear solve to share between %d MPI ranks (the ranks share the "
               "implicit analyses' linear solves); run it as one process",
               analysis.type == AnalysisSpec::Type::kExplicitDynamic ? "EXPLICIT_DYNAMIC"
                                                                     : "DYNAMIC_RELAXATION",
               ranks));
  }
  switch (analysis.linear_solver) {
    case AnalysisSpec::LinearSolver::kAuto:
    case AnalysisSpec::LinearSolver::kAmg:
    case AnalysisSpec::LinearSolver::kMumps:
      return Status::Ok();
    case AnalysisSpec::LinearSolver::kCholmod:
    case AnalysisSpec::LinearSolver::kEigenLdlt:
    case AnalysisSpec::LinearSolver::kPcg:
      break;
  }
  return Status::InvalidArgument(
      "analysis.linear_solver",
      Format("solves in one process; on %d MPI ranks use AUTO, AMG or MUMPS, which share the "
             "solve between the ranks",
             ranks));
}

}  // namespace pba
