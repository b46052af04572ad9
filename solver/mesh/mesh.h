// Mesh: nodes, tetrahedra (4- or 10-node) or 8-node hexahedra, and named
// boundary face sets.
// Coordinates in metres (SI inside the solver).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "mesh/element_shape.h"

namespace pba {

// A named part of the boundary: its triangles and the nodes they touch.
struct FaceSet {
  std::vector<std::array<int, 3>> triangles;  // node indices
  // Quadratic mesh only (else empty): the mid-edge nodes of each triangle,
  // on its edges (0,1), (1,2), (2,0).
  std::vector<std::array<int, 3>> triangle_midside;
  // Hexahedral mesh only (then `triangles` is empty): the boundary
  // quadrilaterals, node indices in order around the face.
  std::vector<std::array<int, 4>> quads;
  std::vector<int> nodes;  // sorted, unique; mid-edge nodes included
};

struct Mesh {
  // nodes x 3 [m]
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> nodes;
  // Positively oriented 4-node tetrahedra (node indices); for a quadratic
  // mesh their corners.
  std::vector<std::array<int, 4>> tets;
  // Quadratic mesh only (else empty): the mid-edge nodes of each tet, in the
  // Abaqus / CalculiX C3D10 order: edges (0,1), (1,2), (2,0), (0,3), (1,3),
  // (2,3) of tets[e] (see mesh/quadratic.h, fem/tet10.h).
  std::vector<std::array<int, 6>> midside;
  // Hexahedral mesh only (else empty; `tets` is then empty): 8-node bricks
  // in the Abaqus C3D8 / VTK_HEXAHEDRON order: 0-1-2-3 one face, 4-7 the
  // opposite one with node 4 + i across from node i, positively oriented
  // (natural coordinates (-1,-1,-1), (1,-1,-1), (1,1,-1), (-1,1,-1), then
  // the same at +1, map to a right-handed brick; see fem/hex8.h).
  std::vector<std::array<int, 8>> hexes;
  std::map<std::string, FaceSet> face_sets;
  // Element regions (the atlas's structures): region_names[element_region[e]]
  // is element e's region. Both empty for a one-region body.
  std::vector<std::string> region_names;
  std::vector<int> element_region;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_elements() const { return static_cast<int>(hexes.empty() ? tets.size() : hexes.size()); }

  // The shape of every element: hexahedra when `hexes` is set, else 10-node
  // tetrahedra when `midside` is, else 4-node tetrahedra (also for a mesh
  // without elements). The one place that tells the shapes apart by which
  // arrays are filled; ShapeInfo(shape()) gives its nodes and names.
  ElementShape shape() const {
    return !hexes.empty()     ? ElementShape::kHex8
           : !midside.empty() ? ElementShape::kTet10
                              : ElementShape::kTet4;
  }
  bool quadratic() const { return shape() == ElementShape::kTet10; }
  bool hexahedral() const { return shape() == ElementShape::kHex8; }

  // Element e's nodes in the Abaqus / VTK order (C3D4, C3D10: corners, then
  // `midside`; C3D8), ShapeInfo(shape()).nodes of them.
  NodeList ElementNodes(int e) const;
  // Its corners: the first ShapeInfo(shape()).corners of those.
  NodeList ElementCorners(int e) const;
};

// Corner coordinates of tetrahedron `e`, one row per node [m].
// The mesh's pieces: elements that share a face (three corners or more)
// are in one piece. Returns each element's piece, 0 .. *pieces - 1.
std::vector<int> MeshPieces(const Mesh& mesh, int* pieces);

Eigen::Matrix<double, 4, 3> TetCorners(const Mesh& mesh, int e);

// Corner coordinates of hexahedron `e`, one row per node in the C3D8 order
// [m].
Eigen::Matrix<double, 8, 3> HexCorners(const Mesh& mesh, int e);

// Signed volume of hexahedron `e` [m^3]: the integral of det J of its
// trilinear map over [-1, 1]^3, by the 2 x 2 x 2 Gauss rule, which is exact
// (det J is at most quadratic in each natural coordinate). Positive for a
// positively oriented brick.
double HexVolume(const Mesh& mesh, int e);

// Total area of a face set [m^2]: its triangles (flat) and its quadrilaterals
// (the bilinear surface through their four nodes, whose area element
// |x_,xi x x_,eta| is integrated by the 2 x 2 Gauss rule: exact for a flat
// parallelogram, close for a gently warped quad).
double FaceSetArea(const Mesh& mesh, const FaceSet& set);

// Sets `set->nodes` to the nodes its faces touch (triangle corners, their
// mid-edge nodes, quad corners), sorted and unique.
void CollectFaceSetNodes(FaceSet* set);

// The faces of `set` all of whose corners `keep` accepts (given the node's
// position [m]), with their mid-edge nodes on a quadratic mesh; `nodes`
// lists what they touch.
// With `complement`, the other faces of `set` instead (those with some
// corner `keep` refuses).
FaceSet FacesWhere(const Mesh& mesh, const FaceSet& set,
                   const std::function<bool(const Eigen::Vector3d& x)>& keep,
                   bool complement = false);

// The faces of `set` whose corners all lie within `radius` of `centre` [m]
// (a patch of it, e.g. where a punch presses), with their mid-edge nodes
// on a quadratic mesh; `nodes` lists what they touch.
FaceSet FacesWithin(const Mesh& mesh, const FaceSet& set, const Eigen::Vector3d& centre,
                    double radius);

// The tetrahedron behind each triangle of a boundary face set: for triangle
// i, {element, corner}, `corner` (0..3) being the element's node opposite the
// triangle; {-1, -1} for a triangle that is no element's face.
std::vector<std::array<int, 2>> FaceElements(const Mesh& mesh, const FaceSet& set);

// The faces of a C3D8 brick, 0-based local nodes in the Abaqus order and
// numbering: face k is Abaqus's S(k+1), S1 = 1-2-3-4, S2 = 5-8-7-6,
// S3 = 1-5-6-2, S4 = 2-6-7-3, S5 = 3-7-8-4, S6 = 4-8-5-1 (1-based). Each
// is listed anticlockwise seen from inside the brick (its right-hand normal
// points into a positively oriented brick), so reversed it faces out.
inline constexpr int kHex8Faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                         {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}};

// The hexahedron behind each quadrilateral of a boundary face set: for quad
// i, {element, face}, `face` (0..5) the local face of kHex8Faces, that is
// the Abaqus face label S(face + 1) a distributed load on it is written
// with; {-1, -1} for a quad that is no element's face. The quad's nodes may
// start anywhere and run either way round.
std::vector<std::array<int, 2>> QuadFaceElements(const Mesh& mesh, const FaceSet& set);

}  // namespace pba
