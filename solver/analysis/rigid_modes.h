// Which rigid-body motions do the constraints leave free?
#pragma once

#include <string>
#include <vector>

#include "assembly/dof_map.h"
#include "mesh/mesh.h"

namespace pba {

// Evaluates the six rigid motions (translations along x, y, z; rotations
// about axes through the centroid) at the prescribed unknowns. A combination
// that vanishes on all of them is a motion the constraints do not stop.
// Returns "" when none is free, else a description such as
// "rotation about z through (10, 10, 15) mm".
std::string DescribeFreeRigidModes(const Mesh& mesh, const DofMap& dofs);

// MeshPieces (mesh/mesh.h) finds the pieces.

// A mesh in several pieces (a real atlas's meshes can hold fragments, and
// parts joined to the rest only by an edge or a corner) is held only when
// each piece is: a piece the constraints leave free makes the stiffness
// singular, and the solve would wander or stop without a word. Returns ""
// when every piece is held, else a description of those that are not
// (their elements, structures, centre, how they touch the rest, their
// free motions; the first five).
std::string DescribeLoosePieces(const Mesh& mesh, const DofMap& dofs);

}  // namespace pba
