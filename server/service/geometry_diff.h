// What changed between two revisions of a structure's plate contours
// (geometry_check.h gives their form): the volume, and how far apart the
// contours lie at the heights both have (Hausdorff and mean distance).
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "pba/status.h"

namespace pba {

struct ContourPlate {
  double z_mm = 0;
  std::vector<std::vector<std::array<double, 2>>> polygons;  // [x_mm, y_mm], closed implicitly
};

// The plates of a contours JSON document, by increasing height; the
// document must pass CheckGeometryContent.
Status ParseContours(std::string_view json, std::vector<ContourPlate>* plates);

// Area of a plate's polygons [mm^2]: each polygon's absolute area, summed
// (polygons of one plate are separate pieces of the structure).
double PlateArea(const ContourPlate& plate);

// Each plate's area times its slab: from half-way to the plate below to
// half-way to the plate above; an end plate's slab reaches as far out as it
// reaches in. 0 for a single plate [mm^3].
double ContoursVolume(const std::vector<ContourPlate>& plates);

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
ContoursDistance DistanceBetween(const std::vector<ContourPlate>& a,
                                 const std::vector<ContourPlate>& b, double step_mm = 0.1);

}  // namespace pba
