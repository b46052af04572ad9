#include "scene/model_builder.h"

#include <algorithm>

#include "mesh/primitive_mesher.h"

namespace pba {

Model BuildModel(const SceneSpec& scene) {
  constexpr double kMm = 1e-3;
  Model model;
  MeshStats stats;
  model.mesh = BuildPrimitiveMesh(scene.geometry, scene.mesh, &stats);
  model.mesh_description = stats.description;
  model.dofs = DofMap(model.mesh.num_nodes());
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    if (bc.is_load()) continue;  // see BuildLoads
    const int normal = bc.kind == BoundaryConditionSpec::Kind::kSymmetry
                           ? PlaneNormalAxis(scene.geometry, bc.set)
                           : -1;
    for (int node : model.mesh.face_sets.at(bc.set).nodes) {
      if (normal >= 0) {
        model.dofs.Prescribe(node, normal, 0.0);
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        if (bc.kind == BoundaryConditionSpec::Kind::kFixed) {
          model.dofs.Prescribe(node, c, 0.0);
        } else if (bc.displacement_mm[c]) {
          model.dofs.Prescribe(node, c, *bc.displacement_mm[c] * kMm);
        }
      }
    }
  }
  model.dofs.Finalize();
  return model;
}

ExternalLoads BuildLoads(const SceneSpec& scene, const Mesh& mesh) {
  ExternalLoads loads(mesh);
  const bool follower = scene.analysis.type == AnalysisSpec::Type::kNonlinearStatic;
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    const FaceSet& set = mesh.face_sets.at(bc.set);
    if (bc.kind == BoundaryConditionSpec::Kind::kPressure && bc.pressure_pa != 0) {
      loads.AddPressure(set, bc.pressure_pa, follower);
    } else if (bc.kind == BoundaryConditionSpec::Kind::kTraction) {
      loads.AddTraction(set, Eigen::Vector3d(bc.traction_pa.data()));
    }
  }
  if (scene.gravity.enabled) {
    loads.AddBodyForce(scene.material.density_kg_per_m3 *
                       Eigen::Vector3d(scene.gravity.acceleration_m_per_s2.data()));
  }
  return loads;
}

std::vector<std::string> ReactionSetNames(const SceneSpec& scene) {
  if (!scene.outputs.reaction_sets.empty()) return scene.outputs.reaction_sets;
  std::vector<std::string> out;
  for (const auto& bc : scene.boundary_conditions) {
    if (bc.is_load()) continue;
    if (std::find(out.begin(), out.end(), bc.set) == out.end()) out.push_back(bc.set);
  }
  return out;
}

}  // namespace pba
