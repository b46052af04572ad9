#include "atlas/atlas_pictures.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "atlas/geometric_validation.h"
#include "core/atomic_write.h"
#include "core/format.h"
#include "core/number_format.h"
#include "io/bitmap_font.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr double kMmPerM = 1000.0;
// A node this close to the plane [mm] is on it.
constexpr double kOnPlaneMm = 1e-7;
// The largest section, per side [pixels].
constexpr int kMaxSectionSide = 20000;
using Rgb = std::array<uint8_t, 3>;

void Put(RgbImage* image, int column, int row, const Rgb& rgb) {
  uint8_t* px = &image->rgb[(static_cast<size_t>(row) * image->width + column) * 3];
  px[0] = rgb[0];
  px[1] = rgb[1];
  px[2] = rgb[2];
}

RgbImage Blank(int width, int height, const Rgb& rgb) {
  RgbImage image;
  image.width = width;
  image.height = height;
  image.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < image.rgb.size(); i += 3) {
    image.rgb[i] = rgb[0];
    image.rgb[i + 1] = rgb[1];
    image.rgb[i + 2] = rgb[2];
  }
  return image;
}

void AddText(const std::string& notice, const std::string& title, RgbImage* image) {
  if (!notice.empty()) image->text.emplace_back("Comment", notice);
  image->text.emplace_back("Title", title);
}

// WriteRgbPng into a temporary file beside `png`, renamed over it.
Status WritePngAtomically(const fs::path& png, const RgbImage& image) {
  return AtomicWrite(png, ".png", [&](int, const std::string& temporary) {
    return WriteRgbPng(temporary, image);
  });
}

// Colour of every label (nullptr: none), indexed by label.
std::vector<const ColourEntry*> ColourIndex(const ColourTable& colours) {
  std::vector<const ColourEntry*> index(65536, nullptr);
  for (const ColourEntry& e : colours.entries()) index[e.label] = &e;
  return index;
}

// "-16", "2.5": the shortest of %g.

}  // namespace

ContactSheetLayout LayOutContactSheet(const PlateStack& plates) {
  ContactSheetLayout l;
  const int n = std::max(1, plates.num_plates());
  l.columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)) - 1e-9));
  l.rows = (n + l.columns - 1) / l.columns;
  l.gap = 4;
  int caption = 0;
  for (double z : plates.z_mm)
    caption = std::max(caption, TextWidth("z " + ShortNumber(z) + " mm", 1));
  const auto cell = [&](int tile, int scale) { return std::max(tile, caption * scale + 2); };
  for (l.step = 1;; ++l.step) {
    l.tile_width = (plates.width + l.step - 1) / l.step;
    l.scale = l.tile_width >= 160 ? 2 : 1;
    if (l.gap + l.columns * (cell(l.tile_width, l.scale) + l.gap) <= kMaxSheetWidth ||
        l.tile_width <= 1) {
      break;
    }
  }
  l.tile_height = (plates.height + l.step - 1) / l.step;
  l.caption_height = kGlyphHeight * l.scale + 6;
  l.cell_width = cell(l.tile_width, l.scale);
  l.width = l.gap + l.columns * (l.cell_width + l.gap);
  l.height = l.gap + l.rows * (l.tile_height + l.caption_height + l.gap);
  return l;
}

Status RenderPlateContactSheet(const PlateStack& plates, const std::string& notice,
                               RgbImage* image) {
  PBA_RETURN_IF_ERROR(ValidatePlateStack(plates, "plates", 1));
  const ContactSheetLayout l = LayOutContactSheet(plates);
  const std::vector<const ColourEntry*> colour = ColourIndex(plates.colours);
  RgbImage sheet = Blank(l.width, l.height, kGapGrey);
  for (int p = 0; p < plates.num_plates(); ++p) {
    const int left = l.TileLeft(p), top = l.TileTop(p);
    for (int r = 0; r < l.tile_height; ++r) {
      for (int c = 0; c < l.tile_width; ++c) {
        const uint16_t label = plates.at(p, c * l.step, r * l.step);
        Rgb rgb = {0, 0, 0};
        if (label != 0) {
          const ColourEntry* e = colour[label];
          if (e == nullptr) {
            return Status::InvalidArgument(
                "plates.colours", Format("label %d on plate %d (%s) has no colour", label, p + 1,
                                         plates.files[p].c_str()));
          }
          rgb = {e->r, e->g, e->b};
        }
        Put(&sheet, left + c, top + r, rgb);
      }
    }
    DrawText("z " + ShortNumber(plates.z_mm[p]) + " mm", left + 2, top + l.tile_height + 3, l.scale,
             kTextColour, &sheet);
  }
  AddText(notice,
          Format("PBA atlas plates: %d plates, bottom first, left to right", plates.num_plates()),
          &sheet);
  *image = std::move(sheet);
  return Status::Ok();
}

Status WritePlateContactSheet(const PlateStack& plates, const fs::path& png,
                              const std::string& notice) {
  RgbImage image;
  PBA_RETURN_IF_ERROR(RenderPlateContactSheet(plates, notice, &image));
  return WritePngAtomically(png, image);
}

const char* CutAxisName(CutAxis axis) {
  switch (axis) {
    case CutAxis::kAxial:
      return "axial";
    case CutAxis::kCoronal:
      return "coronal";
    case CutAxis::kSagittal:
      return "sagittal";
  }
  return "?";
}

char CutAxisCoordinate(CutAxis axis) {
  return axis == CutAxis::kAxial ? 'z' : axis == CutAxis::kCoronal ? 'y' : 'x';
}

namespace {

// The picture's axes: u to the right, v up, w the constant coordinate
// (indices into x, y, z).
struct Axes {
  int u, v, w;
};

Axes AxesOf(CutAxis axis) {
  switch (axis) {
    case CutAxis::kAxial:
      return {0, 1, 2};
    case CutAxis::kCoronal:
      return {0, 2, 1};
    case CutAxis::kSagittal:
      return {1, 2, 0};
  }
  return {0, 1, 2};
}

// The orientation letters at the left, right, top and bottom of a cut.
std::array<const char*, 4> OrientationLetters(CutAxis axis) {
  switch (axis) {
    case CutAxis::kAxial:
      return {"L", "R", "A", "P"};
    case CutAxis::kCoronal:
      return {"L", "R", "S", "I"};
    case CutAxis::kSagittal:
      return {"P", "A", "S", "I"};
  }
  return {"", "", "", ""};
}

}  // namespace

Eigen::Vector3d MeshCutPicture::SectionPixelCentreMm(int c, int r) const {
  const Axes a = AxesOf(axis);
  Eigen::Vector3d p;
  p[a.u] = u0_mm + c * pixel_mm;
  p[a.v] = v0_mm - r * pixel_mm;
  p[a.w] = position_mm;
  return p;
}

std::array<int, 2> MeshCutPicture::ImagePixel(const Eigen::Vector3d& p_mm) const {
  const Axes a = AxesOf(axis);
  return {left + static_cast<int>(std::lround((p_mm[a.u] - u0_mm) / pixel_mm)),
          top + static_cast<int>(std::lround((v0_mm - p_mm[a.v]) / pixel_mm))};
}

std::array<uint8_t, 3> MeshCutPicture::At(int column, int row) const {
  const uint8_t* px = &image.rgb[(static_cast<size_t>(row) * image.width + column) * 3];
  return {px[0], px[1], px[2]};
}

Status MeshCutOptions::Validate() const {
  if (!(pixel_mm > 0 && pixel_mm <= 10)) {
    return Status::InvalidArgument("pixel_mm", Format("%g is outside (0, 10] mm", pixel_mm));
  }
  if (!(margin_mm >= 0 && margin_mm <= 100)) {
    return Status::InvalidArgument("margin_mm", Format("%g is outside [0, 100] mm", margin_mm));
  }
  if (!std::isfinite(position_mm)) {
    return Status::InvalidArgument("position_mm", "not a finite number");
  }
  return Status::Ok();
}

namespace {

Status ValidateMesh(const Mesh& mesh, const std::vector<uint16_t>& region_labels,
                    const ColourTable& colours) {
  PBA_RETURN_IF_ERROR(ValidateLabelledTetMesh(mesh, region_labels, "region_labels", "picture"));
  const size_t regions = std::max<size_t>(1, mesh.region_names.size());
  for (size_t r = 0; r < regions; ++r) {
    if (region_labels[r] != 0 && colours.FindByLabel(region_labels[r]) == nullptr) {
      return Status::InvalidArgument(
          Format("region_labels[%zu]", r),
          Format("label %d has no colour in the colour table", region_labels[r]));
    }
  }
  return Status::Ok();
}

// Bounding box of the nodes [mm].
void MeshBoxMm(const Mesh& mesh, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = mesh.nodes.colwise().minCoeff().transpose() * kMmPerM;
  *hi = mesh.nodes.colwise().maxCoeff().transpose() * kMmPerM;
}

// The one-pixel outline of a polygon (section pixel coordinates, in order
// around it) into `mask` (w x h).
void OutlinePolygon(const std::vector<Eigen::Vector2d>& polygon, int w, int h,
                    std::vector<uint8_t>* mask) {
  const size_t n = polygon.size();
  for (size_t i = 0; i < (n == 2 ? 1 : n); ++i) {
    const Eigen::Vector2d a = polygon[i], b = polygon[(i + 1) % n];
    const Eigen::Vector2d d = b - a;
    const int steps = std::max(1, static_cast<int>(std::ceil(d.cwiseAbs().maxCoeff())));
    for (int s = 0; s <= steps; ++s) {
      const Eigen::Vector2d p = a + d * (static_cast<double>(s) / steps);
      const long c = std::lround(p.x()), r = std::lround(p.y());
      if (c >= 0 && r >= 0 && c < w && r < h) (*mask)[static_cast<size_t>(r) * w + c] = 1;
    }
  }
}

// The polygon (3 or 4 points, in order around it; fewer when the plane
// only touches the element) the plane w = position cuts from the
// tetrahedron with corners x [mm] at signed distances d [mm] from it, in
// section pixel coordinates (column, row).
void CutPolygon(const MeshCutPicture& pic, const Eigen::Matrix<double, 4, 3>& x,
                const std::array<double, 4>& d, std::vector<Eigen::Vector2d>* polygon) {
  constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  const Axes a = AxesOf(pic.axis);
  const auto to_pixel = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d((p[a.u] - pic.u0_mm) / pic.pixel_mm,
                           (pic.v0_mm - p[a.v]) / pic.pixel_mm);
  };
  polygon->clear();
  for (int k = 0; k < 4; ++k) {
    if (std::abs(d[k]) <= kOnPlaneMm) polygon->push_back(to_pixel(x.row(k).transpose()));
  }
  for (const auto& [i, j] : kEdges) {
    if (std::abs(d[i]) <= kOnPlaneMm || std::abs(d[j]) <= kOnPlaneMm || (d[i] > 0) == (d[j] > 0)) {
      continue;
    }
    const double s = d[i] / (d[i] - d[j]);
    polygon->push_back(to_pixel((x.row(i) + s * (x.row(j) - x.row(i))).transpose()));
  }
  if (polygon->size() < 3) return;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : *polygon) centre += p;
  centre /= static_cast<double>(polygon->size());
  // The section of a convex element is convex: in order by angle.
  std::sort(polygon->begin(), polygon->end(), [&](const auto& p, const auto& q) {
    return std::atan2(p.y() - centre.y(), p.x() - centre.x()) <
           std::atan2(q.y() - centre.y(), q.x() - centre.x());
  });
}

// The section's fill (per pixel the region of the element holding its
// centre, -1 outside) and element outlines (1 on an outline). Only the
// elements crossing the plane are visited, each over the pixels of its
// polygon's bounding box: every pixel is tested against the few elements
// over it, so no search structure is needed, and the cost is one pass over
// the elements' plane coordinates plus the section's pixels.
void RasteriseCut(const Mesh& mesh, const MeshCutPicture& pic, bool edges, std::vector<int>* region,
                  std::vector<uint8_t>* edge) {
  const int w = pic.width, ht = pic.height;
  const int axis_w = AxesOf(pic.axis).w;
  region->assign(static_cast<size_t>(w) * ht, -1);
  edge->assign(region->size(), 0);
  constexpr double kTolerance = 1e-9;
  std::vector<Eigen::Vector2d> polygon;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    std::array<double, 4> d;
    double dmin = std::numeric_limits<double>::infinity(), dmax = -dmin;
    for (int k = 0; k < 4; ++k) {
      d[k] = mesh.nodes(mesh.tets[e][k], axis_w) * kMmPerM - pic.position_mm;
      dmin = std::min(dmin, d[k]);
      dmax = std::max(dmax, d[k]);
    }
    if (dmin > kOnPlaneMm || dmax < -kOnPlaneMm) continue;
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e) * kMmPerM;
    CutPolygon(pic, x, d, &polygon);
    if (polygon.size() >= 2 && edges) OutlinePolygon(polygon, w, ht, edge);
    if (polygon.size() < 3) continue;  // an edge or corner in the plane: no area

    Eigen::Matrix3d span;
    for (int k = 0; k < 3; ++k) span.col(k) = (x.row(k + 1) - x.row(0)).transpose();
    if (!(std::abs(span.determinant()) > 0)) continue;
    const Eigen::Matrix3d inverse = span.inverse();
    Eigen::Vector2d lo = polygon[0], hi = polygon[0];
    for (const Eigen::Vector2d& p : polygon) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const int c0 = std::max(0, static_cast<int>(std::ceil(lo.x() - kTolerance)));
    const int c1 = std::min(w - 1, static_cast<int>(std::floor(hi.x() + kTolerance)));
    const int r0 = std::max(0, static_cast<int>(std::ceil(lo.y() - kTolerance)));
    const int r1 = std::min(ht - 1, static_cast<int>(std::floor(hi.y() + kTolerance)));
    const int element_region = mesh.element_region.empty() ? 0 : mesh.element_region[e];
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const Eigen::Vector3d l = inverse * (pic.SectionPixelCentreMm(c, r) - x.row(0).transpose());
        if (l.minCoeff() >= -kTolerance && l.sum() <= 1 + kTolerance) {
          (*region)[static_cast<size_t>(r) * w + c] = element_region;
        }
      }
    }
  }
}

// The source labels on the section's pixel grid, merged as the header says
// (-1: the merged rest).
std::vector<int> SampleSource(const MeshCutPicture& pic, const CutSource& source,
                              const std::vector<uint16_t>& region_labels, std::string* name) {
  const int w = pic.width, h = pic.height;
  int plate = -1;
  if (source.plates != nullptr && pic.axis == CutAxis::kAxial) {
    for (int p = 0; p < source.plates->num_plates(); ++p) {
      if (std::abs(source.plates->z_mm[p] - pic.position_mm) <= 1e-6) plate = p;
    }
  }
  if (plate < 0 && (source.volume == nullptr || source.volume->num_voxels() == 0)) return {};
  std::vector<uint8_t> kept(65536, 0);
  bool rest = false;
  for (uint16_t l : region_labels) {
    kept[l] = 1;
    rest = rest || l == 0;
  }
  const auto merge = [&](uint16_t l) { return l == 0 || kept[l] ? int{l} : rest ? -1 : 0; };
  std::vector<int> labels(static_cast<size_t>(w) * h, 0);
  if (plate >= 0) {
    const PlateStack& s = *source.plates;
    *name = Format("plate %d", plate + 1);
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const Eigen::Vector3d p = pic.SectionPixelCentreMm(c, r);
        const long pc = std::lround((p.x() - s.origin_mm.x()) / s.pixel_size_mm);
        const long pr = std::lround((s.origin_mm.y() - p.y()) / s.pixel_size_mm);
        if (pc < 0 || pr < 0 || pc >= s.width || pr >= s.height) continue;
        labels[static_cast<size_t>(r) * w + c] =
            merge(s.at(plate, static_cast<int>(pc), static_cast<int>(pr)));
      }
    }
  } else {
    *name = "label volume";
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        labels[static_cast<size_t>(r) * w + c] =
            merge(source.volume->SampleNearest(pic.SectionPixelCentreMm(c, r)));
      }
    }
  }
  return labels;
}

}  // namespace

Status RenderMeshCut(const Mesh& mesh, const std::vector<uint16_t>& region_labels,
                     const ColourTable& colours, const CutSource& source,
                     const MeshCutOptions& options, MeshCutPicture* picture) {
  PBA_RETURN_IF_ERROR(options.Validate());
  PBA_RETURN_IF_ERROR(ValidateMesh(mesh, region_labels, colours));
  const Axes a = AxesOf(options.axis);
  const char coordinate = CutAxisCoordinate(options.axis);
  const double pos = options.position_mm, h = options.pixel_mm;
  Eigen::Vector3d lo, hi;
  MeshBoxMm(mesh, &lo, &hi);
  if (pos < lo[a.w] - kOnPlaneMm || pos > hi[a.w] + kOnPlaneMm) {
    return Status::InvalidArgument(
        "position_mm",
        Format("the %s cut at %c = %g mm misses the mesh, whose %c extent is "
               "[%.1f, %.1f] mm",
               CutAxisName(options.axis), coordinate, pos, coordinate, lo[a.w], hi[a.w]));
  }

  // The section's pixel lattice: the plates' for an axial cut with plates.
  MeshCutPicture pic;
  pic.axis = options.axis;
  pic.position_mm = pos;
  pic.pixel_mm = h;
  Eigen::Vector2d anchor(0.5 * h, 0.5 * h);
  if (options.axis == CutAxis::kAxial && source.plates != nullptr) {
    anchor = source.plates->origin_mm;
  }
  const double umin = lo[a.u] - options.margin_mm, umax = hi[a.u] + options.margin_mm;
  const double vmin = lo[a.v] - options.margin_mm, vmax = hi[a.v] + options.margin_mm;
  pic.u0_mm = anchor.x() + std::floor((umin - anchor.x()) / h) * h;
  pic.v0_mm = anchor.y() + std::ceil((vmax - anchor.y()) / h) * h;
  const double wide = std::ceil((umax - pic.u0_mm) / h) + 1;
  const double tall = std::ceil((pic.v0_mm - vmin) / h) + 1;
  if (wide > kMaxSectionSide || tall > kMaxSectionSide) {
    return Status::InvalidArgument(
        "pixel_mm", Format("%g mm pixels make a %.0f x %.0f pixel section (at most %d a side)", h,
                           wide, tall, kMaxSectionSide));
  }
  const int w = pic.width = static_cast<int>(wide);
  const int ht = pic.height = static_cast<int>(tall);

  std::vector<int> region;
  std::vector<uint8_t> edge;
  RasteriseCut(mesh, pic, options.edges, &region, &edge);

  // Region colours, then the frame and the section's layers.
  std::vector<Rgb> region_rgb(region_labels.size(), kSurroundingGrey);
  for (size_t r = 0; r < region_labels.size(); ++r) {
    if (const ColourEntry* c = colours.FindByLabel(region_labels[r]); c != nullptr) {
      region_rgb[r] = {c->r, c->g, c->b};
    }
  }
  std::string contour_name;
  const std::vector<int> src = SampleSource(pic, source, region_labels, &contour_name);
  pic.contour_source = contour_name;
  double shown = std::round(pos * 10) / 10;
  if (shown == 0) shown = 0;  // no "-0.0"
  std::string caption = Format("%s %c %+.1f mm", CutAxisName(options.axis), coordinate, shown);
  if (!src.empty()) caption += ", white: " + contour_name;

  const int scale = w >= 600 ? 2 : 1;
  const int band = kGlyphHeight * scale + 6;
  pic.left = band;
  pic.top = 2 * band;
  RgbImage image =
      Blank(std::max(w + 2 * band, TextWidth(caption, scale) + 6), ht + 3 * band, kFrameColour);
  for (int r = 0; r < ht; ++r) {
    for (int c = 0; c < w; ++c) {
      const size_t i = static_cast<size_t>(r) * w + c;
      Rgb rgb = region[i] < 0 ? Rgb{0, 0, 0} : region_rgb[region[i]];
      if (edge[i]) {
        for (uint8_t& channel : rgb)
          channel = static_cast<uint8_t>(std::lround(channel * kEdgeShade));
      }
      const bool contour = !src.empty() && ((c + 1 < w && src[i] != src[i + 1]) ||
                                            (r + 1 < ht && src[i] != src[i + w]));
      Put(&image, pic.left + c, pic.top + r, contour ? kContourWhite : rgb);
    }
  }
  DrawText(caption, 3, 3, scale, kTextColour, &image);
  const std::array<const char*, 4> letters = OrientationLetters(options.axis);
  const int glyph_w = kGlyphWidth * scale, glyph_h = kGlyphHeight * scale;
  const int mid_c = pic.left + w / 2 - glyph_w / 2, mid_r = pic.top + ht / 2 - glyph_h / 2;
  DrawText(letters[0], (band - glyph_w) / 2, mid_r, scale, kTextColour, &image);
  DrawText(letters[1], pic.left + w + (band - glyph_w) / 2, mid_r, scale, kTextColour, &image);
  DrawText(letters[2], mid_c, band + 3, scale, kTextColour, &image);
  DrawText(letters[3], mid_c, pic.top + ht + 3, scale, kTextColour, &image);
  AddText(options.notice, "PBA atlas mesh cut: " + caption, &image);
  pic.image = std::move(image);
  *picture = std::move(pic);
  return Status::Ok();
}

Status WriteMeshCut(const Mesh& mesh, const std::vector<uint16_t>& region_labels,
                    const ColourTable& colours, const CutSource& source,
                    const MeshCutOptions& options, const fs::path& png) {
  MeshCutPicture picture;
  PBA_RETURN_IF_ERROR(RenderMeshCut(mesh, region_labels, colours, source, options, &picture));
  return WritePngAtomically(png, picture.image);
}

std::string CutFileName(CutAxis axis, double position_mm) {
  double p = std::round(position_mm * 10) / 10;
  if (p == 0) p = 0;  // no "-000.0"
  return Format("cut_%s_%c%+06.1fmm.png", CutAxisName(axis), CutAxisCoordinate(axis), p);
}

Status AtlasPictureOptions::Validate() const {
  if (!(pixel_mm > 0 && pixel_mm <= 10)) {
    return Status::InvalidArgument("pixel_mm", Format("%g is outside (0, 10] mm", pixel_mm));
  }
  const auto finite = [](const std::vector<double>& cuts, const char* field) {
    for (size_t i = 0; i < cuts.size(); ++i) {
      if (!std::isfinite(cuts[i])) {
        return Status::InvalidArgument(Format("%s[%zu]", field, i), "not a finite number");
      }
    }
    return Status::Ok();
  };
  PBA_RETURN_IF_ERROR(finite(axial_z_mm, "axial_z_mm"));
  PBA_RETURN_IF_ERROR(finite(coronal_y_mm, "coronal_y_mm"));
  return finite(sagittal_x_mm, "sagittal_x_mm");
}

namespace {

struct Cut {
  CutAxis axis;
  double position_mm;
};

// The default cuts (AtlasPictureOptions).
std::vector<Cut> DefaultCuts(const AtlasBuildResult& result) {
  Eigen::Vector3d lo, hi;
  MeshBoxMm(result.mesh, &lo, &hi);
  std::vector<Cut> cuts;
  std::vector<double> heights;
  if (result.plates) {
    for (double z : result.plates->z_mm) {
      if (z >= lo.z() && z <= hi.z()) heights.push_back(z);
    }
  }
  const int n = static_cast<int>(heights.size());
  for (int sixth : {1, 3, 5}) {
    const double z =
        n > 0 ? heights[n * sixth / 6] : std::round(lo.z() + (hi.z() - lo.z()) * sixth / 6.0);
    cuts.push_back({CutAxis::kAxial, std::clamp(z, lo.z(), hi.z())});
  }

  double y = std::round(0.5 * (lo.y() + hi.y()));
  std::vector<uint16_t> thalamus;
  for (uint16_t label : result.region_labels) {
    const ColourEntry* e = result.colours.FindByLabel(label);
    if (e != nullptr && e->name.rfind("Thalamus", 0) == 0) thalamus.push_back(label);
  }
  if (!thalamus.empty() && result.volume.num_voxels() > 0) {
    const LabelStats stats = ComputeLabelStats(result.volume, thalamus);
    if (stats.voxel_count > 0) y = std::round(stats.centroid_mm.y());
  }
  cuts.push_back({CutAxis::kCoronal, std::clamp(y, lo.y(), hi.y())});

  const double x = std::round(0.5 * (lo.x() + hi.x()) + 0.4 * 0.5 * (hi.x() - lo.x()));
  cuts.push_back({CutAxis::kSagittal, std::clamp(x, lo.x(), hi.x())});
  return cuts;
}

}  // namespace

Status WriteAtlasPictures(const AtlasBuildResult& result, const fs::path& dir,
                          const AtlasPictureOptions& options, std::vector<std::string>* written) {
  PBA_RETURN_IF_ERROR(options.Validate());
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Io("cannot create " + dir.string() + ": " + ec.message());
  const std::string notice = result.synthetic ? kSyntheticAtlasNotice : "";
  std::vector<std::string> names;
  if (result.plates) {
    PBA_RETURN_IF_ERROR(WritePlateContactSheet(*result.plates, dir / "plates.png", notice));
    names.push_back("plates.png");
  }
  std::vector<Cut> cuts;
  for (double z : options.axial_z_mm) cuts.push_back({CutAxis::kAxial, z});
  for (double y : options.coronal_y_mm) cuts.push_back({CutAxis::kCoronal, y});
  for (double x : options.sagittal_x_mm) cuts.push_back({CutAxis::kSagittal, x});
  if (cuts.empty()) cuts = DefaultCuts(result);

  CutSource source;
  source.volume = &result.volume;
  source.plates = result.plates ? &*result.plates : nullptr;
  std::set<std::string> done;
  for (const Cut& cut : cuts) {
    const std::string name = CutFileName(cut.axis, cut.position_mm);
    if (!done.insert(name).second) continue;
    MeshCutOptions cut_options;
    cut_options.axis = cut.axis;
    cut_options.position_mm = cut.position_mm;
    cut_options.pixel_mm = options.pixel_mm;
    cut_options.notice = notice;
    PBA_RETURN_IF_ERROR(WriteMeshCut(result.mesh, result.region_labels, result.colours, source,
                                     cut_options, dir / name));
    names.push_back(name);
  }
  if (written != nullptr) *written = std::move(names);
  return Status::Ok();
}

}  // namespace pba
