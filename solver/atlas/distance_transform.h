// Exact 2-D Euclidean distance transform of a binary image (Felzenszwalb &
// Huttenlocher, "Distance transforms of sampled functions", Theory of
// Computing 8, 2012): the separable lower envelope of parabolas, first down
// the columns, then along the rows; O(pixels). Used by the loft (signed
// distances of each label) and by the geometric validation (landmark to
// contour distances).
#pragma once

#include <cstdint>
#include <vector>

namespace pba {

// Squared Euclidean distance [pixels^2] from every pixel of a w x h grid
// (row-major, `feature` and `out` both w * h) to the nearest pixel with
// feature[i] != 0; +infinity everywhere when there is none. Distances are
// between pixel centres, so a feature pixel has 0.
void SquaredDistanceTransform2d(const std::vector<uint8_t>& feature, int w, int h,
                                std::vector<double>* out);

}  // namespace pba
