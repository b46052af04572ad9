// Edge collapse for the slivers mesh improvement (mesh/improve.h) cannot
// reach: those around a very short edge on a surface or an interface.
//
// A mesher that follows several labelled surfaces leaves, where an
// interface meets the outer surface or two interfaces meet, edges a small
// fraction of the local element size long. The dihedral angle opposite such
// an edge is about its length over the distance to the edge across, so each
// tetrahedron around it is a sliver, and with all its corners held on
// surfaces no flip, node move or node insertion inside a region changes
// it: the surface itself has to change. Collapsing the edge (a, b) moves
// b onto a: the tetrahedra around the edge vanish, those around b alone
// take a in its place, and b leaves the mesh.
//
// What a collapse keeps, so that each region stays the same shape up to
// the collapsed edge's length where it moves a node on a surface or an
// interface (at most `max_edge_m`, which the caller sets from what the mesh
// must resolve), and exactly where it moves one inside a region:
//   - every surface patch (faces between one region and another, or the
//     outside) that b is on, a is on too, and the edge lies on that patch:
//     b slides along its surfaces and interfaces, never across one, and a
//     node on the line where three patches meet moves only along it;
//   - the topology of the mesh and of each region: the link condition
//     (Dey, Edelsbrunner, Guha & Nekhayev, "Topology preserving edge
//     contraction", 1999) holds for the whole mesh and for each region's
//     tetrahedra alone, each with its boundary coned to a vertex at
//     infinity: the links of a and b meet exactly in the link of the edge,
//     so no two faces fold onto each other and nothing pinches;
//   - no region loses its last tetrahedron, and no node of a face set that
//     is not region-derived (RebuildRegionFaceSets, mesh/region_faces.h)
//     moves;
//   - every tetrahedron that takes a in b's place stays positively
//     oriented, and the worst of them is better than the worst of the
//     tetrahedra around b before (the quality of ImproveOptions: the
//     smallest dihedral angle, or that with the aspect ratio), so the
//     smallest angle around a collapse rises.
// Of the two directions, the one whose worst new tetrahedron is better is
// taken. Region-derived face sets are rebuilt, and the nodes no tetrahedron
// uses any more are taken out (the others keep their order, renumbered).
#pragma once

#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

struct CollapseOptions {
  // The tetrahedra worked on: smallest dihedral angle below this
  // [degrees], in (0, 70.5).
  double target_min_dihedral_deg = 15;
  // The quality a collapse must raise, as ImproveOptions::target_aspect_ratio
  // (0: the smallest dihedral angle alone).
  double target_aspect_ratio = 0;
  // An edge of such a tetrahedron is collapsed only when it is shorter than
  // this fraction of the tetrahedron's longest edge, in (0, 1],
  double max_edge_ratio = 0.25;
  // and, to move a node on a surface or an interface, than this [m], > 0:
  // no surface or interface moves further. (A node inside a region may
  // move further: its region stays the same point set.)
  double max_edge_m = 0;
  // Passes over the tetrahedra below the target, >= 1.
  int max_passes = 3;
};

struct CollapseStats {
  int edges = 0;                 // collapsed (one node taken out each)
  int removed_tetrahedra = 0;    // the tetrahedra around them
  double longest_m = 0;          // the longest edge collapsed: the largest node move
  double longest_surface_m = 0;  // of those, the longest moving a surface or interface node
  // Smallest dihedral angle over the mesh [degrees], before and after.
  double min_dihedral_before_deg = 0;
  double min_dihedral_after_deg = 0;
};

// Collapses short edges of the tetrahedra below the target (see above),
// worst tetrahedron first, its shortest edge first. Errors (the mesh is then
// untouched): InvalidArgument "mesh" for a null mesh or one that is not
// linear tetrahedral, those of TetTopology::Build (mesh/tet_topology.h),
// and the option's name for a bad option.
Status CollapseShortEdges(const CollapseOptions& options, Mesh* mesh, CollapseStats* stats);

}  // namespace pba
