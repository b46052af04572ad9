#include "atlas/loft.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "atlas/distance_transform.h"
#include "core/format.h"

namespace pba {
namespace {

constexpr int kForeground = LoftField::kForeground;

// Signed distance [mm] of `label` (kForeground: any label but background)
// on plate p over `box` (row-major, box width fastest), negative inside;
// returns the label's greatest depth (max of -d, 0 when absent) through
// *depth and false when absent.
bool PlateSignedDistance(const PlateStack& stack, int p, int label, const PixelBox& box,
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

struct LoftField::Field {
  int label = kForeground;
  PixelBox box;  // pixels, with the one-pixel margin
  // Per plate, the signed distance over `box` (row-major, box width
  // fastest); empty where the label is absent.
  std::vector<std::vector<float>> plates;
  std::vector<double> depth;  // per plate, the greatest depth (0 where absent)
  // The box's first and last pixel centres [mm]: where the field is defined.
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;

  bool Has(int plate) const { return plate >= 0 && !plates[plate].empty(); }
};

// Where a height sits between two plates: plate indices a and b (-1 for the
// virtual empty plate beyond an end) and the weight t of b.
struct LoftField::Layer {
  int a = -1, b = -1;
  double t = 0;
};

LoftField::LoftField() = default;
LoftField::~LoftField() = default;
LoftField::LoftField(LoftField&&) noexcept = default;
LoftField& LoftField::operator=(LoftField&&) noexcept = default;

LoftField::Layer LoftField::LayerAt(double z) const {
  const int np = static_cast<int>(z_mm_.size());
  Layer layer;
  if (z < z_mm_[0]) {
    layer.b = 0;
    layer.t = e_bottom_mm_ > 0 ? (z - (z_mm_[0] - 2 * e_bottom_mm_)) / (2 * e_bottom_mm_) : 0;
  } else if (z > z_mm_[np - 1]) {
    layer.a = np - 1;
    layer.t = e_top_mm_ > 0 ? (z - z_mm_[np - 1]) / (2 * e_top_mm_) : 1;
  } else {
    const int b = std::max<int>(1, std::upper_bound(z_mm_.begin(), z_mm_.end(), z) - z_mm_.begin());
    layer.a = std::min(b, np - 1) - 1;
    layer.b = layer.a + 1;
    layer.t = (z - z_mm_[layer.a]) / (z_mm_[layer.b] - z_mm_[layer.a]);
  }
  layer.t = std::clamp(layer.t, 0.0, 1.0);
  return layer;
}

bool LoftField::InBox(const Field& f, double x, double y) const {
  return x >= f.x0 && x <= f.x1 && y >= f.y0 && y <= f.y1;
}

// Bilinear in the plate's field; the point must be InBox.
float LoftField::PlateDistance(const Field& f, int p, double x, double y) const {
  const PixelBox& box = f.box;
  const int w = box.width();
  const double r = (plate_origin_mm_.y() - y) / pixel_mm_ - box.r0;
  const int rf = std::clamp(static_cast<int>(std::floor(r)), 0, box.height() - 2);
  const double fr = std::clamp(r - rf, 0.0, 1.0);
  const double c = (x - plate_origin_mm_.x()) / pixel_mm_ - box.c0;
  const int cf = std::clamp(static_cast<int>(std::floor(c)), 0, w - 2);
  const double fc = std::clamp(c - cf, 0.0, 1.0);
  const float* q = &f.plates[p][static_cast<size_t>(rf) * w + cf];
  return static_cast<float>((1 - fr) * ((1 - fc) * q[0] + fc * q[1]) +
                            fr * ((1 - fc) * q[w] + fc * q[w + 1]));
}

namespace {

// d between the plates of a layer, from the plates' values (da used when
// has_a, db when has_b). A label absent on one side takes there the
// constant +depth of the other side (it tapers to a point midway);
// +infinity when absent on both. Float arithmetic, shared by the
// voxelisation and the continuous field so that both give the same bits.
float Interpolate(bool has_a, float da, bool has_b, float db, double depth_a, double depth_b,
                  double t) {
  if (!has_a && !has_b) return std::numeric_limits<float>::infinity();
  const float ca = has_a ? 0.0f : static_cast<float>(depth_b);
  const float cb = has_b ? 0.0f : static_cast<float>(depth_a);
  const float tf = static_cast<float>(t);
  return (1 - tf) * (has_a ? da : ca) + tf * (has_b ? db : cb);
}

}  // namespace

float LoftField::Distance(const Field& f, const Layer& layer, double x, double y) const {
  if (!InBox(f, x, y)) return std::numeric_limits<float>::infinity();
  const bool has_a = f.Has(layer.a), has_b = f.Has(layer.b);
  return Interpolate(has_a, has_a ? PlateDistance(f, layer.a, x, y) : 0.0f, has_b,
                     has_b ? PlateDistance(f, layer.b, x, y) : 0.0f,
                     layer.a >= 0 ? f.depth[layer.a] : 0.0, layer.b >= 0 ? f.depth[layer.b] : 0.0,
                     layer.t);
}

Status LoftField::Build(const PlateStack& stack, const LoftOptions& options) {
  *this = LoftField();
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

  LoftField field;
  field.pixel_mm_ = ps;
  field.plate_origin_mm_ = stack.origin_mm;
  field.z_mm_ = stack.z_mm;
  field.e_bottom_mm_ = e_bottom;
  field.e_top_mm_ = e_top;
  field.volume_ = LabelVolume({static_cast<int>(nx), static_cast<int>(ny), static_cast<int>(nz)},
                              origin, Eigen::Vector3d::Constant(vs));

  // Bounding boxes of every label over all plates, with a one-pixel ring.
  std::vector<PixelBox> boxes(65536);
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
  PixelBox all;
  for (const PixelBox& b : boxes) all.Add(b);
  field.field_of_.assign(65536, -1);
  if (!all.empty()) {
    const auto add = [&](int label, const PixelBox& box) {
      Field f;
      f.label = label;
      f.box = box;
      f.plates.resize(np);
      f.depth.assign(np, 0);
      for (int p = 0; p < np; ++p) {
        if (!PlateSignedDistance(stack, p, label, box, &f.plates[p], &f.depth[p]))
          f.plates[p].clear();
      }
      f.x0 = stack.origin_mm.x() + box.c0 * ps;
      f.x1 = stack.origin_mm.x() + box.c1 * ps;
      f.y0 = stack.origin_mm.y() - box.r1 * ps;
      f.y1 = stack.origin_mm.y() - box.r0 * ps;
      field.fields_.push_back(std::move(f));
    };
    add(kForeground, all);
    for (int label = 1; label < 65536; ++label) {
      if (boxes[label].empty()) continue;
      field.field_of_[label] = static_cast<int32_t>(field.fields_.size());
      field.labels_.push_back(label);
      add(label, boxes[label]);
    }
  }
  field.Voxelise();
  *this = std::move(field);
  return Status::Ok();
}

// The rule at every voxel centre, a field at a time over its box: each
// plate's field sampled once per voxel column, then combined per layer.
// The same functions as the continuous field, at the points
// LabelVolume::VoxelCentreMm gives, so the labels are the same.
void LoftField::Voxelise() {
  LabelVolume& out = volume_;
  const Eigen::Vector3d& origin = out.origin_mm();
  const double vs = out.spacing_mm().x();
  std::vector<Layer> layers(out.nz());
  for (int k = 0; k < out.nz(); ++k) layers[k] = LayerAt(origin.z() + k * vs);

  // Hands every output voxel of f's box its interpolated d: visit(voxel, d).
  std::vector<std::vector<float>> samples(z_mm_.size());
  const auto loft = [&](const Field& f, const auto& visit) {
    // The voxel columns whose centres are InBox: found by the same test,
    // around the estimate.
    const auto range = [&](double lo, double hi, double o, int n, int* first, int* last) {
      *first = std::max(0, static_cast<int>(std::ceil((lo - o) / vs)) - 1);
      *last = std::min(n - 1, static_cast<int>(std::floor((hi - o) / vs)) + 1);
    };
    int i0, i1, j0, j1;
    range(f.x0, f.x1, origin.x(), out.nx(), &i0, &i1);
    range(f.y0, f.y1, origin.y(), out.ny(), &j0, &j1);
    if (i1 < i0 || j1 < j0) return;
    const int bi = i1 - i0 + 1, bj = j1 - j0 + 1;
    std::vector<char> inside(static_cast<size_t>(bi) * bj);
    for (int j = 0; j < bj; ++j) {
      for (int i = 0; i < bi; ++i) {
        inside[static_cast<size_t>(j) * bi + i] =
            InBox(f, origin.x() + (i0 + i) * vs, origin.y() + (j0 + j) * vs);
      }
    }
    for (size_t p = 0; p < z_mm_.size(); ++p) {
      samples[p].clear();
      if (!f.Has(static_cast<int>(p))) continue;
      samples[p].resize(static_cast<size_t>(bi) * bj);
      for (int j = 0; j < bj; ++j) {
        for (int i = 0; i < bi; ++i) {
          const size_t s = static_cast<size_t>(j) * bi + i;
          if (inside[s]) {
            samples[p][s] = PlateDistance(f, static_cast<int>(p), origin.x() + (i0 + i) * vs,
                                          origin.y() + (j0 + j) * vs);
          }
        }
      }
    }
    for (int k = 0; k < out.nz(); ++k) {
      const Layer& layer = layers[k];
      const bool has_a = f.Has(layer.a), has_b = f.Has(layer.b);
      if (!has_a && !has_b) continue;
      const double depth_a = layer.a >= 0 ? f.depth[layer.a] : 0.0;
      const double depth_b = layer.b >= 0 ? f.depth[layer.b] : 0.0;
      for (int j = 0; j < bj; ++j) {
        for (int i = 0; i < bi; ++i) {
          const size_t s = static_cast<size_t>(j) * bi + i;
          if (!inside[s]) continue;
          visit(out.Index(i0 + i, j0 + j, k),
                Interpolate(has_a, has_a ? samples[layer.a][s] : 0.0f, has_b,
                            has_b ? samples[layer.b][s] : 0.0f, depth_a, depth_b, layer.t));
        }
      }
    }
  };

  if (fields_.empty()) return;
  // Foreground first: best = +inf inside (to be claimed by a label), -inf
  // outside (never claimed).
  std::vector<float> best(out.num_voxels(), -std::numeric_limits<float>::infinity());
  loft(fields_[0], [&](int64_t v, float d) {
    if (d < 0) best[v] = std::numeric_limits<float>::infinity();
  });
  std::vector<uint16_t>& labels = out.mutable_labels();
  for (size_t n = 1; n < fields_.size(); ++n) {
    const uint16_t label = static_cast<uint16_t>(fields_[n].label);
    loft(fields_[n], [&](int64_t v, float d) {
      if (d < best[v]) {
        best[v] = d;
        labels[v] = label;
      }
    });
  }
}

// The smallest d among labels[0..n) (increasing; ties: the first), for a
// point the foreground holds; 0 when none is finite.
int LoftField::Argmin(const Layer& layer, const Eigen::Vector3d& x, const int* labels,
                      int n) const {
  float best = std::numeric_limits<float>::infinity();
  int label = 0;
  for (int m = 0; m < n; ++m) {
    const int32_t f = field_of_[labels[m]];
    if (f < 0) continue;
    const float d = Distance(fields_[f], layer, x.x(), x.y());
    if (d < best) {
      best = d;
      label = labels[m];
    }
  }
  return label;
}

int LoftField::Label(const Eigen::Vector3d& x) const {
  if (fields_.empty() || !x.allFinite()) return 0;
  const Layer layer = LayerAt(x.z());
  if (!(Distance(fields_[0], layer, x.x(), x.y()) < 0)) return 0;
  // The labels of the eight voxels around x.
  const Eigen::Vector3d t = volume_.MmToVoxel(x);
  int lo[3], hi[3];
  bool in_grid = true;
  for (int a = 0; a < 3; ++a) {
    const int n = volume_.dims()[a];
    in_grid &= t[a] >= 0 && t[a] <= n - 1;
    const double f = std::floor(t[a]);
    lo[a] = f < 0 ? 0 : f > n - 1 ? n - 1 : static_cast<int>(f);
    hi[a] = std::min(lo[a] + (f >= 0 && f < n - 1 ? 1 : 0), n - 1);
  }
  int candidates[8], n = 0;
  bool background = false;
  for (int k = lo[2]; k <= hi[2]; ++k) {
    for (int j = lo[1]; j <= hi[1]; ++j) {
      for (int i = lo[0]; i <= hi[0]; ++i) {
        const int l = volume_.at(i, j, k);
        background |= l == 0;
        if (l == 0 || std::find(candidates, candidates + n, l) != candidates + n) continue;
        // Insertion in increasing order, for the tie rule.
        int m = n++;
        for (; m > 0 && candidates[m - 1] > l; --m) candidates[m] = candidates[m - 1];
        candidates[m] = l;
      }
    }
  }
  if (n == 0) return Argmin(layer, x, labels_.data(), static_cast<int>(labels_.size()));
  // One label all around x, inside the grid: x lies within the label's box
  // and between plates that have it, so its d is finite and it wins, as
  // Argmin would find.
  if (n == 1 && !background && in_grid) return candidates[0];
  return Argmin(layer, x, candidates, n);
}

int LoftField::LabelOverAllLabels(const Eigen::Vector3d& x) const {
  if (fields_.empty() || !x.allFinite()) return 0;
  const Layer layer = LayerAt(x.z());
  if (!(Distance(fields_[0], layer, x.x(), x.y()) < 0)) return 0;
  return Argmin(layer, x, labels_.data(), static_cast<int>(labels_.size()));
}

double LoftField::SignedDistance(int label, const Eigen::Vector3d& x) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (fields_.empty()) return label == 0 ? -kInf : kInf;
  const Layer layer = LayerAt(x.z());
  if (label == kForeground || label == 0) {
    const double d = Distance(fields_[0], layer, x.x(), x.y());
    return label == 0 ? -d : d;
  }
  if (label < 0 || label >= 65536 || field_of_[label] < 0) return kInf;
  return Distance(fields_[field_of_[label]], layer, x.x(), x.y());
}

std::size_t LoftField::field_bytes() const {
  std::size_t bytes = 0;
  for (const Field& f : fields_) {
    for (const std::vector<float>& plate : f.plates) bytes += plate.size() * sizeof(float);
  }
  return bytes;
}

Status LoftPlates(const PlateStack& stack, const LoftOptions& options, LabelVolume* volume) {
  LoftField field;
  PBA_RETURN_IF_ERROR(field.Build(stack, options));
  *volume = field.volume();
  return Status::Ok();
}

}  // namespace pba
