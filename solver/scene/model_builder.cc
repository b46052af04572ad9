#include "scene/model_builder.h"

#include <algorithm>

#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {

namespace {

// Where the mid-edge nodes of a 10-node mesh go on the geometry's curved
// faces: radially onto the cylinder's side, onto the shell's spheres. Flat
// faces keep their edge midpoints, which lie in them.
MidsideProjection CurvedSurfaces(const GeometrySpec& g) {
  constexpr double kMm = 1e-3;
  if (g.kind == GeometrySpec::Kind::kCylinder) {
    const double r = g.cylinder.radius_mm * kMm;
    return [r](const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
      if (set != "side") return x;
      const Eigen::Vector2d radial = x.head<2>();
      return Eigen::Vector3d(r * radial.x() / radial.norm(), r * radial.y() / radial.norm(), x.z());
    };
  }
  if (g.kind == GeometrySpec::Kind::kSphericalShell) {
    const double a = g.spherical_shell.inner_radius_mm * kMm;
    const double b = g.spherical_shell.outer_radius_mm * kMm;
    return [a, b](const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
      if (set == "inner") return a * x.normalized();
      if (set == "outer") return b * x.normalized();
      return x;
    };
  }
  return {};
}

}  // namespace

Model BuildModel(const SceneSpec& scene) {
  constexpr double kMm = 1e-3;
  Model model;
  MeshStats stats;
  model.mesh = BuildPrimitiveMesh(scene.geometry, scene.mesh, &stats);
  model.mesh_description = stats.description;
  if (scene.mesh.element == ElementType::kTet10) {
    model.mesh = MakeQuadratic(model.mesh, CurvedSurfaces(scene.geometry));
    model.mesh_description +=
        "; 10-node: a node on every edge, on the true surface of curved faces";
  }
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
