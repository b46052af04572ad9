// What changed between two revisions of a structure's geometry: for plate
// contours (contours.h) the volume and how far apart the contours lie at the
// heights both have (Hausdorff and mean distance); for any forms, the two
// shapes compared on voxels.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
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

// The most voxels a shape comparison's grid may hold: 2^23 (203^3), a
// whole brain's box at 1 mm. A comparison costs about 30 bytes and a few
// hundred nanoseconds a voxel (two label volumes, the inside and boundary
// masks, two distance transforms): about 250 MB and a second or two here.
// Past it the voxels are coarsened rather than the diff refused: two 990 mm
// boxes at 1 mm would be 10^9 voxels (tens of GB, minutes).
inline constexpr int64_t kMaxDiffVoxels = int64_t{1} << 23;

// Voxels of edge `voxel_mm` in the grid a comparison of `a` and `b` would
// use: their union's box with the two voxels of margin ComposeStructureSet
// adds on each side. Errors: geometry that does not parse (kInvalidArgument
// on "from"/"to" naming the format's complaint).
Status DiffGridVoxels(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                      std::string_view b, double voxel_mm, double* voxels);

// `voxel_mm`, or the first coarser of 1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8
// times a power of ten times it, whose grid (DiffGridVoxels) holds at most
// `max_voxels`.
Status ChooseDiffVoxel(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                       std::string_view b, double voxel_mm, int64_t max_voxels, double* chosen_mm);

// Two revisions' geometry in any forms compared on voxels (CompareShapes,
// atlas/structure_overlap.h): volumes, the volume they share, Dice, and
// Hausdorff and mean distance between their surfaces. The voxel is
// ChooseDiffVoxel's (at least `voxel_mm`; comparison->overlap.voxel_mm
// says which). The bytes go through a scratch directory under the system's
// temporary one. `cancelled` (may be empty) is asked between the phases
// (sizing, writing, comparing); true gives Status::Cancelled. The
// voxelisation and distance transforms themselves do not look at it: the
// voxel budget bounds them to seconds.
Status CompareRevisionShapes(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                             std::string_view b, double voxel_mm, int64_t max_voxels,
                             const std::function<bool()>& cancelled, ShapeComparison* comparison);

}  // namespace pba
