// Local refinement of a 4-node tetrahedral mesh by longest-edge bisection
// (Rivara 1991, "Local modification of meshes for adaptive and/or multigrid
// finite-element methods", J. Comput. Appl. Math. 36:79; Rivara & Levin
// 1992 for tetrahedra).
//
// Every marked tetrahedron is cut through the midpoint of its longest edge.
// A cut edge is shared by every element around it, and each of them is cut
// in turn through its own longest edge, until no element has a cut edge
// that is not one of its bisections: the mesh stays conforming without
// hanging nodes, and the refinement spreads only as far as the longest
// edges lead. The result depends only on the set of cut edges, so an
// element's boundary faces are cut exactly as the element is, and the
// face sets follow the elements.
//
// "Longest" is a strict order: squared length, then the edge's node
// indices, so neighbours sharing an edge always agree. Bisecting by the
// longest edge keeps the shapes from degenerating: for triangles the
// smallest angle provably stays above half the coarse one's; for
// tetrahedra no such bound is proven, and refine_test measures the
// smallest dihedral angle over repeated refinement.
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

struct RefineReport {
  int64_t marked = 0;      // elements asked for
  int64_t cut_edges = 0;   // edges given a midpoint (the new nodes)
  int64_t elements = 0;    // in the refined mesh
  int64_t propagated = 0;  // cut edges added to keep the mesh conforming
};

// The mesh with every element e for which marked[e] is non-zero bisected at
// least once; its nodes are the coarse mesh's (same indices, first) and the
// midpoints of the cut edges. Elements keep their region
// (Mesh::element_region), and every face-set triangle is cut as the
// element behind it is (a triangle of no element is cut by the same rule),
// keeping its orientation. Positive orientation is kept.
// InvalidArgument ("mesh") for a mesh that is not 4-node tetrahedral:
// quadratic and hexahedral meshes are refined as their linear corner mesh,
// before the mid-edge nodes are added. InvalidArgument ("marked") when
// `marked` has not one entry per element. `parent`, when given, receives
// the coarse element each refined element lies in.
Status RefineTets(const Mesh& coarse, const std::vector<char>& marked, Mesh* fine,
                  RefineReport* report = nullptr, std::vector<int>* parent = nullptr);

// RefineTets `times` times over, each time bisecting every element that
// lies in a marked coarse element (the others only as the mesh's
// conformity needs): three times halves the marked elements' edges, as one
// uniform refinement would. The report counts the coarse elements marked
// and the final mesh. With `max_elements` > 0 it stops after the first
// pass that passes that many elements (refinement only adds elements, so
// the whole would too): the report's count is then that pass's, above the
// bound, and `fine` is unspecified; memory stays within a pass of it.
Status RefineTetsRepeatedly(const Mesh& coarse, const std::vector<char>& marked, int times,
                            Mesh* fine, RefineReport* report = nullptr, int64_t max_elements = 0);

// Dorfler's bulk criterion: the fewest elements that carry at least
// `fraction` (0..1] of the total of `share` (e.g. the estimated squared
// error of each element), largest first, and with them every element whose
// share ties with the last one taken (within kShareTie, relative): equal
// errors are treated alike whatever their rounding, so a symmetric problem
// keeps a symmetric mesh, and solves that differ only by rounding (one
// process or several, one linear solver or another) refine alike.
inline constexpr double kShareTie = 1e-6;
std::vector<char> MarkLargestShare(const std::vector<double>& share, double fraction);

}  // namespace pba
