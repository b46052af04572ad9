// Plate contours: one structure as it is drawn on atlas plates, its outline
// on each plate as polygons - the editable form of a structure whose atlas
// came from plates (GeometryFormat CONTOURS_JSON of the atlas store).
//
// JSON form (ParseContoursJson / FormatContoursJson):
//   {"format": "pba-contours", "version": 1,   (both optional on input)
//    "pixel_size_mm": 0.5,                     (optional: the pixel grid the
//                                               outline was traced on, a hint
//                                               for rasterising it back)
//    "plates": [{"z_mm": Z, "polygons": [[[x_mm, y_mm], ...], ...]}, ...]}
// Coordinates in mm in the atlas frame (plates.h). A polygon is closed by
// its last point joining its first. A point of a plate is inside the
// structure when a ray from it crosses that plate's polygons an odd number
// of times (even-odd rule: a polygon inside another is a hole). Other keys
// are allowed (comments, provenance) and ignored.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "atlas/plates.h"
#include "pba/status.h"

namespace pba {

// Coordinates farther than this from the atlas origin are refused: an atlas
// spans at most a metre, so such a value is a unit mistake (metres,
// micrometres) or garbage.
inline constexpr double kMaxAtlasCoordinateMm = 500;

struct ContourPlate {
  double z_mm = 0;
  std::vector<std::vector<Eigen::Vector2d>> polygons;  // x, y [mm]
};

struct Contours {
  // The pixel edge the outline was traced on [mm]; 0: not known.
  double pixel_size_mm = 0;
  std::vector<ContourPlate> plates;  // by increasing z_mm
};

// Parses and checks the JSON form: an object with a non-empty "plates"
// list; plates at distinct heights (sorted by height in the result); each
// with at least one polygon of at least three points and non-zero area;
// every coordinate a finite number within kMaxAtlasCoordinateMm of the
// origin; pixel_size_mm, when given, in (0, 10]. Errors are
// kInvalidArgument on `field` with a message "contours JSON: <where>:
// <what>", <where> a path such as plates[2].polygons[0][5].
Status ParseContoursJson(std::string_view text, const std::string& field, Contours* contours);

// The JSON form, with "format" and "version"; numbers printed so that they
// parse back to the same doubles.
std::string FormatContoursJson(const Contours& contours);

// The plate's polygons drawn onto a pixel grid laid out as a PlateStack's
// (plates.h: pixel (c, r) centred at x = origin.x + c * pixel_mm,
// y = origin.y - r * pixel_mm; `labels` row-major, width * height): every
// pixel whose centre is inside by the even-odd rule is set to `label`,
// the others are left as they are.
void RasterizeContourPlate(const ContourPlate& plate, const Eigen::Vector2d& origin_mm,
                           double pixel_mm, int width, int height, uint16_t label,
                           std::vector<uint16_t>* labels);

// The outline of the pixels of `label` on one plate of `stack`: closed
// polygons along the pixel faces (outer boundaries and holes), runs of
// collinear points merged. Rasterised back onto the same grid it gives
// exactly those pixels. An empty plate (no polygons) where the label is
// absent.
ContourPlate TraceContourPlate(const PlateStack& stack, int plate, uint16_t label);

// TraceContourPlate on every plate the label is on; pixel_size_mm the
// stack's. No plates when the label is on none.
Contours TraceContours(const PlateStack& stack, uint16_t label);

}  // namespace pba
