#include "mesh/element_shape.h"

namespace pba {
namespace {

// shape, name, nodes, corners, VTK cell, XDMF topology, Gmsh type, Abaqus
// type, boundary face. All three keep the mesh's node order in VTK, XDMF
// and Abaqus (mesh.h); Gmsh's 10-node order differs (io/mesh_export.h).
constexpr ElementShapeInfo kShapes[] = {
    {ElementShape::kTet4, "TET4", 4, 4, 10, "Tetrahedron", 4, "C3D4", BoundaryFace::kTri3},
    {ElementShape::kTet10, "TET10", 10, 4, 24, "Tetrahedron_10", 11, "C3D10", BoundaryFace::kTri6},
    {ElementShape::kHex8, "HEX8", 8, 8, 12, "Hexahedron", 5, "C3D8", BoundaryFace::kQuad4},
};

// ShapeInfo indexes the table by the enum's value.
static_assert(static_cast<int>(kShapes[0].shape) == 0 && static_cast<int>(kShapes[1].shape) == 1 &&
              static_cast<int>(kShapes[2].shape) == 2);

}  // namespace

std::span<const ElementShapeInfo> ElementShapes() { return kShapes; }

const ElementShapeInfo& ShapeInfo(ElementShape shape) { return kShapes[static_cast<int>(shape)]; }

const ElementShapeInfo* ShapeWithNodes(int nodes) {
  for (const ElementShapeInfo& row : kShapes) {
    if (row.nodes == nodes) return &row;
  }
  return nullptr;
}

}  // namespace pba
