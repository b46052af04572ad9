// What changed between two revisions of a structure's geometry: for plate
// contours (contours.h) the volume and how far apart the contours lie at the
// heights both have (Hausdorff and mean distance); for any forms, the two
// shapes compared on voxels.
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "atlas/contours.h"
#include "atlas/structure_overlap.h"
#include "pba/status.h"
#include "store/atlas_types.h"

namespace pba {

// Area of a plate's polygons [mm^2]: each polygon's absolute area, summed
// (polygons of one plate are separate pieces of the structure).
double PlateArea(const ContourPlate& plate);

// Each plate's area times its slab: from half-way to the plate below to
// half-way to the plate above; an end plate's slab reaches as far out as it
// reaches in. 0 for a single plate [mm^3].
double ContoursVolume(const Contours& contours);

struct ContoursDistance {
  double hausdorff_mm = 0;
  double mean_mm = 0;
  int plates_compared = 0;
  std::vector<double> only_in_a_z_mm, only_in_b_z_mm;
};

// Distances between the contours of `a` and `b` at the heights both have
// (equal within 1e-6 mm): every polygon edge sampled every `step_mm` (and
// at its ends), each sample's distance to the nearest edge of the other
// revision's plate; the Hausdorff distance is the largest over both
// directions, the mean is over all samples of both.
ContoursDistance DistanceBetween(const Contours& a, const Contours& b, double step_mm = 0.1);

// Two revisions' geometry in any forms compared on `voxel_mm` voxels
// (CompareShapes, atlas/structure_overlap.h): volumes, the volume they
// share, Dice, and Hausdorff and mean distance between their surfaces. The
// bytes go through a scratch directory under the system's temporary one.
Status CompareRevisionShapes(GeometryFormat format_a, std::string_view a, GeometryFormat format_b,
                             std::string_view b, double voxel_mm, ShapeComparison* comparison);

}  // namespace pba
