// The element shapes a Mesh holds, in one table: each shape's nodes, its
// corners, the names and numbers the file formats give it and the kind of
// its boundary faces. Code that only needs to know "how many nodes, which
// ones, what is it called in VTK / XDMF / Gmsh / Abaqus" reads the row of
// Mesh::shape() instead of asking whether the mesh is quadratic or
// hexahedral; a new shape is a row here (and a case in the switches the
// compiler then points at).
//
// This is the geometry of the mesh, not the element formulation: TET4 and
// TET4_ANP, HEX8 and HEX8_FULL share a shape (fem/element_kind.h is the
// formulation table).
#pragma once

#include <array>
#include <span>

namespace pba {

enum class ElementShape {
  kTet4,   // 4-node tetrahedron (Mesh::tets)
  kTet10,  // 10-node tetrahedron (Mesh::tets, their corners, and Mesh::midside)
  kHex8,   // 8-node hexahedron (Mesh::hexes)
};

// The faces on a mesh's boundary (FaceSet::triangles, with
// FaceSet::triangle_midside for kTri6, or FaceSet::quads).
enum class BoundaryFace {
  kTri3,   // 3-node triangle
  kTri6,   // 6-node triangle: corners, then the mid-edge nodes
  kQuad4,  // 4-node (bilinear) quadrilateral
};

struct ElementShapeInfo {
  ElementShape shape;
  const char* name;           // "TET4", "TET10", "HEX8"
  int nodes;                  // per element: 4, 10, 8
  int corners;                // the first `corners` nodes are vertices: 4, 4, 8
  int vtk_cell_type;          // vtkCellType.h: VTK_TETRA 10, VTK_QUADRATIC_TETRA 24,
                              // VTK_HEXAHEDRON 12
  const char* xdmf_topology;  // XDMF 3 TopologyType: "Tetrahedron", "Tetrahedron_10",
                              // "Hexahedron"
  int gmsh_type;              // Gmsh element type: 4, 11, 5
  const char* abaqus_type;    // the plain Abaqus / CalculiX element: "C3D4", "C3D10", "C3D8"
  BoundaryFace boundary_face;
};

// Every shape, in the order of ElementShape.
std::span<const ElementShapeInfo> ElementShapes();

// The row of `shape`.
const ElementShapeInfo& ShapeInfo(ElementShape shape);

// The row whose elements have `nodes` nodes (a connectivity's width, as
// result files store it); null for a width no shape has.
const ElementShapeInfo* ShapeWithNodes(int nodes);

// The most nodes an element of any shape has.
inline constexpr int kMaxElementNodes = 10;

// One element's node indices (Mesh::ElementNodes), held by value without a
// heap allocation; iterable, `for (int node : mesh.ElementNodes(e))`.
struct NodeList {
  std::array<int, kMaxElementNodes> node{};
  int count = 0;

  int size() const { return count; }
  int operator[](int i) const { return node[i]; }
  const int* begin() const { return node.data(); }
  const int* end() const { return node.data() + count; }
};

}  // namespace pba
