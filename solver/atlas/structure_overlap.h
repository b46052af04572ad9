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

// How two revisions of one structure differ in shape, in any forms:
// both voxelised on one grid (each in full, whichever else claims its
// voxels), then their volumes, the volume they share, the Dice coefficient
// 2|A n B| / (|A| + |B|), and the distances between their surfaces (the
// boundary voxels: inside ones with a face-neighbour outside), Hausdorff
// (the largest of either's boundary voxels' distance to the other's) and
// mean (over both), by an exact 3-D Euclidean distance transform
// [voxel-centre distances, mm].
struct ShapeComparison {
  OverlapMeasure overlap;
  double dice = 0;
  double hausdorff_mm = 0;
  double mean_surface_distance_mm = 0;
};

Status CompareShapes(const StructureGeometry& a, const StructureGeometry& b, double voxel_mm,
                     ShapeComparison* comparison);

}  // namespace pba
