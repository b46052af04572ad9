// The loft: a label volume from a stack of atlas plates by shape-based
// interpolation (Raya & Udupa, "Shape-based interpolation of
// multidimensional objects", IEEE TMI 9(1), 1990; Herman, Zheng &
// Bucholtz, "Shape-based interpolation", IEEE CG&A 12(3), 1992).
//
// Method. For every label present on any plate, and on every plate, the
// signed Euclidean distance to the label's boundary [mm] is computed on the
// plate's pixel grid (negative inside):
//   d(pixel) = EDT(pixel, nearest pixel inside)  - h/2   for pixels outside,
//   d(pixel) = -(EDT(pixel, nearest pixel outside) - h/2) for pixels inside,
// h = pixel size, so the zero level lies on the pixel faces between an inside
// and an outside pixel. The distance transform is the exact 2-D Euclidean
// one of Felzenszwalb & Huttenlocher ("Distance transforms of sampled
// functions", Theory of Computing 8, 2012): the separable lower envelope of
// parabolas, O(pixels). Each plate's field is sampled bilinearly at the
// output voxel centres in x-y. At an output height z between plates a (z_a)
// and b (z_b), t = (z - z_a) / (z_b - z_a),
//   d(z) = (1 - t) d_a + t d_b,
// Labelling, in two steps. (1) The foreground - all labels but background
// (0) together - is lofted like one label; a voxel with d(z) >= 0 for it is
// background. (2) A foreground voxel takes the label with the smallest
// d(z) (ties: the lowest label id). For a lone structure this is the rule
// "the label with the most negative d(z) among those below 0, else
// background"; unlike that rule it leaves no background where two labels
// touch (on a shared boundary both fields are about 0, so neither is
// negative: lofting the synthetic atlas's plates at 1 mm, 3.5 % of the
// brain voxels at plate heights took none of the labels of the pixels they
// cover, nearly all of them background) nor where one structure shrinks away
// inside another between plates. A cross-section that splits into two (or
// two that merge) between plates comes out of the interpolation with no
// special handling.
//
// A label absent from one plate of a pair. Its field there is the constant
// +R, with R = the label's greatest depth (largest inside distance, max of
// -d) on the other plate of the pair. Then the cross-section at t is the
// other plate's section eroded by R t / (1 - t), and it shrinks to its
// deepest point at t = 1/2: a structure that ends between two plates tapers
// to a point midway between them. (A large constant would cut it off at the
// plate where it is present; the mirrored field -d would keep its full
// section up to midway and end in a flat face.)
//
// End caps. Above the top plate (below the bottom plate) the top (bottom)
// plate is paired with a virtual empty plate 2 * max_extrapolation_mm
// beyond it, so every structure on the end plate tapers by the rule above
// to a point max_extrapolation_mm beyond it; nothing is produced farther
// out.
//
// Output grid. Cubic voxels of edge voxel_size_mm. In x-y it covers the
// plates' extent from pixel face to pixel face (voxel (0, 0) centred half a
// voxel inside the plates' left, posterior corner; x right, y anterior, as
// LabelVolume). In z, voxel layers are voxel_size_mm apart with one layer at
// the lowest plate's height, and the grid spans [z_bottom - e_bottom,
// z_top + e_top] (e = the end's extrapolation), so plates whose heights
// differ from the lowest by multiples of voxel_size_mm lie on voxel layers.
//
// Cost and memory. Labels are lofted one at a time within their bounding
// box over all plates (plus a one-pixel margin, which keeps the transform
// exact inside the box); besides the output, memory holds one float per
// output voxel (the best distance so far) and one label's fields (one
// float per pixel of its box, and per plate one per output voxel of its
// box in x-y). The 1.5 mm synthetic atlas lofts in well under a second.
#pragma once

#include <optional>

#include "atlas/label_volume.h"
#include "atlas/plates.h"
#include "pba/status.h"

namespace pba {

struct LoftOptions {
  // Edge of the cubic output voxels, in-plane and in z [mm]; (0, 50].
  double voxel_size_mm = 1.0;
  // How far above the top plate and below the bottom plate a structure may
  // extend [mm], >= 0. Unset: half the spacing of the two plates at that
  // end (each end its own), as if the stack continued with an empty plate.
  std::optional<double> max_extrapolation_mm;

  Status Validate() const;
};

// Lofts `stack` into `volume` (replaced). Errors (kInvalidArgument naming
// the field): invalid options; a stack with fewer than 2 plates, a pixel
// size not positive and finite, width or height < 1, a plate whose label
// count is not width * height, plate heights not strictly increasing; an
// output grid over 2^31 voxels.
Status LoftPlates(const PlateStack& stack, const LoftOptions& options, LabelVolume* volume);

}  // namespace pba
