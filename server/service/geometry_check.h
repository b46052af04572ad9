// The minimal check of uploaded geometry before it becomes a revision, by
// format. What is checked:
//   contours_json  {"plates": [{"z_mm": Z, "polygons": [[[x, y], ...]]}]}:
//                  plates at distinct heights, each with polygons of at
//                  least three points and non-zero area, coordinates in mm
//                  within 500 mm of the origin (geometry_check.cc)
//   nifti          a NIfTI-1 header: sizeof_hdr 348 (either byte order) and
//                  magic "n+1" or "ni1"; gzip-compressed files (.nii.gz) are
//                  inflated just far enough to read the header
//   stl, obj, vtk  a closed surface: binary or ASCII STL, OBJ (v and f),
//                  ASCII legacy VTK POLYDATA; points welded by coordinates;
//                  at least four triangles, every edge shared by exactly
//                  two, a non-zero enclosed volume, points within 500 mm
//                  of the origin
// What is not checked yet (future work): self-intersecting polygons and
// surfaces, the NIfTI data block and its labels, that a shape lies within
// the atlas's own bounds, and that it does not overlap neighbouring
// structures that others hold locked.
#pragma once

#include <string_view>

#include "pba/status.h"
#include "store/atlas_types.h"

namespace pba {

// kInvalidArgument (field `field`) saying what is wrong.
Status CheckGeometryContent(std::string_view field, GeometryFormat format,
                            std::string_view content);

}  // namespace pba
