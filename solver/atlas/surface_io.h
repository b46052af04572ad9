// Closed triangulated surfaces as a structure travels in them (structure
// sets, atlas store uploads): binary or ASCII STL, OBJ (v and f lines,
// polygons fanned into triangles) and ASCII legacy VTK POLYDATA (POINTS and
// POLYGONS). Coordinates are millimetres in the atlas frame.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "atlas/structure_set.h"
#include "pba/status.h"

namespace pba {

struct TriangleSurface {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<int, 3>> triangles;  // point indices
};

// Parses `content` in `format` (kStl, kObj or kVtk; the others are an
// error), welds points with identical coordinates (STL repeats them per
// triangle), and checks that it can bound a structure: at least four
// triangles, every point finite and within kMaxAtlasCoordinateMm of the
// origin, every edge shared by exactly two triangles (closed and
// manifold), a non-zero enclosed volume. Errors are kInvalidArgument on
// `field`, the message starting with the format ("STL: ...").
Status ReadSurface(std::string_view content, StructureFormat format, const std::string& field,
                   TriangleSurface* surface);

// The signed volume the triangles enclose [mm^3]: positive when they face
// outwards.
double EnclosedVolume(const TriangleSurface& surface);

}  // namespace pba
