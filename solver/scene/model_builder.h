// The model a scene describes: its mesh and its constraints, built the same
// way for a solve and for an export.
#pragma once

#include <string>
#include <vector>

#include "assembly/dof_map.h"
#include "mesh/mesh.h"
#include "pba/scene.h"

namespace pba {

struct Model {
  Mesh mesh;
  DofMap dofs{0};
  std::string mesh_description;  // how the mesh was made, for the summary
};

// Meshes the geometry and applies the boundary conditions in order (a later
// condition on the same node and component wins); displacements in metres.
// Expects a validated scene.
Model BuildModel(const SceneSpec& scene);

// The sets whose reactions are reported: outputs.reaction_sets, or else every
// set a boundary condition names, in the order of first mention.
std::vector<std::string> ReactionSetNames(const SceneSpec& scene);

}  // namespace pba
