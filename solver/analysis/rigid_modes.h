// Which rigid-body motions do the constraints leave free?
#pragma once

#include <string>

#include "assembly/dof_map.h"
#include "mesh/mesh.h"

namespace pba {

// Evaluates the six rigid motions (translations along x, y, z; rotations
// about axes through the centroid) at the prescribed unknowns. A combination
// that vanishes on all of them is a motion the constraints do not stop.
// Returns "" when none is free, else a description such as
// "rotation about z through (10, 10, 15) mm".
std::string DescribeFreeRigidModes(const Mesh& mesh, const DofMap& dofs);

}  // namespace pba
