// Conforming multi-material tetrahedral meshes of a labelled body, by
// Delaunay refinement (CGAL Mesh_3; Jamin, Alliez, Yvinec & Boissonnat,
// "CGALmesh: a generic framework for Delaunay mesh generation", ACM TOMS 41,
// 2015). The body is given by a labelling function: region k's points are
// those where it returns k (1, 2, ...), 0 outside. Every region gets its own
// tetrahedra, and the interfaces between regions are meshed once, shared by
// the tetrahedra on both sides, so neighbouring structures of the atlas are
// joined node to node.
//
// Only label_mesher.cc includes CGAL: it is heavy to compile and needs
// -frounding-math, which the rest of the solver does without.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

// The region label at a point [mm]: 0 outside the body, k >= 1 inside region
// k (region_names[k - 1]). Called many times, from one thread; it must be
// deterministic for the mesh to be.
using LabelFunction = std::function<int(const Eigen::Vector3d& x_mm)>;

struct LabelMeshOptions {
  // Bounding box of the labelled body [mm]; the function is only sampled
  // inside it, and a region touching its faces is cut off there.
  Eigen::Vector3d box_min_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d box_max_mm = Eigen::Vector3d::Zero();
  // Upper bound on the circumradius of a tetrahedron [mm], so roughly the
  // edge length inside the regions; > 0.
  double cell_size_mm = 0;
  // Upper bound on the radius of the surface Delaunay balls of the surface
  // and interface triangles [mm] (about their circumradius); 0: cell_size_mm.
  double facet_size_mm = 0;
  // Upper bound on the distance between a surface triangle's circumcentre
  // and the centre of its surface Delaunay ball, a point of the true surface
  // [mm]: how far the triangles may stray from the surface; 0: a tenth of
  // the facet size.
  double facet_distance_mm = 0;
  // Lower bound on the angles of the surface triangles [degrees], <= 30
  // (Delaunay refinement terminates only up to 30).
  double facet_angle_deg = 25;
  // Upper bound on a tetrahedron's circumradius over its shortest edge,
  // >= 2 (refinement terminates only above 2). Does not remove slivers; the
  // perturbation and exudation below do.
  double cell_radius_edge_ratio = 3;
  // Accuracy of the surface points found by bisection between labels,
  // relative to the bounding box's diagonal.
  double relative_error_bound = 1e-6;
  // Sliver removal after refinement, both aiming at a smallest dihedral
  // angle of `sliver_bound_deg` in every tetrahedron: perturbation moves
  // vertices (pseudo-random, deterministically seeded), exudation then gives
  // them weights, which reshapes the tetrahedra around the remaining slivers.
  // Each stops when every tetrahedron is above the bound, when no move helps
  // or at `optimisation_time_limit_s`. Without the limit either can run for
  // minutes (CGAL 5.5's exuder on the nested spheres at 5 mm cells); when it
  // is reached, the result depends on the machine's speed and load, and is
  // no longer reproducible. Slivers with all four corners on a surface may
  // remain.
  bool perturb = true;
  bool exude = true;
  double sliver_bound_deg = 12;
  double optimisation_time_limit_s = 20;  // per step; 0: no limit
  // Global optimisation before the sliver removal: passes of optimal
  // Delaunay triangulation smoothing (ODT; Alliez, Cohen-Steiner, Yvinec &
  // Desbrun, SIGGRAPH 2005) or of Lloyd smoothing, which move the vertices,
  // those on surfaces along them, towards better-shaped tetrahedra. Each pass
  // costs about as much as the refinement; 0: none. A fixed count, not a
  // time limit, so the result does not depend on the machine (the time
  // limit above still applies as a safeguard). Two ODT passes lift the
  // synthetic atlas's worst angles, the ones between surface vertices that
  // perturbation and exudation cannot reach (docs/atlas.md).
  int odt_iterations = 0;
  int lloyd_iterations = 0;
  // Region of interest (off when radius_mm is 0): within radius_mm of
  // centre_mm cells and facets are at most roi_size_mm; beyond it the bound
  // grows linearly with the distance from the sphere, reaching cell_size_mm
  // (facet_size_mm) a further `transition_mm` out (0: radius_mm), and
  // stays there. Refined where a scene acts, coarse where it does not.
  Eigen::Vector3d roi_centre_mm = Eigen::Vector3d::Zero();
  double roi_radius_mm = 0;
  double roi_size_mm = 0;
  double roi_transition_mm = 0;
  // Per region (empty, or one entry per region name): an upper bound on the
  // facet size [mm] of the region's surfaces and interfaces, 0 for none. An
  // interface takes the smaller bound of its two regions, and its facet
  // distance bound shrinks in the same proportion as its facet size. Small
  // structures need smaller triangles than the bulk to keep their shape.
  std::vector<double> region_facet_size_mm;
  // Per region (empty, or one entry per region name): an upper bound on the
  // cell size [mm] inside the region, 0 for none. A small structure meshed
  // with small facets but the global cells gets tetrahedra stretched
  // between the two sizes; bounding its cells as well keeps them shaped.
  std::vector<double> region_cell_size_mm;
  // Points known to lie inside a region [mm], e.g. one per connected piece
  // of each region: the surfaces around each are seeded where the label
  // first changes along the six axis directions from it, so that a region
  // smaller than the seeding grid (see MeshLabels) is not missed. Points
  // outside every region (label 0) are ignored.
  std::vector<Eigen::Vector3d> interior_points_mm;
  // Seed of CGAL's random surface sampling, used only when the grid seeding
  // (see MeshLabels) finds too few points; the same inputs and seed give the
  // same mesh (unless a time limit is reached).
  unsigned seed = 0;
};

// What MeshLabels did: the time of each step [s] and the optimisation
// steps that stopped at optimisation_time_limit_s (their result depends on
// the machine's speed and load, so the mesh is not reproducible).
struct LabelMeshReport {
  double seed_s = 0, refine_s = 0, odt_s = 0, lloyd_s = 0, perturb_s = 0, exude_s = 0;
  std::vector<std::string> time_limit_reached;  // "odt", "lloyd", "perturb", "exude"
};

// Meshes the regions of `label` inside the box. On success `mesh` holds:
//   nodes   the vertices of the tetrahedra, in metres (input is in mm);
//           vertices of the refinement used by no tetrahedron are dropped;
//   tets    positively oriented 4-node tetrahedra;
//   region_names = `region_names`, element_region[e] = label - 1;
//   face_sets
//     "surface"                the boundary triangles (a region against the
//                              outside), numbered anticlockwise seen from
//                              outside the body;
//     "interface:<a>|<b>"      the triangles between regions a and b
//                              (names, a's label < b's), anticlockwise seen
//                              from b, i.e. the normal points from a into b;
//     "surface:<a>"            the whole boundary of region a (against the
//                              outside and against other regions),
//                              anticlockwise seen from outside a; absent
//                              for a region that got no tetrahedron.
//
// Every surface is seeded where the label changes between the points of a
// grid of spacing about the facet size over the box (CGAL's own random
// seeding can miss a surface hidden behind another, and refinement never
// finds a surface without a seed), and from the interior points given. A
// region missed by that grid, thinner than the facet size, with no interior
// point, may therefore be missing from the mesh.
//
// Errors: InvalidArgument naming the field for bad options (sizes <= 0, an
// empty or inverted box, no region names, a facet angle outside (0, 30], a
// radius-edge ratio below 2, a sliver bound outside (0, 70.5), a region of
// interest with a negative radius or transition, or a size not in
// (0, cell size], a region size list of the wrong length or with an entry
// negative or not finite);
// InvalidArgument "region_names" for a label the function returns that has
// no name, "label" for a negative label or no function; FailedPrecondition
// when no region is found (the function is 0 at every grid point, or no
// tetrahedron ends up inside a region); Internal for a failure inside CGAL
// (no exception escapes). The function is only called from the calling
// thread; the result is deterministic for a deterministic function.
//
Status MeshLabels(const LabelFunction& label, const std::vector<std::string>& region_names,
                  const LabelMeshOptions& options, Mesh* mesh, LabelMeshReport* report = nullptr);

}  // namespace pba
