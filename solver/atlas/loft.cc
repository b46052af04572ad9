#include "atlas/loft.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "atlas/distance_transform.h"
#include "core/format.h"

namespace pba {
namespace {

using Box = PixelBox;

// Where an output layer sits between two plates: plate indices a and b
// (-1 for the virtual empty plate beyond an end) and the weight t of b.
struct Layer {
  int a = -1, b = -1;
  double t = 0;
};

// Signed distance [mm] of `label` (kForeground: any label but background)
// on plate p over `box` (row-major, box width fastest), negative inside;
// returns the label's greatest depth (max of -d, 0 when absent) through
// *depth and false when absent.
constexpr int kForeground = -1;

bool SignedDistance(const PlateStack& stack, int p, int label, const Box& box,
                    std::vector<float>* field, double* depth) {
  const int w = box.width(), h = box.height();
  std::vector<uint8_t> inside(static_cast<size_t>(w) * h, 0), outside(inside.size(), 0);
  bool present = false;
  for (int r = box.r0; r <= box.r1; ++r) {
    for (int c = box.c0; c <= box.c1; ++c) {
      const bool on = c >= 0 && r >= 0 && c < stack.width && r < stack.height;
      const bool in =
          on && (label == kForeground ? stack.at(p, c, r) != 0 : stack.at(p, c, r) == label);
      const size_t i = static_cast<size_t>(r - box.r0) * w + (c - box.c0);
      inside[i] = in;
      outside[i] = !in;
      present |= in;
    }
  }
  *depth = 0;
  if (!present) return false;
  std::vector<double> to_inside, to_outside;
  SquaredDistanceTransform2d(inside, w, h, &to_inside);
  SquaredDistanceTransform2d(outside, w, h, &to_outside);
  const double half = 0.5, pixel = stack.pixel_size_mm;
  field->resize(inside.size());
  for (size_t i = 0; i < inside.size(); ++i) {
    const double d =
        inside[i] ? -(std::sqrt(to_outside[i]) - half) : std::sqrt(to_inside[i]) - half;
    (*field)[i] = static_cast<float>(d * pixel);
    *depth = std::max(*depth, -d * pixel);
  }
  return true;
}

}  // namespace

Status LoftOptions::Validate() const {
  if (!(voxel_size_mm > 0 && voxel_size_mm <= 50)) {
    return Status::InvalidArgument("voxel_size_mm",
                                   Format("%g is outside (0, 50] mm", voxel_size_mm));
  }
  if (max_extrapolation_mm &&
      !(*max_extrapolation_mm >= 0 && std::isfinite(*max_extrapolation_mm))) {
    return Status::InvalidArgument("max_extrapolation_mm",
                                   Format("%g is not a finite length >= 0", *max_extrapolation_mm));
  }
  return Status::Ok();
}

Status LoftPlates(const PlateStack& stack, const LoftOptions& options, LabelVolume* volume) {
  PBA_RETURN_IF_ERROR(options.Validate());
  PBA_RETURN_IF_ERROR(ValidatePlateStack(stack, "stack", 2));
  const int np = stack.num_plates();
  const double ps = stack.pixel_size_mm, vs = options.voxel_size_mm;
  const double bottom_gap = stack.z_mm[1] - stack.z_mm[0];
  const double top_gap = stack.z_mm[np - 1] - stack.z_mm[np - 2];
  const double e_bottom = options.max_extrapolation_mm.value_or(0.5 * bottom_gap);
  const double e_top = options.max_extrapolation_mm.value_or(0.5 * top_gap);

  // The output grid (see the header).
  const double lo_x = stack.origin_mm.x() - 0.5 * ps;
  const double lo_y = stack.origin_mm.y() - (stack.height - 0.5) * ps;
  const auto cells = [vs](double extent) { return std::max(1.0, std::ceil(extent / vs - 1e-9)); };
  const double nx = cells(stack.width * ps), ny = cells(stack.height * ps);
  const double below = std::floor(e_bottom / vs + 1e-9);
  const double above = std::floor((stack.z_mm[np - 1] + e_top - stack.z_mm[0]) / vs + 1e-9);
  const double nz = below + above + 1;
  if (nx * ny * nz > std::numeric_limits<int32_t>::max()) {
    return Status::InvalidArgument(
        "voxel_size_mm",
        Format("a %g mm grid over the plates has %.3g voxels, over 2^31", vs, nx * ny * nz));
  }
  const Eigen::Vector3d origin(lo_x + 0.5 * vs, lo_y + 0.5 * vs, stack.z_mm[0] - below * vs);
  LabelVolume out({static_cast<int>(nx), static_cast<int>(ny), static_cast<int>(nz)}, origin,
                  Eigen::Vector3d::Constant(vs));

  // Each output layer's pair of plates.
  std::vector<Layer> layers(out.nz());
  for (int k = 0; k < out.nz(); ++k) {
    const double z = origin.z() + k * vs;
    Layer& layer = layers[k];
    if (z < stack.z_mm[0]) {
      layer.b = 0;
      layer.t = e_bottom > 0 ? (z - (stack.z_mm[0] - 2 * e_bottom)) / (2 * e_bottom) : 0;
    } else if (z > stack.z_mm[np - 1]) {
      layer.a = np - 1;
      layer.t = e_top > 0 ? (z - stack.z_mm[np - 1]) / (2 * e_top) : 1;
    } else {
      const int b = std::max<int>(
          1, std::upper_bound(stack.z_mm.begin(), stack.z_mm.end(), z) - stack.z_mm.begin());
      layer.a = std::min(b, np - 1) - 1;
      layer.b = layer.a + 1;
      layer.t = (z - stack.z_mm[layer.a]) / (stack.z_mm[layer.b] - stack.z_mm[layer.a]);
    }
    layer.t = std::clamp(layer.t, 0.0, 1.0);
  }

  // Bounding boxes of every label over all plates, with a one-pixel ring.
  std::vector<Box> boxes(65536);
  for (int p = 0; p < np; ++p) {
    for (int r = 0; r < stack.height; ++r) {
      for (int c = 0; c < stack.width; ++c) {
        const uint16_t l = stack.at(p, c, r);
        if (l == 0) continue;
        // With a one-pixel margin: the label's boundary lies inside.
        boxes[l].Add(c - 1, r - 1);
        boxes[l].Add(c + 1, r + 1);
      }
    }
  }

  // Lofts one label's field and hands every output voxel of its box its
  // interpolated distance: visit(voxel index, d).
  std::vector<float> plate_field;
  const auto loft = [&](int label, const Box& box, const auto& visit) {
    // Output voxels whose centres lie within the box's pixel centres.
    const double x0 = stack.origin_mm.x() + box.c0 * ps, x1 = stack.origin_mm.x() + box.c1 * ps;
    const double y0 = stack.origin_mm.y() - box.r1 * ps, y1 = stack.origin_mm.y() - box.r0 * ps;
    const int i0 = std::max(0, static_cast<int>(std::ceil((x0 - origin.x()) / vs)));
    const int i1 = std::min(out.nx() - 1, static_cast<int>(std::floor((x1 - origin.x()) / vs)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((y0 - origin.y()) / vs)));
    const int j1 = std::min(out.ny() - 1, static_cast<int>(std::floor((y1 - origin.y()) / vs)));
    if (i1 < i0 || j1 < j0) return;
    const int bi = i1 - i0 + 1, bj = j1 - j0 + 1;

    // Each plate's field sampled bilinearly at those voxel centres.
    std::vector<std::vector<float>> fields(np);
    std::vector<double> depths(np, 0);
    for (int p = 0; p < np; ++p) {
      if (!SignedDistance(stack, p, label, box, &plate_field, &depths[p])) continue;
      std::vector<float>& f = fields[p];
      f.resize(static_cast<size_t>(bi) * bj);
      const int w = box.width();
      for (int j = 0; j < bj; ++j) {
        const double r = (stack.origin_mm.y() - (origin.y() + (j0 + j) * vs)) / ps - box.r0;
        const int rf = std::clamp(static_cast<int>(std::floor(r)), 0, box.height() - 2);
        const double fr = std::clamp(r - rf, 0.0, 1.0);
        for (int i = 0; i < bi; ++i) {
          const double c = (origin.x() + (i0 + i) * vs - stack.origin_mm.x()) / ps - box.c0;
          const int cf = std::clamp(static_cast<int>(std::floor(c)), 0, w - 2);
          const double fc = std::clamp(c - cf, 0.0, 1.0);
          const float* q = &plate_field[static_cast<size_t>(rf) * w + cf];
          f[static_cast<size_t>(j) * bi + i] = static_cast<float>(
              (1 - fr) * ((1 - fc) * q[0] + fc * q[1]) + fr * ((1 - fc) * q[w] + fc * q[w + 1]));
        }
      }
    }

    for (int k = 0; k < out.nz(); ++k) {
      const Layer& layer = layers[k];
      const std::vector<float>* fa =
          layer.a >= 0 && !fields[layer.a].empty() ? &fields[layer.a] : nullptr;
      const std::vector<float>* fb =
          layer.b >= 0 && !fields[layer.b].empty() ? &fields[layer.b] : nullptr;
      if (fa == nullptr && fb == nullptr) continue;
      // Absent on one side: the constant +depth of the other (tapers to a
      // point midway).
      const float ca = fa ? 0.0f : static_cast<float>(depths[layer.b]);
      const float cb = fb ? 0.0f : static_cast<float>(depths[layer.a]);
      const float t = static_cast<float>(layer.t);
      for (int j = 0; j < bj; ++j) {
        for (int i = 0; i < bi; ++i) {
          const size_t s = static_cast<size_t>(j) * bi + i;
          visit(out.Index(i0 + i, j0 + j, k),
                (1 - t) * (fa ? (*fa)[s] : ca) + t * (fb ? (*fb)[s] : cb));
        }
      }
    }
  };

  // Foreground first: best = +inf inside (to be claimed by a label), -inf
  // outside (never claimed).
  Box all;
  for (const Box& b : boxes) all.Add(b);
  std::vector<float> best(out.num_voxels(), -std::numeric_limits<float>::infinity());
  if (!all.empty()) {
    loft(kForeground, all, [&](int64_t v, float d) {
      if (d < 0) best[v] = std::numeric_limits<float>::infinity();
    });
  }
  std::vector<uint16_t>& labels = out.mutable_labels();
  for (int label = 1; label < 65536; ++label) {
    if (boxes[label].empty()) continue;
    loft(label, boxes[label], [&](int64_t v, float d) {
      if (d < best[v]) {
        best[v] = d;
        labels[v] = static_cast<uint16_t>(label);
      }
    });
  }
  *volume = std::move(out);
  return Status::Ok();
}

}  // namespace pba
