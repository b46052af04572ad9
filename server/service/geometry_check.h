// The minimal check of uploaded geometry before it becomes a revision, by
// format. What is checked:
//   contours_json  the solver's ParseContoursJson (atlas/contours.h):
//                  plates at distinct heights, each with polygons of at
//                  least three points and non-zero area, coordinates in mm
//                  within 500 mm of the origin, pixel_size_mm in (0, 10]
//   nifti          a NIfTI-1 header: sizeof_hdr 348 (either byte order) and
//                  magic "n+1" (gzip-compressed files inflated; "ni1", a
//                  header whose data is in a separate .img, is refused);
//                  then the data through the solver's ReadNifti: integer
//                  values, not truncated, at least one voxel non-zero, the
//                  non-zero voxels' centres within 500 mm of the origin
//   stl, obj, vtk  the solver's ReadSurface (atlas/surface_io.h): a closed
//                  surface, binary or ASCII STL, OBJ (v and f), ASCII
//                  legacy VTK POLYDATA; at least four triangles, every
//                  edge shared by exactly two, a non-zero enclosed volume,
//                  points within 500 mm of the origin
//   derived        the recipe of a derived structure (atlas/derived_structure.h):
//                  one merge, fill or cut as YAML, no mask file; the
//                  structures it reads are checked against the project
//                  apart (derived_check.h)
// The same readers compose a structure set (atlas/structure_set.h), so what
// passes here can be meshed.
// Overlap with neighbours others hold locked is checked apart
// (overlap_check.h). Not checked: self-intersecting polygons and surfaces.
//
// The check runs in a child process under `limits` (bounded_child.h): the
// readers refuse sizes a header announces but the file does not hold, and
// the child's address-space and wall-time limits catch whatever they miss.
// Past a limit the answer is kInvalidArgument ("the nifti file needs more
// than 1024 MiB to check", "... took longer than 30 s to check"). No
// temporary file outlives the check.
#pragma once

#include <string_view>

#include "pba/status.h"
#include "service/bounded_child.h"
#include "store/atlas_types.h"

namespace pba {

// kInvalidArgument (field `field`) saying what is wrong.
Status CheckGeometryContent(std::string_view field, StructureFormat format,
                            std::string_view content, const ChildLimits& limits = {});

}  // namespace pba
