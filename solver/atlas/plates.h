// Atlas plates: a label volume rendered as a stack of colour-coded axial
// images, the form the physics-based brain atlas was drawn from (27 plates
// 2-5 mm apart, each structure in its own RGB colour), and the reader the
// plate -> contour -> mesh pipeline starts from.
//
// A plate directory holds
//   plate_01.png ...  8-bit RGB, one per plate, bottom (lowest z) first;
//                     background black; a tEXt chunk "Comment" carries
//                     kSyntheticAtlasNotice;
//   colour_table.csv  the colour table (colour_table.h);
//   plates.json       {"notice", "format": "pba-atlas-plates", "version": 1,
//                     "colour_table", "pixel_size_mm", "origin_mm": [x, y],
//                     "width", "height", "plates": [{"file", "z_mm"}, ...]}.
// Pixel (column c, row r) of every plate is centred at
//   x = origin_mm[0] + c * pixel_size_mm   (columns run to the right, +x)
//   y = origin_mm[1] - r * pixel_size_mm   (row 0 is the most anterior)
// at the plate's height z_mm [mm], coordinates as in synthetic_atlas.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "atlas/colour_table.h"
#include "atlas/label_volume.h"
#include "pba/status.h"

namespace pba {

// The 27 default plate heights [mm]: 3 mm apart from z = -16 to 20 through
// the deep nuclei, 4-5 mm apart above and below; every spacing in [2, 5].
std::vector<double> DefaultPlateHeightsMm();

struct PlateOptions {
  std::vector<double> z_mm = DefaultPlateHeightsMm();  // strictly increasing [mm]
  double pixel_size_mm = 0.5;                          // square pixels [mm]

  // z_mm non-empty, finite and strictly increasing; pixel_size_mm in
  // (0, 10].
  Status Validate() const;
};

struct PlateStack {
  double pixel_size_mm = 0;
  Eigen::Vector2d origin_mm = Eigen::Vector2d::Zero();  // centre of pixel (0, 0): x, y
  int width = 0;                                        // columns
  int height = 0;                                       // rows
  std::vector<double> z_mm;                             // per plate, strictly increasing
  std::vector<std::string> files;                       // per plate, file name in the directory
  // Per plate, width * height labels, row-major from row 0 (label 0 =
  // background).
  std::vector<std::vector<uint16_t>> labels;
  ColourTable colours;

  int num_plates() const { return static_cast<int>(z_mm.size()); }
  uint16_t at(int plate, int column, int row) const {
    return labels[plate][static_cast<size_t>(row) * width + column];
  }
  // Centre of pixel (column, row) on plate `plate` [mm].
  Eigen::Vector3d PixelCentreMm(int plate, int column, int row) const {
    return {origin_mm.x() + column * pixel_size_mm, origin_mm.y() - row * pixel_size_mm,
            z_mm[plate]};
  }
};

// Checks a stack's shape, naming the bad field under `name` (e.g.
// "stack.z_mm[3]"): at least `min_plates` plates, a positive pixel size, at
// least one pixel, a finite origin, one label image of width x height per
// plate, finite and strictly increasing heights.
Status ValidatePlateStack(const PlateStack& stack, const std::string& name, int min_plates);

// Renders the plates of `volume` into the new directory `dir` (it must not
// exist, or be empty). The pixel grid spans the volume's x-y extent (voxel
// faces, not centres); each pixel takes the label of the voxel nearest to
// its centre (LabelVolume::SampleNearest), coloured from `colours`. A
// label with no colour is an error. Atomic: everything is written into a
// temporary directory beside `dir` and renamed; on failure nothing is left.
Status WritePlates(const LabelVolume& volume, const ColourTable& colours,
                   const PlateOptions& options, const std::filesystem::path& dir);

// Reads a plate directory. Errors name the file: a missing or malformed
// file, a plate whose size differs from width x height, a z_mm not above
// the previous plate's, a pixel colour not in the colour table (with the
// pixel's column, row and RGB). Any positive spacing is accepted.
Status ReadPlates(const std::filesystem::path& dir, PlateStack* stack);

// A plate directory's colour table alone (its index and table file read,
// no plate decoded), with ReadPlates's errors for those two files.
Status ReadPlateColours(const std::filesystem::path& dir, ColourTable* colours);

}  // namespace pba
