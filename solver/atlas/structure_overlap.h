// How much two structures overlap: the check a commit gets against the
// neighbours others hold locked (the atlas store's editing rule: no one may
// grow into a structure someone else is working on). Both geometries, in
// any form a structure set takes (contours, a NIfTI mask, a closed
// surface), are voxelised on one grid of cubic voxels, as
// ComposeStructureSet does with force_volume: a mask by its non-zero
// voxels, a surface by its inside, contours by their loft.
#pragma once

#include <filesystem>
#include <string>

#include "atlas/structure_set.h"
#include "pba/status.h"

namespace pba {

struct StructureGeometry {
  StructureFormat format = StructureFormat::kContours;
  std::filesystem::path file;
};

struct OverlapMeasure {
  double a_mm3 = 0, b_mm3 = 0;  // each structure's volume at this voxel size
  double overlap_mm3 = 0;       // the voxels both claim
  double voxel_mm = 0;
  // The overlap as a fraction of the smaller of the two volumes (0 when
  // either is empty).
  double fraction_of_smaller() const;
};

// Measures the overlap of `a` and `b` on voxels of `voxel_mm` [mm]. The files
// are read (not changed); a scratch directory under the system's temporary
// directory is used and removed. Errors: a file that does not parse as its
// format (kInvalidArgument, naming "a" or "b"), kIo.
Status MeasureOverlap(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                      OverlapMeasure* measure);

}  // namespace pba
