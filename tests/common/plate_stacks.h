// Plate stacks painted by a function, for the atlas tests (loft, geometric
// validation): no files, exact labels.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "atlas/plates.h"

namespace pba::testing {

// A stack of `z_mm.size()` plates of width x height pixels of `pixel` mm
// centred on (0, 0), pixel (c, r) at (origin.x + c pixel, origin.y - r
// pixel); pixel (c, r) of plate p is labelled paint(p, x, y, z) at its
// centre. No colour table.
inline PlateStack PaintPlateStack(
    double pixel, int width, int height, const std::vector<double>& z_mm,
    const std::function<uint16_t(int plate, double x, double y, double z)>& paint) {
  PlateStack stack;
  stack.pixel_size_mm = pixel;
  stack.width = width;
  stack.height = height;
  stack.origin_mm = Eigen::Vector2d(-0.5 * (width - 1) * pixel, 0.5 * (height - 1) * pixel);
  stack.z_mm = z_mm;
  for (int p = 0; p < stack.num_plates(); ++p) {
    std::vector<uint16_t> labels(static_cast<size_t>(width) * height);
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const Eigen::Vector3d x = stack.PixelCentreMm(p, c, r);
        labels[static_cast<size_t>(r) * width + c] = paint(p, x.x(), x.y(), x.z());
      }
    }
    stack.labels.push_back(std::move(labels));
    stack.files.push_back("plate");
  }
  return stack;
}

}  // namespace pba::testing
