#include "scene/unsolved.h"

namespace pba {

Status RefuseUnsupportedFields(const SceneSpec& scene, const std::string& action) {
  const auto refuse = [&](const std::string& field, const std::string& what) {
    return Status::FailedPrecondition(field + ": " + what + " is not " + action +
                                      " by this version");
  };
  if (scene.analysis.type == AnalysisSpec::Type::kQuasiStatic) {
    return refuse("analysis.type", "QUASI_STATIC");
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
