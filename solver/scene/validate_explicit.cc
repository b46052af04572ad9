// The scene checks of the explicit analyses (EXPLICIT_DYNAMIC and
// DYNAMIC_RELAXATION): their controls, elements, materials, velocity
// conditions and sensors; every failure names its field path.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <set>
#include <string>

#include "atlas/colour_table.h"
#include "fem/element_kind.h"
#include "material/tissue_library.h"
#include "scene/problem.h"
#include "scene/validate_loading.h"

namespace pba::scene_checks {
namespace {

using Type = AnalysisSpec::Type;

constexpr double kDefaultSensorIntervalS = SensorOptions::kIntervalS;

bool NonNegativeFinite(double value) { return std::isfinite(value) && value >= 0; }

bool Explicit(Type type) {
  return type == Type::kExplicitDynamic || type == Type::kDynamicRelaxation;
}

// One field of analysis.explicit_dynamics: whether the scene set it, which
// analyses read it, and its range.
struct ExplicitField {
  const char* name;
  bool set;
  double value;
  bool dynamic;     // EXPLICIT_DYNAMIC reads it
  bool relaxation;  // DYNAMIC_RELAXATION reads it
};

const char* UsedBy(const ExplicitField& f) {
  if (f.dynamic && f.relaxation) return "EXPLICIT_DYNAMIC and DYNAMIC_RELAXATION";
  return f.dynamic ? "EXPLICIT_DYNAMIC" : "DYNAMIC_RELAXATION";
}

// The range of each field, as the message that refuses a value outside it
// (empty: inside).
std::string OutOfRange(const std::string& name, double value, const TimeSpec& time) {
  if (!std::isfinite(value)) return "must be a finite number, got " + ShortNumber(value);
  if (name == "time_step_factor") {
    if (value < 0 || value > 2) {
      return "must lie in (0, 2] (0 for the default " +
             ShortNumber(ExplicitOptions::kTimeStepFactor) + ", or " +
             ShortNumber(ExplicitOptions::kRelaxationTimeStepFactor) +
             " for DYNAMIC_RELAXATION; above 1 the integration is unstable), got " +
             ShortNumber(value);
    }
  } else if (name == "bulk_viscosity_linear" || name == "bulk_viscosity_quadratic") {
    if (value < 0 || value > 10) {
      return "must lie in [0, 10] (0 turns the term off; leave it out for the default), got " +
             ShortNumber(value);
    }
  } else if (name == "mass_damping_per_s") {
    if (value < 0)
      return "must be a non-negative number of 1/s (0: none), got " + ShortNumber(value);
  } else if (name == "hourglass_coefficient") {
    if (value < 0 || value > 0.5) {
      return "must lie in [0, 0.5] (0 for the default " +
             ShortNumber(ExplicitOptions::kHourglassCoefficient) + "), got " + ShortNumber(value);
    }
  } else if (name == "output_interval_s") {
    if (value < 0) {
      return "must be a non-negative number of s (0 for end_time_s / " +
             ShortNumber(1 / ExplicitOptions::kOutputIntervalFraction) + "), got " +
             ShortNumber(value);
    }
    if (time.end_time_s > 0 && value > time.end_time_s) {
      return "must not exceed analysis.time.end_time_s (" + ShortNumber(time.end_time_s) +
             " s), got " + ShortNumber(value) + " s";
    }
  } else if (name == "erosion_strain") {
    if (value < 0) {
      return "must be a non-negative strain (0: no erosion), got " + ShortNumber(value);
    }
  } else if (name == "mass_scaling_step_s") {
    if (value < 0) {
      return "must be a non-negative number of s (0: no mass scaling), got " + ShortNumber(value);
    }
  } else if (name == "relaxation_tolerance") {
    if (value < 0 || value >= 0.1) {
      return "must lie in [0, 0.1) (0 for the default " +
             ShortNumber(ExplicitOptions::kRelaxationTolerance) + "), got " + ShortNumber(value);
    }
  }
  return "";
}

// analysis.explicit_dynamics: each field set only for an analysis that reads
// it (as analysis.time outside QUASI_STATIC), and in range.
Status ValidateControls(const AnalysisSpec& analysis) {
  const ExplicitSpec& e = analysis.explicit_dynamics;
  const ExplicitField fields[] = {
      {"time_step_factor", e.time_step_factor != 0, e.time_step_factor, true, true},
      // Dynamic relaxation damps on its own: no bulk viscosity.
      {"bulk_viscosity_linear", e.bulk_viscosity_linear.has_value(),
       e.bulk_viscosity_linear.value_or(0), true, false},
      {"bulk_viscosity_quadratic", e.bulk_viscosity_quadratic.has_value(),
       e.bulk_viscosity_quadratic.value_or(0), true, false},
      {"mass_damping_per_s", e.mass_damping_per_s != 0, e.mass_damping_per_s, true, false},
      {"hourglass_coefficient", e.hourglass_coefficient != 0, e.hourglass_coefficient, true, true},
      {"output_interval_s", e.output_interval_s != 0, e.output_interval_s, true, false},
      {"erosion_strain", e.erosion_strain != 0, e.erosion_strain, true, false},
      {"mass_scaling_step_s", e.mass_scaling_step_s != 0, e.mass_scaling_step_s, true, false},
      {"relaxation_tolerance", e.relaxation_tolerance != 0, e.relaxation_tolerance, false, true},
  };
  for (const ExplicitField& f : fields) {
    if (!f.set) continue;
    const std::string path = std::string("analysis.explicit_dynamics.") + f.name;
    const bool used = (analysis.type == Type::kExplicitDynamic && f.dynamic) ||
                      (analysis.type == Type::kDynamicRelaxation && f.relaxation);
    if (!used) {
      return Status::InvalidArgument(path, std::string("belongs to ") + UsedBy(f) +
                                               "; this analysis is " +
                                               AnalysisTypeName(analysis.type));
    }
    const std::string why = OutOfRange(f.name, f.value, analysis.time);
    if (!why.empty()) return Status::InvalidArgument(path, why);
  }
  return Status::Ok();
}

// The sensors' fields outside EXPLICIT_DYNAMIC: refused, naming the first.
Status RefuseSensors(const OutputSpec& outputs, Type type) {
  std::string field;
  if (!outputs.sensors.empty()) {
    field = "outputs.sensors";
  } else if (outputs.sensor_interval_s != 0) {
    field = "outputs.sensor_interval_s";
  } else if (outputs.filter_cutoff_hz != 0) {
    field = "outputs.filter_cutoff_hz";
  } else if (outputs.filter_order != 0) {
    field = "outputs.filter_order";
  }
  if (field.empty()) return Status::Ok();
  return Status::InvalidArgument(field, std::string("sensors belong to an EXPLICIT_DYNAMIC "
                                                    "analysis; this one is ") +
                                            AnalysisTypeName(type));
}

// outputs.sensors (names fit for column names, unique; finite points;
// radii) and their sampling and filter.
Status ValidateSensors(const SceneSpec& scene) {
  const OutputSpec& outputs = scene.outputs;
  std::set<std::string> names;
  for (std::size_t i = 0; i < outputs.sensors.size(); ++i) {
    const SensorSpec& s = outputs.sensors[i];
    const std::string path = "outputs.sensors[" + std::to_string(i) + "]";
    if (s.name.empty()) {
      return Status::InvalidArgument(path + ".name",
                                     "a sensor needs a name: it labels its columns of sensors.csv");
    }
    const bool plain = std::all_of(s.name.begin(), s.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    if (!plain) {
      return Status::InvalidArgument(
          path + ".name",
          "'" + s.name + "' labels columns of sensors.csv: use letters, digits, '_' and '-' only");
    }
    if (!names.insert(s.name).second) {
      return Status::InvalidArgument(path + ".name",
                                     "another sensor is already named '" + s.name + "'");
    }
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(s.position_mm[c])) {
        return Status::InvalidArgument(
            path + ".position_mm[" + std::to_string(c) + "]",
            "must be a finite number of mm, got " + ShortNumber(s.position_mm[c]));
      }
    }
    if (!NonNegativeFinite(s.radius_mm)) {
      return Status::InvalidArgument(
          path + ".radius_mm",
          "must be a non-negative number of mm (0: the element holding the point), got " +
              ShortNumber(s.radius_mm));
    }
  }
  const double end = scene.analysis.time.end_time_s;
  const double interval = outputs.sensor_interval_s;
  if (!NonNegativeFinite(interval) || interval >= end) {
    return Status::InvalidArgument(
        "outputs.sensor_interval_s",
        "must be a non-negative number of s below analysis.time.end_time_s (" + ShortNumber(end) +
            " s; 0 for " + ShortNumber(kDefaultSensorIntervalS) + " s), got " +
            ShortNumber(interval));
  }
  if (outputs.filter_order < 0 || outputs.filter_order > 10) {
    return Status::InvalidArgument("outputs.filter_order",
                                   "must lie in 1..10 (0 for the default " +
                                       std::to_string(SensorOptions::kFilterOrder) + "), got " +
                                       std::to_string(outputs.filter_order));
  }
  // Below the Nyquist frequency of the samples (of the default interval when
  // none is given).
  const double nyquist = 1 / (2 * (interval > 0 ? interval : kDefaultSensorIntervalS));
  const double cutoff = outputs.filter_cutoff_hz;
  if (!NonNegativeFinite(cutoff) || (cutoff > 0 && cutoff >= nyquist)) {
    return Status::InvalidArgument(
        "outputs.filter_cutoff_hz",
        "must be a non-negative number of Hz below half the sampling rate (" +
            ShortNumber(nyquist) + " Hz for samples every " +
            ShortNumber(interval > 0 ? interval : kDefaultSensorIntervalS) +
            " s; 0 for the default " + ShortNumber(SensorOptions::kFilterCutoffHz) + " Hz), got " +
            ShortNumber(cutoff));
  }
  // The filter the engine designs, with every default applied (a default
  // cutoff may not fit a coarse interval the scene chose).
  if (outputs.sensors.empty()) return Status::Ok();
  return ResolveOutputs(scene).sensors.Validate();
}

// A material EXPLICIT_DYNAMIC can move: it needs a mass.
Status CheckDensity(const MaterialSpec& material, const std::string& path) {
  if (material.density_kg_per_m3 > 0) return Status::Ok();
  return Status::InvalidArgument(
      path + ".density_kg_per_m3",
      "EXPLICIT_DYNAMIC needs a positive mass density in kg/m^3 (brain tissue: about 1040), got " +
          ShortNumber(material.density_kg_per_m3));
}

// Every material of the scene: hyperelastic (the scene's is checked by
// ValidateAnalysis and the others share its family) and, in
// EXPLICIT_DYNAMIC, with a density.
Status ValidateMaterials(const SceneSpec& scene) {
  const bool dynamic = scene.analysis.type == Type::kExplicitDynamic;
  if (!dynamic) return Status::Ok();  // dynamic relaxation chooses fictitious masses
  PBA_RETURN_IF_ERROR(CheckDensity(scene.material, "material"));
  for (std::size_t i = 0; i < scene.region_materials.size(); ++i) {
    PBA_RETURN_IF_ERROR(CheckDensity(scene.region_materials[i].material,
                                     "region_materials[" + std::to_string(i) + "].material"));
  }
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    PBA_RETURN_IF_ERROR(CheckDensity(scene.inclusions[i].material,
                                     "inclusions[" + std::to_string(i) + "].material"));
  }
  if (scene.material_library.empty()) return Status::Ok();
  for (const ColourEntry& entry : ColourTable::Builtin().entries()) {
    MaterialSpec material;
    if (!LibraryMaterial(scene.material_library, entry.name, &material, nullptr).ok()) continue;
    if (!material.hyperelastic() || !(material.density_kg_per_m3 > 0)) {
      return Status::InvalidArgument("material_library",
                                     "the library's material for '" + entry.name +
                                         "' has no mass density (or is not hyperelastic), which "
                                         "EXPLICIT_DYNAMIC needs");
    }
  }
  return Status::Ok();
}

}  // namespace

Status CheckVelocity(const BoundaryConditionSpec& bc, AnalysisSpec::Type type,
                     const std::string& path) {
  if (type != Type::kExplicitDynamic) {
    return Status::InvalidArgument(
        path + ".velocity",
        std::string("a prescribed velocity belongs to an EXPLICIT_DYNAMIC analysis; this one is ") +
            AnalysisTypeName(type));
  }
  static const char* kNames[3] = {"x_m_per_s", "y_m_per_s", "z_m_per_s"};
  bool any = false;
  for (int c = 0; c < 3; ++c) {
    if (!bc.velocity_m_per_s[c]) continue;
    if (!std::isfinite(*bc.velocity_m_per_s[c])) {
      return Status::InvalidArgument(path + ".velocity." + kNames[c],
                                     "must be a finite number of m/s");
    }
    any = true;
  }
  if (!any) {
    return Status::InvalidArgument(
        path + ".velocity",
        "no component given: set at least one of x_m_per_s, y_m_per_s, z_m_per_s");
  }
  return Status::Ok();
}

Status ValidateExplicit(const SceneSpec& scene) {
  const Type type = scene.analysis.type;
  PBA_RETURN_IF_ERROR(ValidateControls(scene.analysis));
  if (type != Type::kExplicitDynamic) {
    PBA_RETURN_IF_ERROR(RefuseSensors(scene.outputs, type));
  }
  if (!Explicit(type)) return Status::Ok();

  const ElementType e = scene.mesh.element;
  if (e != ElementType::kDefault && !KindOf(e).explicit_engine) {
    return Status::InvalidArgument(
        "mesh.element", std::string(ElementName(e)) +
                            " is not implemented by the explicit engine; " +
                            AnalysisTypeName(type) +
                            " takes TET4_ANP (the default), TET4 or HEX8 (one-point, with "
                            "hourglass control)");
  }
  if (scene.formulation == Formulation::kAuto) {
    return Status::InvalidArgument("formulation", std::string("AUTO is not available for ") +
                                                      AnalysisTypeName(type) +
                                                      " yet; use AS_WRITTEN (or leave it out)");
  }
  PBA_RETURN_IF_ERROR(ValidateMaterials(scene));
  if (type == Type::kExplicitDynamic) PBA_RETURN_IF_ERROR(ValidateSensors(scene));
  return Status::Ok();
}

}  // namespace pba::scene_checks
