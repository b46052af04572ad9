#include "scene/unsolved.h"

namespace pba {

Status RefuseUnsupportedFields(const SceneSpec& scene, const std::string& action) {
  const auto refuse = [&](const std::string& field, const std::string& what) {
    return Status::FailedPrecondition(field + ": " + what + " is not " + action +
                                      " by this version");
  };
  switch (scene.analysis.type) {
    case AnalysisSpec::Type::kLinearStatic:
    case AnalysisSpec::Type::kNonlinearStatic:
      break;
    case AnalysisSpec::Type::kQuasiStatic:
      return refuse("analysis.type", "QUASI_STATIC");
    // One static step cannot hold them: an explicit dynamic step, or the
    // damped run to rest (the static answer is NONLINEAR_STATIC's).
    case AnalysisSpec::Type::kExplicitDynamic:
      return refuse("analysis.type", "EXPLICIT_DYNAMIC");
    case AnalysisSpec::Type::kDynamicRelaxation:
      return refuse("analysis.type", "DYNAMIC_RELAXATION");
  }
  if (!scene.material_library.empty()) return refuse("material_library", "the tissue library");
  if (!scene.region_materials.empty()) {
    return refuse("region_materials", "a material per structure");
  }
  if (!scene.inclusions.empty()) return refuse("inclusions", "an inclusion");
  if (!scene.contacts.empty()) return refuse("contacts", "rigid contact");
  if (scene.gravity.fluid_density_kg_per_m3 > 0) {
    return refuse("gravity.fluid_density_kg_per_m3", "buoyancy");
  }
  if (!scene.outputs.structure_displacements.empty()) {
    return refuse("outputs.structure_displacements", "a structure's displacement");
  }
  return Status::Ok();
}

}  // namespace pba
