// Exact 2-D Euclidean distance transform of a binary image (Felzenszwalb &
// Huttenlocher, "Distance transforms of sampled functions", Theory of
// Computing 8, 2012): the separable lower envelope of parabolas, first down
// the columns, then along the rows; O(pixels). Used by the loft (signed
// distances of each label) and by the geometric validation (landmark to
// contour distances).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace pba {

// A bounding box of pixels, inclusive; empty until a pixel is added.
// Columns and rows may lie outside the grid (e.g. -1, a virtual background
// ring around a plate).
struct PixelBox {
  int c0 = std::numeric_limits<int>::max(), c1 = -1;
  int r0 = std::numeric_limits<int>::max(), r1 = -1;
  bool empty() const { return c1 < c0; }
  int width() const { return c1 - c0 + 1; }
  int height() const { return r1 - r0 + 1; }
  void Add(int c, int r) {
    c0 = std::min(c0, c);
    c1 = std::max(c1, c);
    r0 = std::min(r0, r);
    r1 = std::max(r1, r);
  }
  void Add(const PixelBox& b) {
    if (b.empty()) return;
    Add(b.c0, b.r0);
    Add(b.c1, b.r1);
  }
};

// Squared Euclidean distance [pixels^2] from every pixel of a w x h grid
// (row-major, `feature` and `out` both w * h) to the nearest pixel with
// feature[i] != 0; +infinity everywhere when there is none. Distances are
// between pixel centres, so a feature pixel has 0.
void SquaredDistanceTransform2d(const std::vector<uint8_t>& feature, int w, int h,
                                std::vector<double>* out);

// The same in 3-D [voxels^2]: an nx x ny x nz grid, x fastest (as
// LabelVolume), each z-slice transformed in-plane, then along z.
void SquaredDistanceTransform3d(const std::vector<uint8_t>& feature, int nx, int ny, int nz,
                                std::vector<double>* out);

// The same between voxel centres [mm^2] on a grid of voxels
// spacing_mm[0] x [1] x [2]: anisotropic voxels measured as they are.
void SquaredDistanceTransform3dMm(const std::vector<uint8_t>& feature, int nx, int ny, int nz,
                                  const double spacing_mm[3], std::vector<double>* out);

}  // namespace pba
