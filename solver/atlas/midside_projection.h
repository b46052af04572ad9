// Curving a 10-node atlas mesh onto the loft's surfaces. MakeQuadratic
// (without a projection) puts the mid-edge nodes at the middles of the
// straight edges, inside a convex surface and outside a concave one. Here
// each mid-edge node of a triangle of "surface" or "interface:<a>|<b>"
// moves onto the zero level of the function that
// separates the two sides there:
//   interface a|b   phi = m_A - m_B,
//   surface         phi = d_fg                 (every label kept)
//                   phi = max(d_fg, m_K - m_D) (some labels dropped),
// with d the loft's signed distances (LoftField::SignedDistance, negative
// inside), m_S = min over the labels of S of d_l, A and B the labels of
// regions a and b (one label, or for a region standing for several, as
// "Surrounding tissue" does, all of them), K the labels of every region
// and D the others, which are outside the body. phi = 0 is where
// LoftField::Label changes from one side to the other (the smallest d
// switches from A to B; the foreground ends, or a dropped label takes
// over).
//
// Method: Newton steps from the midpoint, x <- x - J^+ phi, with J the
// gradients of the node's constraints (one per face set holding it: two on
// the rim of an interface at the outer surface, three where three regions
// meet, of which two are independent), by central differences, and J^+ the
// least-squares pseudo-inverse (SVD, so dependent constraints are fine).
// A node stays at its midpoint when a phi is not finite there (outside a
// label's field), when it moves more than max_move_fraction of its edge
// from the midpoint or when the steps do not converge.
//
// Then the elements are checked: one with a moved node whose Jacobian
// ratio (mesh/quality.h Tet10MaxJacobianRatio: max det J / min det J over
// its corners and 4 stiffness points) is above max_jacobian_ratio, or that
// is inverted at one of those points, has the moves of its nodes halved,
// up to `halvings` times, then undone (the nodes back at their midpoints);
// repeated for the elements those nodes touch until no element fails. An
// element with every mid-edge node at its midpoint has ratio 1, so this
// ends. Halving first keeps part of the curvature where the full move
// would invert a flat element at the surface: on the synthetic atlas at
// 3 mm a fifth of the full moves fail the check, nearly all by inverting
// an element at a corner (docs/atlas.md).
#pragma once

#include <cstdint>
#include <vector>

#include "atlas/loft.h"
#include "mesh/mesh.h"

namespace pba {

struct MidsideProjectionOptions {
  // Largest move from the midpoint, over the edge's length [-].
  double max_move_fraction = 0.25;
  // Largest Jacobian ratio accepted [-]: 40, the limit the PBA thesis
  // accepts for its 10-node atlas meshes (mesh/quality.h).
  double max_jacobian_ratio = 40;
  // Newton steps per node, and the accuracy they stop at: every |phi| /
  // |grad phi| (about the distance to the level set) below tolerance_mm.
  int max_iterations = 20;
  double tolerance_mm = 1e-4;
  // Halvings of a move before the element check undoes it; 0: undone at
  // once.
  int halvings = 2;
  // Step of the central differences [mm]. The fields are piecewise bilinear
  // on the pixel grid and linear in z between plates, and float (about
  // 1e-6 mm of resolution), so a step far below a pixel is exact within a
  // piece.
  double difference_step_mm = 0.01;
};

// Distances of the boundary mid-edge nodes from their level sets [mm] (to
// first order: the largest |phi| / |grad phi| of a node's constraints).
// The mean is dominated by the nodes left at their midpoints where the
// level set is far or flat (|grad phi| near 0: an interface the voxels have
// and the smooth loft has not); the median and 90th percentile are the
// typical distances.
struct GapStats {
  double mean_mm = 0, median_mm = 0, p90_mm = 0;
};

struct MidsideProjectionReport {
  int64_t boundary_nodes = 0;  // mid-edge nodes on surface and interface triangles
  int64_t projected = 0;       // on the level set
  int64_t shortened = 0;       // moved part of the way (moves halved by the element check)
  int64_t reset = 0;           // moved, then put back at the midpoint by the element check
  int64_t unprojected = 0;     // left at the midpoint: no convergence within the bound
  double max_move_mm = 0;      // largest distance of a node from its midpoint
  double mean_move_mm = 0;     // over the projected and shortened nodes
  // The boundary mid-edge nodes' distances from their level sets at the
  // midpoints and after the projection (where the fields are defined).
  GapStats gap_midpoints_mm;
  GapStats gap_mm;
  int check_passes = 0;  // rounds of the element check
};

// Projects the boundary mid-edge nodes of `mesh` (quadratic, from MeshLabels
// and MakeQuadratic; nodes in metres) onto `loft`'s level sets.
// region_labels[r] are the loft labels region r (mesh->region_names[r])
// stands for, one entry per region; labels in no region are outside the
// body. Face sets other than "surface" and the interfaces between the
// mesh's regions are left alone, and so are corners and interior mid-edge
// nodes. A linear mesh, or a count of label sets other than the regions',
// is a broken invariant (abort).
//
// Done here rather than through MakeQuadratic's MidsideProjection, which
// sees a node's position and one face set at a time: the move is bounded by
// the edge's length, and a node on two face sets (the rim of an interface
// at the outer surface) must meet both constraints at once.
MidsideProjectionReport ProjectMidsideNodes(const LoftField& loft,
                                            const std::vector<std::vector<int>>& region_labels,
                                            const MidsideProjectionOptions& options, Mesh* mesh);

}  // namespace pba
