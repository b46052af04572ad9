// The scene checks of time, rigid contacts, inclusions, buoyancy and line
// profiles; every failure names its field path.
#include "scene/validate_loading.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <set>
#include <utility>

#include "scene/problem.h"

namespace pba::scene_checks {
namespace {

bool NonNegativeFinite(double value) { return std::isfinite(value) && value >= 0; }

bool FiniteStrain(AnalysisSpec::Type type) {
  return type == AnalysisSpec::Type::kNonlinearStatic || type == AnalysisSpec::Type::kQuasiStatic;
}

// Each of three coordinates finite; names "<path>[c]".
Status CheckFiniteThree(const std::array<double, 3>& values, const std::string& path,
                        const char* unit) {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(values[c])) {
      return Status::InvalidArgument(
          path + "[" + std::to_string(c) + "]",
          std::string("must be a finite number") + unit + ", got " + ShortNumber(values[c]));
    }
  }
  return Status::Ok();
}

}  // namespace

Status ValidateTime(const AnalysisSpec& analysis) {
  const TimeSpec& t = analysis.time;
  const bool dynamic = analysis.type == AnalysisSpec::Type::kExplicitDynamic;
  if (analysis.type != AnalysisSpec::Type::kQuasiStatic && !dynamic) {
    const bool given = t.end_time_s != 0 || t.initial_step_s != 0 || t.min_step_s != 0 ||
                       t.max_step_s != 0 || !t.curve.empty();
    if (given) {
      return Status::InvalidArgument(
          "analysis.time", std::string("a time section or curve belongs to a QUASI_STATIC or "
                                       "EXPLICIT_DYNAMIC analysis; this one is ") +
                               AnalysisTypeName(analysis.type));
    }
    return Status::Ok();
  }
  if (!PositiveFinite(t.end_time_s)) {
    return Status::InvalidArgument("analysis.time.end_time_s",
                                   std::string(AnalysisTypeName(analysis.type)) +
                                       " needs a positive end time in s, got " +
                                       ShortNumber(t.end_time_s));
  }
  if (dynamic) {
    // The explicit step is the stable one times time_step_factor: no
    // adaptive steps to bound.
    const std::pair<const char*, double> unused[] = {{"initial_step_s", t.initial_step_s},
                                                     {"min_step_s", t.min_step_s},
                                                     {"max_step_s", t.max_step_s}};
    for (const auto& [name, value] : unused) {
      if (value == 0) continue;
      return Status::InvalidArgument(
          std::string("analysis.time.") + name,
          "not used by EXPLICIT_DYNAMIC: the step comes from the stability limit (scaled by "
          "analysis.explicit_dynamics.time_step_factor); leave it out");
    }
  }
  // Given steps (0 picks a default) must nest: min <= initial <= max <= end.
  const std::pair<const char*, double> steps[] = {{"min_step_s", t.min_step_s},
                                                  {"initial_step_s", t.initial_step_s},
                                                  {"max_step_s", t.max_step_s},
                                                  {"end_time_s", t.end_time_s}};
  for (int k = 0; k < 3; ++k) {
    if (!NonNegativeFinite(steps[k].second)) {
      return Status::InvalidArgument(
          std::string("analysis.time.") + steps[k].first,
          "must be a non-negative number of s (0 for the default), got " +
              ShortNumber(steps[k].second));
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (steps[k].second == 0) continue;
    const double fraction =
        k == 2 ? TimeOptions::kMaxStepFloorFraction : TimeOptions::kStepFloorFraction;
    if (steps[k].second < fraction * t.end_time_s) {
      return Status::InvalidArgument(
          std::string("analysis.time.") + steps[k].first,
          "must be at least " + ShortNumber(fraction) + " of end_time_s (" +
              ShortNumber(fraction * t.end_time_s) + " s), got " + ShortNumber(steps[k].second) +
              " s: smaller steps would take " + (k == 2 ? "over a million" : "over 1e9") +
              " increments (0 picks the default)");
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (steps[k].second == 0) continue;
    for (int later = k + 1; later < 4; ++later) {
      if (steps[later].second == 0) continue;
      if (steps[k].second > steps[later].second) {
        return Status::InvalidArgument(
            std::string("analysis.time.") + steps[k].first,
            "must not exceed " + std::string(steps[later].first) + " (" +
                ShortNumber(steps[later].second) + " s), got " + ShortNumber(steps[k].second) +
                " s; given steps need min_step_s <= initial_step_s <= max_step_s <= end_time_s");
      }
      break;  // the next given one; the chain covers the rest
    }
  }
  for (std::size_t i = 0; i < t.curve.size(); ++i) {
    const auto& [time_s, amplitude] = t.curve[i];
    const std::string path = "analysis.time.curve[" + std::to_string(i) + "]";
    if (!NonNegativeFinite(time_s)) {
      return Status::InvalidArgument(
          path + ".time_s", "must be a non-negative number of s, got " + ShortNumber(time_s));
    }
    if (i > 0 && !(time_s > t.curve[i - 1].first)) {
      return Status::InvalidArgument(
          path + ".time_s", "times must increase strictly: " + ShortNumber(time_s) + " s follows " +
                                ShortNumber(t.curve[i - 1].first) + " s");
    }
    if (!std::isfinite(amplitude)) {
      return Status::InvalidArgument(path + ".amplitude",
                                     "must be a finite number, got " + ShortNumber(amplitude));
    }
  }
  return Status::Ok();
}

Status ValidateBuoyancy(const GravitySpec& gravity) {
  if (!NonNegativeFinite(gravity.fluid_density_kg_per_m3)) {
    return Status::InvalidArgument(
        "gravity.fluid_density_kg_per_m3",
        "must be a non-negative number of kg/m^3 (0 for no fluid; cerebrospinal fluid: about "
        "1007), got " +
            ShortNumber(gravity.fluid_density_kg_per_m3));
  }
  if (gravity.fluid_level_mm && !std::isfinite(*gravity.fluid_level_mm)) {
    return Status::InvalidArgument(
        "gravity.fluid_level_mm",
        "must be a finite number of mm (or left out: the fluid covers everything), got " +
            ShortNumber(*gravity.fluid_level_mm));
  }
  return Status::Ok();
}

Status ValidateInclusions(const SceneSpec& scene) {
  const std::vector<std::string> sets = FaceSetNames(scene.geometry);
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    const InclusionSpec& inclusion = scene.inclusions[i];
    const std::string path = "inclusions[" + std::to_string(i) + "]";
    if (inclusion.name.empty()) {
      return Status::InvalidArgument(path + ".name",
                                     "an inclusion needs a name: it becomes a region's");
    }
    for (std::size_t before = 0; before < i; ++before) {
      if (scene.inclusions[before].name == inclusion.name) {
        return Status::InvalidArgument(path + ".name", "'" + inclusion.name +
                                                           "' is already the name of inclusions[" +
                                                           std::to_string(before) + "]");
      }
    }
    if (std::find(sets.begin(), sets.end(), inclusion.name) != sets.end() ||
        IsAtlasSetName(scene.geometry, inclusion.name)) {
      return Status::InvalidArgument(path + ".name",
                                     "'" + inclusion.name + "' is a face set name; choose another");
    }
    if (IsAtlasStructureName(scene.geometry, inclusion.name)) {
      return Status::InvalidArgument(
          path + ".name",
          "'" + inclusion.name + "' is an atlas structure's name; an inclusion is a new region");
    }
    PBA_RETURN_IF_ERROR(CheckFiniteThree(inclusion.centre_mm, path + ".centre_mm", " of mm"));
    if (!PositiveFinite(inclusion.radius_mm)) {
      return Status::InvalidArgument(path + ".radius_mm", "must be a positive number of mm, got " +
                                                              ShortNumber(inclusion.radius_mm));
    }
    PBA_RETURN_IF_ERROR(CheckExtraMaterial(inclusion.material, scene.material, path + ".material"));
    if (!std::isfinite(inclusion.growth_strain) || inclusion.growth_strain <= -1) {
      return Status::InvalidArgument(
          path + ".growth_strain",
          "must be a finite number above -1 (at -1 the inclusion would shrink to nothing), got " +
              ShortNumber(inclusion.growth_strain));
    }
    if (inclusion.growth_strain != 0 && !FiniteStrain(scene.analysis.type)) {
      return Status::InvalidArgument(
          path + ".growth_strain",
          std::string("growth is a finite-strain load: it needs a NONLINEAR_STATIC or "
                      "QUASI_STATIC analysis; this one is ") +
              AnalysisTypeName(scene.analysis.type));
    }
  }
  return Status::Ok();
}

Status ValidateContacts(const SceneSpec& scene) {
  const AnalysisSpec::Type type = scene.analysis.type;
  const bool impact = type == AnalysisSpec::Type::kExplicitDynamic;
  if (!scene.contacts.empty() && type == AnalysisSpec::Type::kDynamicRelaxation) {
    return Status::InvalidArgument("contacts[0]",
                                   "rigid contact is not supported by DYNAMIC_RELAXATION yet; "
                                   "NONLINEAR_STATIC solves the same static problem with it");
  }
  if (!scene.contacts.empty() && !FiniteStrain(type) && !impact) {
    return Status::InvalidArgument(
        "contacts", std::string("rigid contact needs a NONLINEAR_STATIC, QUASI_STATIC or "
                                "EXPLICIT_DYNAMIC analysis; this one is ") +
                        AnalysisTypeName(type));
  }
  for (std::size_t i = 0; i < scene.contacts.size(); ++i) {
    const ContactSpec& c = scene.contacts[i];
    const std::string path = "contacts[" + std::to_string(i) + "]";
    if (c.name.empty()) {
      return Status::InvalidArgument(path + ".name",
                                     "a contact needs a name: it labels its force in the summary");
    }
    for (std::size_t before = 0; before < i; ++before) {
      if (scene.contacts[before].name == c.name) {
        return Status::InvalidArgument(
            path + ".name",
            "'" + c.name + "' is already the name of contacts[" + std::to_string(before) + "]");
      }
    }
    PBA_RETURN_IF_ERROR(CheckFaceSet(scene.geometry, c.set, path + ".set"));
    if (c.shape == ContactSpec::Shape::kNone) {
      return Status::InvalidArgument(
          path + ".shape",
          "no shape given: FLAT_PUNCH, SPHERE, PLANE, CYLINDER_FLAT or CYLINDER_ROUNDED");
    }
    PBA_RETURN_IF_ERROR(CheckFiniteThree(c.position_mm, path + ".position_mm", " of mm"));
    PBA_RETURN_IF_ERROR(CheckFiniteThree(c.motion_mm, path + ".motion_mm", " of mm"));
    if (c.shape != ContactSpec::Shape::kPlane && !PositiveFinite(c.radius_mm)) {
      return Status::InvalidArgument(
          path + ".radius_mm",
          "a flat punch, a sphere or a cylinder needs a positive radius in mm, got " +
              ShortNumber(c.radius_mm));
    }
    PBA_RETURN_IF_ERROR(CheckFiniteThree(c.axis, path + ".axis", ""));
    if (c.axis[0] == 0 && c.axis[1] == 0 && c.axis[2] == 0) {
      return Status::InvalidArgument(
          path + ".axis", "must not be zero: it is the direction the body presses into the tissue");
    }
    if (!std::isfinite(c.friction) || c.friction < 0 || c.friction > 0.5) {
      return Status::InvalidArgument(
          path + ".friction",
          "the Coulomb coefficient must lie in [0, 0.5] (0: frictionless), got " +
              ShortNumber(c.friction));
    }
    if (impact && c.friction != 0) {
      return Status::InvalidArgument(
          path + ".friction",
          "friction is not modelled in EXPLICIT_DYNAMIC (an impactor is frictionless): leave it "
          "0, got " +
              ShortNumber(c.friction));
    }
    if (impact && c.start_touching) {
      return Status::InvalidArgument(
          path + ".start_touching",
          "not available in EXPLICIT_DYNAMIC: place the impactor with position_mm; it moves by "
          "motion_mm times a(t)");
    }
    if (!NonNegativeFinite(c.penalty_factor)) {
      return Status::InvalidArgument(path + ".penalty_factor",
                                     "must be a non-negative number (0 for the default 100), got " +
                                         ShortNumber(c.penalty_factor));
    }
    if (!NonNegativeFinite(c.penetration_tolerance_mm)) {
      return Status::InvalidArgument(
          path + ".penetration_tolerance_mm",
          "must be a non-negative number of mm (0 for 1 % of the element size), got " +
              ShortNumber(c.penetration_tolerance_mm));
    }
  }
  return Status::Ok();
}

// A profile names its file (profile_<name>.csv), so its name is a plain
// word; its line has two distinct finite ends and 2..1000 points (0: 50).
Status ValidateProfiles(const OutputSpec& outputs) {
  constexpr int kMaxPoints = 1000;
  std::set<std::string> names;
  for (std::size_t i = 0; i < outputs.profiles.size(); ++i) {
    const ProfileSpec& p = outputs.profiles[i];
    const std::string path = "outputs.profiles[" + std::to_string(i) + "]";
    if (p.name.empty()) return Status::InvalidArgument(path + ".name", "is empty");
    const bool plain = std::all_of(p.name.begin(), p.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!plain) {
      return Status::InvalidArgument(path + ".name",
                                     "'" + p.name +
                                         "' names the file profile_<name>.csv: use letters, "
                                         "digits, '_' and '-' only");
    }
    if (!names.insert(p.name).second) {
      return Status::InvalidArgument(path + ".name",
                                     "another profile is already named '" + p.name + "'");
    }
    for (const auto& [end, field] : {std::pair{&p.from_mm, ".from_mm"}, {&p.to_mm, ".to_mm"}}) {
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite((*end)[c])) {
          return Status::InvalidArgument(
              path + field, "xyz"[c] + std::string(" must be a finite number of mm, got ") +
                                ShortNumber((*end)[c]));
        }
      }
    }
    if (p.from_mm == p.to_mm) {
      return Status::InvalidArgument(path + ".to_mm",
                                     "is the same point as from_mm: a line needs two ends");
    }
    if (p.points != 0 && (p.points < 2 || p.points > kMaxPoints)) {
      return Status::InvalidArgument(path + ".points", "must be 2.." + std::to_string(kMaxPoints) +
                                                           " (or left out for 50), got " +
                                                           std::to_string(p.points));
    }
  }
  return Status::Ok();
}

}  // namespace pba::scene_checks
