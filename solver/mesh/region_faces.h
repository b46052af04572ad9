// The face sets of a multi-region tetrahedral mesh that follow from its
// element regions (the atlas's structures), and the one change of regions
// that removes the slivers mesh improvement cannot: a flat tetrahedron
// lying against an interface, whose two faces on it meet at a few degrees.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "mesh/mesh.h"

namespace pba {

// Replaces the region-derived face sets of a linear tetrahedral mesh with
// ones built from Mesh::element_region (the other face sets are kept):
//   "surface"            faces of one tetrahedron only, anticlockwise seen
//                        from outside;
//   "interface:<a>|<b>"  faces between regions a and b (region indices
//                        a < b), anticlockwise seen from b: the normal
//                        points from a into b;
//   "surface:<a>"        every face of region a against the outside or
//                        another region, anticlockwise seen from outside a.
// Names are Mesh::region_names; a mesh without regions gets "surface" only.
// The conventions are those of MeshLabels (atlas/label_mesher.h).
void RebuildRegionFaceSets(Mesh* mesh);

// The names of the region-derived face sets (see RebuildRegionFaceSets).
std::string RegionSurfaceSetName(const std::string& region);
std::string InterfaceSetName(const std::string& first, const std::string& second);

// A region-derived face set's name taken apart: "surface:<first>", or
// "interface:<first>|<second>" (split at the first '|'). Empty for any
// other name, an "interface:" one without '|' among them.
struct RegionSetName {
  bool interface = false;
  std::string first, second;  // second: empty for a region's surface
};
std::optional<RegionSetName> ParseRegionSetName(const std::string& name);

struct RelabelStats {
  int tetrahedra = 0;    // moved to another region
  double volume_m3 = 0;  // their total volume
};

// Every tetrahedron whose smallest dihedral angle is below `target_deg` and
// that has at least two faces against one other region b (and is not the
// last of its own region) is moved into region b, largest count of shared
// faces first. Such a sliver is nearly flat and lies along the interface:
// the interface then runs over its other faces, the regions change by its
// volume (reported), and inside b it has neighbours of its own region that
// flips can use (mesh/improve.h). Region-derived face sets are rebuilt when
// anything moved. A linear tetrahedral mesh with regions; others are left
// as they are.
RelabelStats RelabelInterfaceSlivers(double target_deg, Mesh* mesh);

// Tetrahedra taken out of a mesh: how many, their volume and the regions
// they were in (Mesh::region_names, sorted, each once).
struct RemovedTetrahedra {
  int tetrahedra = 0;
  double volume_m3 = 0;
  std::vector<std::string> regions;
};

// Takes out the nodes of a mesh that no element uses (the rest keep their
// order, renumbered in the elements and face sets; a face set triangle with
// a node taken out goes too). Region-derived face sets are not rebuilt.
void DropUnusedNodes(Mesh* mesh);

// Takes the tetrahedra with remove[e] out of a linear tetrahedral mesh, and
// the nodes no other tetrahedron uses (the rest keep their order,
// renumbered), and rebuilds the region-derived face sets; another face set
// keeps the triangles whose nodes all remain. A region may be left with no
// tetrahedron: the callers below never take a region's last one.
RemovedTetrahedra RemoveTetrahedra(const std::vector<char>& remove, Mesh* mesh);

// Every tetrahedron whose smallest dihedral angle is below `target_deg` and
// that has a face on the outer boundary (a face of no other tetrahedron),
// unless it is the last of its region, is taken out: after mesh
// improvement (mesh/improve.h) such a sliver is one no flip or node move
// could lift, lying in a fold of the body's surface or pinned between it
// and an interface; the body loses only its volume (reported). A linear
// tetrahedral mesh; others are left as they are.
RemovedTetrahedra PeelBoundarySlivers(double target_deg, Mesh* mesh);

// The mesh's pieces (MeshPieces) whose volume is under `share` of the
// largest piece's are taken out: the fragments a mesher leaves where a few
// voxels touch the rest by an edge or a corner, which nothing holds and
// would leave the stiffness singular; a piece with the last tetrahedra of a
// region stays. `pieces` (may be null) gets how many were taken. A linear
// tetrahedral mesh; others are left as they are.
RemovedTetrahedra DropMeshFragments(double share, Mesh* mesh, int* pieces);

}  // namespace pba
