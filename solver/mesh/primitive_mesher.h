// Structured tetrahedral or hexahedral meshes of the primitive bodies.
//
// The cross-section (a rectangle, or a disk cut as an O-grid: a central
// square and four curved blocks) is meshed with quadrilaterals, each split
// into two triangles, and extruded along z into prisms; every prism is cut
// into three tetrahedra with the smallest-global-index rule (Dompierre et al.
// 1999, "How to subdivide pyramids, prisms and hexahedra into tetrahedra"),
// which makes neighbouring prisms agree on their shared faces whatever the
// numbering, so the mesh is conforming. The spherical shell's octant is
// built the same way from a cubed-sphere surface extruded radially.
//
// With MeshSpec::element == kHex8 the quadrilaterals are extruded into
// 8-node bricks instead (Mesh::hexes, positively oriented), and each face
// set holds boundary quads (FaceSet::quads, anticlockwise seen from outside
// the body) in place of triangles; the sets have the same names.
#pragma once

#include <cstdint>
#include <string>

#include "mesh/mesh.h"
#include "pba/scene.h"

namespace pba {

struct MeshStats {
  // e.g. "structured grid of 10 x 10 x 15 cells, each cut into 6
  // tetrahedra", or "... 10 x 10 x 15 hexahedra".
  std::string description;
};

// Builds the mesh of `geometry` (mm in, metres out) with face sets named as in
// FaceSetNames(). Expects a validated scene.
Mesh BuildPrimitiveMesh(const GeometrySpec& geometry, const MeshSpec& options, MeshStats* stats);

// The element count BuildPrimitiveMesh would produce (for validation):
// tetrahedra, or bricks for kHex8.
int64_t EstimateElementCount(const GeometrySpec& geometry, const MeshSpec& options);

// The element size used: options.element_size_mm or the default, a twentieth
// of the body's largest dimension [mm].
double EffectiveElementSize(const GeometrySpec& geometry, const MeshSpec& options);

// The element size of an atlas geometry when the scene gives none [mm].
inline constexpr double kDefaultAtlasElementSizeMm = 8;

}  // namespace pba
