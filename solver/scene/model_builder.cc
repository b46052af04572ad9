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

std::vector<std::string> ReactionSetNames(const SceneSpec& scene) {
  if (!scene.outputs.reaction_sets.empty()) return scene.outputs.reaction_sets;
  std::vector<std::string> out;
  for (const auto& bc : scene.boundary_conditions) {
    if (std::find(out.begin(), out.end(), bc.set) == out.end()) out.push_back(bc.set);
  }
  return out;
}

}  // namespace pba
