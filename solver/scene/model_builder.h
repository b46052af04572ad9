// The model a scene describes: its mesh and its constraints, built the same
// way for a solve and for an export.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "assembly/dof_map.h"
#include "assembly/external_loads.h"
#include "mesh/mesh.h"
#include "pba/scene.h"
#include "scene/materials.h"

namespace pba {

struct AtlasBuildResult;  // atlas/atlas_build.h

struct Model {
  Mesh mesh;
  DofMap dofs{0};
  std::string mesh_description;  // how the mesh was made, for the summary
  SceneMaterials materials;      // the material of every element
};

struct BuildModelOptions {
  // Where built atlas meshes are kept and looked up (atlas/atlas_mesh_cache.h);
  // empty: every atlas is meshed. Only 4-node atlas meshes are cached (a
  // 10-node one needs the loft, which is not kept).
  std::filesystem::path atlas_cache_dir;
  // The bound of that directory [bytes]; least recently used entries go.
  std::uint64_t atlas_cache_max_bytes = std::uint64_t{2} << 30;
};

// Meshes the geometry, cuts its patches and applies the boundary conditions
// in order (a later condition on the same node and component wins);
// displacements in metres. Expects a validated scene; fails (naming it) on
// a patch that holds no face, which only the mesh can tell.
// BuildBaseMesh, then BuildModelOn.
Status BuildModel(const SceneSpec& scene, Model* model, const BuildModelOptions& options = {});

// The geometry meshed: the primitive's grid or the atlas's structures, with
// the face sets the geometry names, before patches, inclusions, materials,
// mid-edge nodes and conditions. What an adaptive solve refines
// (mesh.adapt) and builds the model on again and again.
struct BaseMesh {
  Mesh mesh;                // 4-node tetrahedra or 8-node hexahedra
  std::string description;  // how it was made, for the summary
  // The atlas's build (null for a primitive), which curves a 10-node
  // mesh's faces onto the atlas's smooth surfaces; holds no mesh.
  std::shared_ptr<const AtlasBuildResult> atlas;
};
Status BuildBaseMesh(const SceneSpec& scene, const BuildModelOptions& options, BaseMesh* base);

// The model on a base mesh: the patches cut, the inclusions, the materials,
// the mid-edge nodes of a 10-node mesh, the conditions.
Status BuildModelOn(const SceneSpec& scene, BaseMesh base, Model* model);

// The loads of the scene's pressure and traction conditions and its gravity,
// at full value (SI). Pressure follows the deformation in a nonlinear
// analysis. Gravity acts on each element's own density, less the buoyancy
// of the fluid below its level. `model` must outlive the result.
ExternalLoads BuildLoads(const SceneSpec& scene, const Model& model);

// The sets whose reactions are reported: outputs.reaction_sets, or else every
// set a displacement-type condition (fixed, displacement, symmetry) names, in
// the order of first mention.
std::vector<std::string> ReactionSetNames(const SceneSpec& scene);

}  // namespace pba
