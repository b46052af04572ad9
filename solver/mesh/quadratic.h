// Quadratic (10-node) tetrahedral meshes from linear ones: one node per
// edge, the corners left as they are, so that Mesh::tets still describes a
// valid linear mesh of the corners.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>

#include "fem/tet10.h"
#include "mesh/mesh.h"

namespace pba {

// Moves a boundary mid-edge node from `position` (on entry the edge's
// midpoint) onto the true surface of face set `face_set`, e.g. radially onto
// a cylinder [m].
using MidsideProjection =
    std::function<Eigen::Vector3d(const Eigen::Vector3d& position, const std::string& face_set)>;

// A copy of `linear` (which must not be quadratic) with a node at the
// midpoint of every unique edge, Mesh::midside and FaceSet::triangle_midside
// filled, and the mid-edge nodes added to the face sets' `nodes`.
//
// Numbering is deterministic: the corners keep their indices 0..n-1 and the
// mid-edge nodes follow, ordered by their edge's (smaller, larger) corner
// index pair.
//
// When `project` is set it is called for each mid-edge node on a face set,
// once per face set holding it, in face-set name order, each call receiving
// the position returned by the previous one (a node on the rim between a
// cylinder's side and top goes onto the circle, then stays in the top
// plane). Interior mid-edge nodes stay at their midpoints.
Mesh MakeQuadratic(const Mesh& linear, const MidsideProjection& project = {});

// The ten node indices of tet `e` of a quadratic mesh, in the order of
// fem/tet10.h (corners, then Mesh::midside).
std::array<int, 10> Tet10NodeIndices(const Mesh& mesh, int e);

// Their coordinates, one row per node [m].
Tet10Nodes Tet10Coordinates(const Mesh& mesh, int e);

}  // namespace pba
