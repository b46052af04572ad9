// The face sets of a multi-region tetrahedral mesh that follow from its
// element regions (the atlas's structures), and the one change of regions
// that removes the slivers mesh improvement cannot: a flat tetrahedron
// lying against an interface, whose two faces on it meet at a few degrees.
#pragma once

#include <optional>
#include <string>

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

}  // namespace pba
