// Improvement of a linear tetrahedral mesh after it has been generated:
// edge removal, 2-3 flips and smoothing of interior nodes, aimed at the
// slivers (nearly flat tetrahedra, smallest dihedral angle a few degrees)
// that Delaunay refinement leaves between the surfaces of a multi-material
// mesh, where sliver perturbation and exudation cannot move the vertices.
//
// The quality of a tetrahedron is its smallest dihedral angle (as in
// TetDihedralRangeDegrees, mesh/quality.h), or with
// ImproveOptions::target_aspect_ratio that angle together with its aspect
// ratio (TetMeasure, mesh/tet_angles.h); "angle" below stands for the
// quality. Only the tetrahedra below
// ImproveOptions::target_min_dihedral_deg are worked on, worst first (a
// worklist, so a mesh of a few hundred thousand tetrahedra with a few
// hundred slivers takes a fraction of a second, most of it building the
// adjacency). For each, the schedule of Klingner & Shewchuk ("Aggressive
// tetrahedral mesh improvement", 16th International Meshing Roundtable,
// 2007):
//   1. smoothing: each node of the tetrahedron that may move tries the
//      mean of the centroids of the faces opposite it in its tetrahedra,
//      then a few steps of the non-smooth steepest ascent of the smallest
//      dihedral angle among them (the active angles' gradients combined
//      into the shortest vector of their convex hull, a step to where a
//      further angle is predicted to become the smallest, halved until it
//      helps; Freitag & Ollivier-Gooch, "Tetrahedral mesh improvement using
//      swapping and smoothing", IJNME 40 (1997) 3979-4002; see
//      StarObjective in mesh/tet_angles.h);
//   2. the best of these flips:
//      - edge removal on each of its six edges: the ring of m = 3 ..
//        max_ring_size tetrahedra around an interior edge (a, b) is
//        replaced by the 2 (m - 2) tetrahedra joining a and b to a
//        triangulation of the ring's polygon, the triangulation that
//        maximises the smallest angle being found by dynamic programming
//        over the polygon's sub-chains (Shewchuk, "Two discrete optimization
//        algorithms for the topological improvement of tetrahedral meshes",
//        2002). A ring of three is the 3-2 flip, of four the 4-4 flip;
//      - the 2-3 flip across each of its four faces: the tetrahedron and
//        its neighbour become three tetrahedra around the edge joining
//        their far corners, which must cross the shared triangle;
//   3. when no flip improves on its own (typically because the polygon's
//      triangulation makes a new flat tetrahedron with a free node), the
//      three best flips in turn, each followed by smoothing the free
//      corners of its new tetrahedra (twice round), kept only if the
//      result is better, else undone;
//   4. after a pass that lifts fewer than 5 % of the tetrahedra below the
//      target it found above it, a pass over the neighbours of those whose
//      smallest dihedral angle is below target_min_dihedral_deg (the
//      tetrahedra sharing an edge with each, once for each): 1-3 for them
//      towards twice the target, then 1-3 for the one below it again (a
//      neighbour's flip or move can open one for it);
//   5. for a tetrahedron whose smallest dihedral angle is below
//      target_min_dihedral_deg and that steps 1-3 left there, node
//      insertion: a cavity grown from it, one tetrahedron at a time across
//      the boundary face whose tetrahedron with the new node is worst,
//      through faces of its region on no face set, up to 16 tetrahedra; for
//      each cavity the node is placed at the better of the sliver's
//      centroid and the mean of the cavity's corners and moved by the
//      steepest ascent of step 1, and the best cavity whose corners all
//      stay on its boundary is replaced by the new node joined to that
//      boundary (every new tetrahedron positive: the cavity is star-shaped
//      from the node, and they fill it exactly). This frees a sliver whose
//      four corners are all held (on surfaces and interfaces), which no
//      move and often no flip can lift.
// An operation is taken only when it strictly raises the smallest dihedral
// angle of the tetrahedra it replaces or reshapes (the worst new one better
// than the worst old one) and every new tetrahedron is positively oriented
// (6 V > 1e-12 l^3, l its longest edge): the mesh's smallest angle never
// falls. With the aspect ratio in the quality an operation must also keep
// the smallest dihedral angle of what it touches at or above the lower of
// what it was and target_min_dihedral_deg (else it would trade a sliver
// for a better aspect ratio nearby), so the mesh's smallest angle never
// falls below the lower of its value and that target. Passes stop when
// none is left below the target, when a pass of the fourth kind changes
// nothing or lifts fewer than 5 % of those it found, or after max_passes.
// A tetrahedron on which steps 1-3 changed nothing is not tried again
// until something around its corners changes.
//
// What never changes, so that every region keeps its geometry and every
// face set its triangles:
//   - a flip stays inside one region (all tetrahedra it replaces in the
//     same element_region), on an interior edge or face, and never removes
//     a face of a face set: the replaced tetrahedra's outer faces are
//     exactly the new tetrahedra's, so each region is the same point set;
//   - a node moves only when it touches no face set triangle and no
//     boundary face and all its tetrahedra lie in one region (within the
//     polyhedron they fill, which stays filled);
//   - node indices (Mesh::nodes is only written at the moving nodes; an
//     inserted node is appended, strictly inside one region and on no face
//     set), face sets (triangles, orientation, nodes) and region names.
// Element indices do change: tetrahedra are removed and added, new ones
// taking the places of removed ones or following the survivors, which keep
// their order.
//
// What it cannot do: a sliver whose smallest angle lies between two faces
// that are both face set triangles (or boundary faces, or faces against
// another region) is the whole of its region's wedge at that edge, and no
// conforming mesh of the same face sets does better there; a sliver with all
// four corners held whose every flip would cross a face set or another
// region, or make a flat tetrahedron no free node can lift (no search over
// sequences of flips is made), and whose every cavity within its region
// swallows a corner or leaves a tetrahedron no better than it, also stays.
// Those around a very short edge on a surface or an interface need the
// surface itself changed: CollapseShortEdges (mesh/collapse.h).
#pragma once

#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

struct ImproveOptions {
  // A tetrahedron is worked on while its smallest dihedral angle is below
  // this [degrees], in (0, 70.5) (a regular tetrahedron's is 70.53).
  double target_min_dihedral_deg = 10;
  // And, when not 0, while its aspect ratio (TetAspectRatio,
  // mesh/quality.h) is above this, >= 1.5. The quality every operation
  // must then raise is TetMeasure's min(1 / A, theta / (theta_t A_t)), so a
  // needle or a cap with good dihedral angles but a large aspect ratio is
  // worked on too, and a sliver still is; 0: the smallest dihedral angle
  // alone, as described above.
  double target_aspect_ratio = 0;
  // Passes over the tetrahedra below the target; >= 0 (0: only measure).
  int max_passes = 5;
  // Largest ring of tetrahedra around an edge that edge removal replaces,
  // 3..10; the dynamic programme costs O(m^3) quality evaluations.
  int max_ring_size = 7;
  // Move nodes that no face set, boundary face or region interface holds
  // (steps 1 and 3 above).
  bool smooth = true;
  // Try flips (steps 2 and 3).
  bool flip = true;
  // Insert nodes (step 5).
  bool insert = true;
};

struct ImproveStats {
  int flips_23 = 0;
  int flips_32 = 0;        // edge removal, ring of 3
  int flips_44 = 0;        // edge removal, ring of 4
  int edge_removals = 0;   // edge removal, ring of 5 or more
  int smoothed_nodes = 0;  // node moves kept (a node may move more than once)
  // Flips (counted above too) taken only together with moving the free
  // corners of their new tetrahedra, having made things worse on their own.
  int smoothed_flips = 0;
  int inserted_nodes = 0;  // node insertions (one new node each)
  int passes = 0;          // passes made (each over the tetrahedra then below the target)
  // Smallest dihedral angle over all tetrahedra [degrees], and how many
  // tetrahedra lie below the target, before and after.
  double min_dihedral_before_deg = 0;
  double min_dihedral_after_deg = 0;
  int below_target_before = 0;
  int below_target_after = 0;
  // Largest aspect ratio over all tetrahedra, before and after.
  double max_aspect_ratio_before = 0;
  double max_aspect_ratio_after = 0;
};

// Adds a later pass's counts to `total`, whose "after" figures become the
// later pass's (its "before" ones stay those of the first pass).
void AddLaterPass(const ImproveStats& later, ImproveStats* total);

// Improves `mesh` in place (see above); `stats` may be null. A mesh with no
// tetrahedron below the target comes back unchanged.
//
// Errors (the mesh is then untouched): InvalidArgument "mesh" for a null
// mesh or a quadratic or hexahedral one; "mesh.tets" for a node index out
// of range, an inverted tetrahedron (negative volume) or a face shared by
// more than two tetrahedra; "mesh.face_sets" for a face set node out of
// range; "mesh.element_region" when it is neither empty nor one entry per
// tetrahedron; the option's name for a bad option.
Status ImproveTetMesh(const ImproveOptions& options, Mesh* mesh, ImproveStats* stats);

}  // namespace pba
