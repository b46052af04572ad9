#include "scene/model_builder.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/format.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {

namespace {

// Where the mid-edge nodes of a 10-node mesh go on the geometry's curved
// faces: radially onto the cylinder's side, onto the shell's spheres. Flat
// faces keep their edge midpoints, which lie in them.
MidsideProjection CurvedSurfaces(const GeometrySpec& g) {
  constexpr double kMm = 1e-3;
  if (g.kind == GeometrySpec::Kind::kEllipsoid) {
    const auto& a = g.ellipsoid.semi_axes_mm;
    const Eigen::Vector3d inverse(1 / (a[0] * kMm), 1 / (a[1] * kMm), 1 / (a[2] * kMm));
    // Along the ray from the centre: the point where it leaves the body.
    return [inverse](const Eigen::Vector3d& x, const std::string&) -> Eigen::Vector3d {
      return x / x.cwiseProduct(inverse).norm();
    };
  }
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

// A patch's mid-edge nodes go where its parent set's do.
MidsideProjection WithPatches(const GeometrySpec& g, MidsideProjection project) {
  if (!project || g.patches.empty()) return project;
  std::map<std::string, std::string> parent;
  for (const PatchSpec& p : g.patches) parent[p.name] = p.set;
  return [parent = std::move(parent), project = std::move(project)](
             const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
    const auto it = parent.find(set);
    return project(x, it == parent.end() ? set : it->second);
  };
}

// Cuts the geometry's patches out of their sets; a patch that holds no
// face is an error naming it and the radius that would hold one.
Status CutPatches(const GeometrySpec& g, Mesh* mesh) {
  constexpr double kMm = 1e-3;
  for (std::size_t i = 0; i < g.patches.size(); ++i) {
    const PatchSpec& p = g.patches[i];
    const FaceSet& parent = mesh->face_sets.at(p.set);
    const Eigen::Vector3d centre =
        Eigen::Vector3d(p.centre_mm[0], p.centre_mm[1], p.centre_mm[2]) * kMm;
    FaceSet patch = FacesWithin(*mesh, parent, centre, p.radius_mm * kMm);
    if (patch.triangles.empty() && patch.quads.empty()) {
      // The smallest radius about this centre that would hold a face.
      double needed = INFINITY;
      const auto reach = [&](const auto& face) {
        double r = 0;
        for (int node : face) r = std::max(r, (mesh->nodes.row(node).transpose() - centre).norm());
        needed = std::min(needed, r);
      };
      for (const auto& t : parent.triangles) reach(t);
      for (const auto& q : parent.quads) reach(q);
      return Status::InvalidArgument(
          "geometry.patches[" + std::to_string(i) + "].radius_mm",
          Format("patch '%s' holds no face of '%s': no face has all its nodes within %g mm of "
                 "(%g, %g, %g) mm; about this centre the radius must be at least %.3g mm at "
                 "this element size (or move the centre onto the surface)",
                 p.name.c_str(), p.set.c_str(), p.radius_mm, p.centre_mm[0], p.centre_mm[1],
                 p.centre_mm[2], needed / kMm));
    }
    mesh->face_sets[p.name] = std::move(patch);
  }
  return Status::Ok();
}

}  // namespace

Status BuildModel(const SceneSpec& scene, Model* out) {
  constexpr double kMm = 1e-3;
  Model& model = *out;
  model = Model();
  MeshStats stats;
  model.mesh = BuildPrimitiveMesh(scene.geometry, scene.mesh, &stats);
  model.mesh_description = stats.description;
  PBA_RETURN_IF_ERROR(CutPatches(scene.geometry, &model.mesh));
  if (IsQuadratic(scene.mesh.element)) {
    model.mesh =
        MakeQuadratic(model.mesh, WithPatches(scene.geometry, CurvedSurfaces(scene.geometry)));
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
  return Status::Ok();
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
