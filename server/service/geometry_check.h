// The minimal check of uploaded geometry before it becomes a revision, by
// format. What is checked:
//   contours_json  {"plates": [{"z_mm": Z, "polygons": [[[x, y], ...]]}]}:
//                  plates at distinct heights, each with polygons of at
//                  least three points and non-zero area, coordinates in mm
//                  within 500 mm of the origin (geometry_check.cc)
//   nifti          a NIfTI-1 header: sizeof_hdr 348 (either byte order) and
//                  magic "n+1" or "ni1"; gzip-compressed files (.nii.gz) are
//                  inflated just far enough to read the header
//   stl, obj, vtk  non-empty (the store refuses empty geometry anyway)
// What is not checked yet (future work): self-intersecting polygons, the
// NIfTI data block and its labels, that a surface is closed and manifold,
// that it lies within the atlas bounds, and that the new shape does not
// overlap neighbouring structures that others hold locked.
#pragma once

#include <string_view>

#include "pba/status.h"
#include "store/atlas_types.h"

namespace pba {

// kInvalidArgument (field `field`) saying what is wrong.
Status CheckGeometryContent(std::string_view field, GeometryFormat format,
                            std::string_view content);

}  // namespace pba
