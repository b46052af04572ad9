// Geometric validation of a region-labelled tetrahedral mesh against the
// atlas plates it was built from (the physics-based brain atlas thesis,
// section 4.8.1 and Table 4-3): the mesh is cut at each plate's height and
// each structure's cross-section is compared with its contour on the plate.
//
// Section. At plate i (height z_i [mm]) the mesh is rasterised onto the
// plate's own pixel grid: pixel centre (x, y, z_i) takes the colour-table
// label of the region of the tetrahedron containing it (barycentric
// coordinates all >= -1e-9, so a centre on a shared face or edge is never
// lost; which of the neighbours wins there is unspecified), 0 if none. A
// 10-node mesh is cut through its corner tetrahedra (straight edges; the
// mid-edge nodes are ignored). Only tetrahedra whose z-range spans z_i are
// visited, and each only over the pixels of its x-y bounding box. Mesh
// nodes are in metres, plates in millimetres.
//
// Landmarks. On a label image, the boundary pixels of label l are the
// pixels of l with a 4-neighbour of another label (outside the image
// counts as background 0). The plate's boundary pixels of l are the
// landmarks; distances are between pixel centres, by an exact 2-D
// Euclidean distance transform (atlas/distance_transform.h), in mm.
//
// Sectional error e_i of structure l on plate i, for every plate where l
// appears on the plate or in the section (pixel-centre distances, mm):
//   both present:  e_i = (d(P -> S) + d(S -> P)) / 2, where d(P -> S) is the
//                  mean over the plate's boundary pixels of the distance to
//                  the nearest boundary pixel of the section, and d(S -> P)
//                  the same the other way. The thesis measures from the
//                  plate's landmarks only; averaging both directions makes
//                  e_i symmetric, so a spurious piece of l in the section
//                  far from the plate's contour is penalised as much as a
//                  missing piece.
//   plate only:    e_i = the mean distance of the plate's boundary pixels to
//                  the centroid of their own 8-connected piece of l on the
//                  plate, i.e. the error of a section in which every piece
//                  has shrunk to its centre (each piece's mean radius; the
//                  loft tapers a structure that ends between plates to a
//                  point the same way). The mesh lost the structure here;
//                  the penalty grows with its size. Per piece, because a
//                  bilateral structure's overall centroid lies on the
//                  midline, far from both of its pieces.
//   section only:  the same with the roles swapped: the section's boundary
//                  pixels to the centroids of their pieces of l in the
//                  section.
// (With l on both, a piece missing on one side is measured to the nearest
// contour of the other, as any landmark.)
//
// Perimeter P_i [mm]: the length of the marching-squares contour of the
// 0/1 image of l on the plate (isovalue 1/2 between pixel centres, with
// outside the image background): straight across a cell with two
// neighbouring pixels in, a diagonal of length h/sqrt(2) across a corner,
// h the pixel size. Along a straight contour at angle theta (0 to 45
// degrees) to the grid it measures cos(theta) + (sqrt(2) - 1) sin(theta)
// times the true length, 5.5 % too long averaged over directions (a
// circle), where the count of boundary pixel edges times h is 4/pi, 27 %,
// too long. For a section-only plate, P_i is the
// section's perimeter, so a spurious piece weighs as much as its contour.
//
// Per structure, over its N sections (thesis eqs. 4.2 and 4.3):
//   E    = sum_i P_i e_i / sum_i P_i                  [mm]
//   %Err = E N / sum_i P_i * 100                      (= E / mean P_i, in %)
//   flagged when %Err > kGeometricErrorLimitPercent (0.65).
// Overall: every structure's sections pooled, the same two equations over
// the pooled sums (E_all = sum P e / sum P over all sections, %Err_all =
// E_all N_all / sum P * 100 with N_all the total number of sections): the
// perimeter-weighted error of the whole atlas relative to its mean contour
// length.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "atlas/colour_table.h"
#include "atlas/plates.h"
#include "atlas/report_format.h"
#include "core/thread_context.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

// The thesis's acceptance limit for %Err (section 4.8.1).
inline constexpr double kGeometricErrorLimitPercent = 0.65;

struct SectionError {
  int plate = 0;                // index into the plate stack
  double z_mm = 0;              // plate height [mm]
  double perimeter_mm = 0;      // P_i [mm]
  double mean_distance_mm = 0;  // e_i [mm]
  int landmarks = 0;            // boundary pixels of the structure on the plate
  int section_landmarks = 0;    // boundary pixels of the structure in the section
  bool in_plate = false;        // the structure appears on the plate
  bool in_section = false;      // the structure appears in the mesh section
};

struct StructureValidation {
  std::string name;  // from the plates' colour table, else "label <n>"
  uint16_t label = 0;
  std::vector<SectionError> sections;  // by plate, bottom first
  double structural_error_mm = 0;      // E, eq. 4.2 [mm]
  double percentage_error = 0;         // %Err, eq. 4.3 [%]
  bool flagged = false;                // percentage_error > 0.65
};

struct GeometricValidation {
  // Every label on any plate or of any mesh region, by label.
  std::vector<StructureValidation> structures;
  int total_sections = 0;                  // N_all
  double overall_structural_error_mm = 0;  // E_all [mm]
  double overall_percentage_error = 0;     // %Err_all [%]
  bool overall_flagged = false;            // overall_percentage_error > 0.65
};

// region_label[r]: the colour-table label of mesh region r, for every
// region of mesh.region_names, from the names (ColourTable::FindByName).
// A name not in the table is an error naming it.
Status RegionLabelsFromNames(const Mesh& mesh, const ColourTable& colours,
                             std::vector<uint16_t>* region_label);

// Checks a region-labelled tetrahedral mesh before it is cut: tetrahedra
// (else "mesh", saying that `what` cuts tetrahedra), at least one,
// element_region empty or one in range per element, one label per region
// (field `labels_field`). Shared by the validation and the pictures.
Status ValidateLabelledTetMesh(const Mesh& mesh, const std::vector<uint16_t>& labels,
                               const std::string& labels_field, const std::string& what);

// Validates `mesh` against `plates` as described above. region_label[r] is
// the colour-table label of region r (for a one-region mesh, with no
// region_names, region_label[0]); label 0 makes a region invisible (as if
// background). Errors (kInvalidArgument naming the field): a hexahedral or
// empty mesh, element_region of the wrong size or out of range,
// region_label of the wrong size, a malformed plate stack. The sections
// are cut on `threads`.
Status ValidateAgainstPlates(const Mesh& mesh, const std::vector<uint16_t>& region_label,
                             const PlateStack& plates, const ThreadContext& threads,
                             GeometricValidation* out);

// The per-structure table: structure, label, sections, E [mm], %Err, flag,
// and an overall footer row (sections N_all, E_all, %Err_all).
ReportTable ValidationReportTable(const GeometricValidation& validation);

// FormatReportTable(ValidationReportTable(validation), format).
std::string FormatValidationTable(const GeometricValidation& validation, TableFormat format);

}  // namespace pba
