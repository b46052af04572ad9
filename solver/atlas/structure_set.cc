// Structure sets (structure_set.h): the manifest, and composing the
// structures into the plates or the label volume BuildAtlas meshes.
#include "atlas/structure_set.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include "atlas/contours.h"
#include "atlas/derived_structure.h"
#include "atlas/label_volume_io.h"
#include "atlas/loft.h"
#include "atlas/surface_io.h"
#include "core/atomic_write.h"
#include "core/format.h"
#include "core/sha256.h"
#include "core/yaml_guard.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr char kManifestFormat[] = "pba-structure-set";

bool SafeFileName(const std::string& name) {
  if (name.empty() || name == "." || name == "..") return false;
  for (unsigned char c : name) {
    if (c == '/' || c == '\\' || c < 0x20 || c == 0x7f) return false;
  }
  return true;
}

bool GoodName(const std::string& name) {
  if (name.empty()) return false;
  for (unsigned char c : name) {
    if (c == '/' || c == '\\' || c == ',' || c < 0x20 || c == 0x7f) return false;
  }
  return true;
}

Status ReadFile(const fs::path& path, std::string* content) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot open " + path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return Status::Io("cannot read " + path.string());
  *content = buffer.str();
  return Status::Ok();
}

// "r,g,b", each 0..255 (spaces around the numbers allowed).
bool ParseColour(const std::string& text, uint8_t rgb[3]) {
  std::istringstream in(text);
  for (int k = 0; k < 3; ++k) {
    int v = -1;
    if (!(in >> v) || v < 0 || v > 255) return false;
    rgb[k] = static_cast<uint8_t>(v);
    char comma = 0;
    if (k < 2 && (!(in >> comma) || comma != ',')) return false;
  }
  std::string rest;
  return !(in >> rest);
}

// Indices of the structures in byte-wise order of their names: label
// order[i] is i + 1.
std::vector<int> NameOrder(const StructureSet& set) {
  std::vector<int> order(set.structures.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&set](int a, int b) {
    return set.structures[a].name < set.structures[b].name;  // char_traits: unsigned bytes
  });
  return order;
}

// Overlap tallies: (height or -1, kept label, lost label) -> cells.
using OverlapCounts = std::map<std::tuple<int, uint16_t, uint16_t>, int64_t>;

void ReportOverlaps(const OverlapCounts& counts, const ColourTable& colours, double cell_measure,
                    const char* unit, const std::vector<double>& heights,
                    std::vector<std::string>* notes) {
  for (const auto& [key, n] : counts) {
    const auto& [plate, a, b] = key;
    std::string note =
        Format("%s and %s overlap on %lld %s (%g %s)", colours.FindByLabel(a)->name.c_str(),
               colours.FindByLabel(b)->name.c_str(), static_cast<long long>(n),
               plate >= 0 ? "pixels" : "voxels", n * cell_measure, unit);
    if (plate >= 0) note += Format(" at z = %g mm", heights[plate]);
    note += Format("; %s keeps them", colours.FindByLabel(a)->name.c_str());
    notes->push_back(note);
  }
}

// A grid of square pixels covering every polygon of `all` with `margin`
// pixels to spare. The first pixel centre is half a pixel inside the
// leftmost and the topmost point, so contours traced along the pixel faces
// of a grid of the same pixel size (TraceContours) land on its faces again.
void CoverContours(const std::vector<const Contours*>& all, double pixel_mm, int margin,
                   PlateStack* stack) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const Contours* c : all) {
    for (const ContourPlate& plate : c->plates) {
      for (const auto& polygon : plate.polygons) {
        for (const Eigen::Vector2d& v : polygon) {
          x0 = std::min(x0, v.x());
          x1 = std::max(x1, v.x());
          y0 = std::min(y0, v.y());
          y1 = std::max(y1, v.y());
        }
      }
    }
  }
  stack->pixel_size_mm = pixel_mm;
  stack->origin_mm =
      Eigen::Vector2d(x0 + pixel_mm / 2 - margin * pixel_mm, y1 - pixel_mm / 2 + margin * pixel_mm);
  stack->width = static_cast<int>(std::ceil((x1 - x0) / pixel_mm - 1e-9)) + 2 * margin;
  stack->height = static_cast<int>(std::ceil((y1 - y0) / pixel_mm - 1e-9)) + 2 * margin;
}

// Pixel edge for contours: the option, else the finest the contours carry,
// else 0.5 mm.
double ContourPixelMm(const std::vector<const Contours*>& all, double option) {
  if (option > 0) return option;
  double finest = 0;
  for (const Contours* c : all) {
    if (c->pixel_size_mm > 0 && (finest == 0 || c->pixel_size_mm < finest)) {
      finest = c->pixel_size_mm;
    }
  }
  return finest > 0 ? finest : 0.5;
}

// A stack of one structure's own plates (label 1) on `grid`'s pixels.
Status OneStructureStack(const Contours& contours, const PlateStack& grid, PlateStack* stack) {
  stack->pixel_size_mm = grid.pixel_size_mm;
  stack->origin_mm = grid.origin_mm;
  stack->width = grid.width;
  stack->height = grid.height;
  stack->z_mm.clear();
  stack->labels.clear();
  stack->files.clear();
  for (const ContourPlate& plate : contours.plates) {
    stack->z_mm.push_back(plate.z_mm);
    stack->files.push_back(Format("plate_%02d.png", static_cast<int>(stack->files.size()) + 1));
    stack->labels.emplace_back(static_cast<size_t>(grid.width) * grid.height, 0);
    RasterizeContourPlate(plate, grid.origin_mm, grid.pixel_size_mm, grid.width, grid.height, 1,
                          &stack->labels.back());
  }
  return ColourTable::FromEntries({{1, "structure", 255, 255, 255}}, &stack->colours);
}

// The loft of one structure's contours. One plate alone gets an empty plate
// a voxel above and below it (the loft needs two), so it becomes a lens a
// voxel thick.
Status LoftOne(const Contours& contours, const PlateStack& grid, double voxel_mm, LoftField* loft) {
  Contours own = contours;
  if (own.plates.size() == 1) {
    const double z = own.plates[0].z_mm;
    ContourPlate below, above;
    below.z_mm = z - voxel_mm;
    above.z_mm = z + voxel_mm;
    own.plates.insert(own.plates.begin(), below);
    own.plates.push_back(above);
  }
  PlateStack stack;
  PBA_RETURN_IF_ERROR(OneStructureStack(own, grid, &stack));
  LoftOptions options;
  options.voxel_size_mm = voxel_mm;
  return loft->Build(stack, options);
}

// The structures of a set as read from their files.
struct Loaded {
  std::vector<Contours> contours;         // per structure (kContours)
  std::vector<LabelVolume> masks;         // per structure (kNifti)
  std::vector<TriangleSurface> surfaces;  // per structure (surfaces)
};

Status LoadStructures(const fs::path& dir, const StructureSet& set, Loaded* loaded) {
  const size_t n = set.structures.size();
  loaded->contours.resize(n);
  loaded->masks.resize(n);
  loaded->surfaces.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const StructureEntry& e = set.structures[i];
    const std::string field = Format("structures[%d]", static_cast<int>(i));
    const fs::path path = dir / e.file;
    if (e.format == StructureFormat::kNifti) {
      Status s = ReadNifti(path, &loaded->masks[i]);
      if (!s.ok() && s.code() == Status::Code::kInvalidArgument) {
        return Status::InvalidArgument(field, "'" + e.name + "' (" + e.file + "): " + s.message());
      }
      PBA_RETURN_IF_ERROR(s);
      continue;
    }
    std::string content;
    PBA_RETURN_IF_ERROR(ReadFile(path, &content));
    Status s = e.format == StructureFormat::kContours
                   ? ParseContoursJson(content, field, &loaded->contours[i])
                   : ReadSurface(content, e.format, field, &loaded->surfaces[i]);
    if (!s.ok()) {
      return Status::InvalidArgument(field, "'" + e.name + "' (" + e.file + "): " + s.message());
    }
  }
  return Status::Ok();
}

Status ComposePlates(const StructureSet& set, const Loaded& loaded, const std::vector<int>& order,
                     const ComposeOptions& options, ComposedAtlas* atlas) {
  std::vector<const Contours*> all;
  for (const Contours& c : loaded.contours) all.push_back(&c);
  PlateStack stack;
  CoverContours(all, ContourPixelMm(all, options.pixel_size_mm), 3, &stack);
  std::set<double> heights;
  for (const Contours* c : all) {
    for (const ContourPlate& p : c->plates) heights.insert(p.z_mm);
  }
  if (heights.size() < 2) {
    return Status::InvalidArgument(
        "structures", Format("every structure is drawn at z = %g mm only: plates at two heights "
                             "at least are needed to make a volume",
                             *heights.begin()));
  }
  stack.z_mm.assign(heights.begin(), heights.end());
  const size_t pixels = static_cast<size_t>(stack.width) * stack.height;
  for (size_t p = 0; p < stack.z_mm.size(); ++p) {
    stack.files.push_back(Format("plate_%02d.png", static_cast<int>(p) + 1));
    stack.labels.emplace_back(pixels, 0);
  }
  OverlapCounts overlaps;
  std::vector<uint16_t> own(pixels);
  for (size_t rank = 0; rank < order.size(); ++rank) {
    const uint16_t label = static_cast<uint16_t>(rank + 1);
    const Contours& contours = loaded.contours[order[rank]];
    const double z_low = contours.plates.front().z_mm, z_high = contours.plates.back().z_mm;
    LoftField loft;  // built when a plate between its own needs it
    bool lofted = false;
    for (int p = 0; p < stack.num_plates(); ++p) {
      const double z = stack.z_mm[p];
      if (z < z_low || z > z_high) continue;
      std::fill(own.begin(), own.end(), 0);
      const auto drawn = std::find_if(contours.plates.begin(), contours.plates.end(),
                                      [z](const ContourPlate& c) { return c.z_mm == z; });
      if (drawn != contours.plates.end()) {
        RasterizeContourPlate(*drawn, stack.origin_mm, stack.pixel_size_mm, stack.width,
                              stack.height, 1, &own);
      } else {
        // Between two of its own plates: its section as its loft has it.
        if (!lofted) {
          PlateStack one;
          PBA_RETURN_IF_ERROR(OneStructureStack(contours, stack, &one));
          LoftOptions loft_options;
          loft_options.voxel_size_mm = std::max(2.0, stack.pixel_size_mm);
          PBA_RETURN_IF_ERROR(loft.Build(one, loft_options));
          lofted = true;
        }
        // Only pixels within its outline's box on any of its plates can be
        // inside (its field is +infinity beyond that box).
        double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
        for (const ContourPlate& own_plate : contours.plates) {
          for (const auto& polygon : own_plate.polygons) {
            for (const Eigen::Vector2d& v : polygon) {
              x0 = std::min(x0, v.x());
              x1 = std::max(x1, v.x());
              y0 = std::min(y0, v.y());
              y1 = std::max(y1, v.y());
            }
          }
        }
        const double h = stack.pixel_size_mm;
        const int c0 = std::max(0, static_cast<int>((x0 - stack.origin_mm.x()) / h) - 1);
        const int c1 =
            std::min(stack.width - 1, static_cast<int>((x1 - stack.origin_mm.x()) / h) + 1);
        const int r0 = std::max(0, static_cast<int>((stack.origin_mm.y() - y1) / h) - 1);
        const int r1 =
            std::min(stack.height - 1, static_cast<int>((stack.origin_mm.y() - y0) / h) + 1);
        for (int r = r0; r <= r1; ++r) {
          for (int c = c0; c <= c1; ++c) {
            if (loft.SignedDistance(1, stack.PixelCentreMm(p, c, r)) < 0) {
              own[static_cast<size_t>(r) * stack.width + c] = 1;
            }
          }
        }
      }
      std::vector<uint16_t>& plate = stack.labels[p];
      for (size_t i = 0; i < pixels; ++i) {
        if (own[i] == 0) continue;
        if (plate[i] == 0) {
          plate[i] = label;
        } else {
          ++overlaps[{p, plate[i], label}];
        }
      }
    }
  }
  stack.colours = atlas->colours;
  ReportOverlaps(overlaps, atlas->colours, stack.pixel_size_mm * stack.pixel_size_mm, "mm^2",
                 stack.z_mm, &atlas->notes);
  atlas->plates = std::move(stack);
  return Status::Ok();
}

// Whether the z-ray's crossings below `z` are odd: `crossings` sorted.
bool OddBelow(const std::vector<double>& crossings, double z) {
  return (std::lower_bound(crossings.begin(), crossings.end(), z) - crossings.begin()) % 2 == 1;
}

// Fills `inside` (one flag per voxel of `grid`) with the voxels whose centre
// a closed surface encloses: per (x, y) column the heights where a ray along
// z crosses the triangles, a voxel inside when an odd number lie below its
// centre. The ray is moved off the column centre by a tiny irrational
// fraction of a voxel so that it passes through no edge or vertex of a
// surface drawn on the same grid.
void SurfaceInside(const TriangleSurface& surface, const LabelVolume& grid,
                   std::vector<uint8_t>* inside) {
  const double v = grid.spacing_mm().x();
  const Eigen::Vector2d jitter(0.3183098861837907e-5 * v, 0.2718281828459045e-5 * v);
  const int nx = grid.nx(), ny = grid.ny();
  // Triangles binned by the columns their x-y bounding box covers.
  std::vector<std::vector<int>> columns(static_cast<size_t>(nx) * ny);
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(surface.points[surface.triangles[t][k]].head<2>());
      hi = hi.cwiseMax(surface.points[surface.triangles[t][k]].head<2>());
    }
    const Eigen::Vector3d a = grid.MmToVoxel(Eigen::Vector3d(lo.x(), lo.y(), 0));
    const Eigen::Vector3d b = grid.MmToVoxel(Eigen::Vector3d(hi.x(), hi.y(), 0));
    const int i0 = std::max(0, static_cast<int>(std::floor(a.x()))),
              i1 = std::min(nx - 1, static_cast<int>(std::ceil(b.x())));
    const int j0 = std::max(0, static_cast<int>(std::floor(a.y()))),
              j1 = std::min(ny - 1, static_cast<int>(std::ceil(b.y())));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        columns[static_cast<size_t>(j) * nx + i].push_back(static_cast<int>(t));
      }
    }
  }
  std::vector<double> crossings;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const auto& candidates = columns[static_cast<size_t>(j) * nx + i];
      if (candidates.empty()) continue;
      const Eigen::Vector3d centre = grid.VoxelCentreMm(i, j, 0);
      const Eigen::Vector2d q = centre.head<2>() + jitter;
      crossings.clear();
      for (int t : candidates) {
        const Eigen::Vector3d& a = surface.points[surface.triangles[t][0]];
        const Eigen::Vector3d& b = surface.points[surface.triangles[t][1]];
        const Eigen::Vector3d& c = surface.points[surface.triangles[t][2]];
        // Barycentric coordinates of q in the triangle's x-y projection.
        const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
        if (det == 0) continue;  // seen edge-on: the ray does not cross it
        const double u =
            ((q.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (q.y() - a.y())) / det;
        const double w =
            ((b.x() - a.x()) * (q.y() - a.y()) - (q.x() - a.x()) * (b.y() - a.y())) / det;
        if (u < 0 || w < 0 || u + w > 1) continue;
        crossings.push_back(a.z() + u * (b.z() - a.z()) + w * (c.z() - a.z()));
      }
      std::sort(crossings.begin(), crossings.end());
      for (int k = 0; k < grid.nz(); ++k) {
        if (OddBelow(crossings, grid.VoxelCentreMm(i, j, k).z())) {
          (*inside)[grid.Index(i, j, k)] = 1;
        }
      }
    }
  }
}

// The x-y-z box a structure occupies [mm], loft extrapolation included
// (contours on one plate only: `voxel_mm` either side, as LoftOne makes
// them).
void StructureBox(const StructureEntry& e, const Loaded& loaded, size_t i, double voxel_mm,
                  Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(INFINITY);
  *hi = Eigen::Vector3d::Constant(-INFINITY);
  if (e.format == StructureFormat::kNifti) {
    const LabelVolume& m = loaded.masks[i];
    for (int k = 0; k < m.nz(); ++k) {
      for (int j = 0; j < m.ny(); ++j) {
        for (int x = 0; x < m.nx(); ++x) {
          if (m.at(x, j, k) == 0) continue;
          const Eigen::Vector3d c = m.VoxelCentreMm(x, j, k);
          *lo = lo->cwiseMin(c - m.spacing_mm() / 2);
          *hi = hi->cwiseMax(c + m.spacing_mm() / 2);
        }
      }
    }
  } else if (e.format == StructureFormat::kContours) {
    const Contours& c = loaded.contours[i];
    for (const ContourPlate& plate : c.plates) {
      for (const auto& polygon : plate.polygons) {
        for (const Eigen::Vector2d& v : polygon) {
          *lo = lo->cwiseMin(Eigen::Vector3d(v.x(), v.y(), plate.z_mm));
          *hi = hi->cwiseMax(Eigen::Vector3d(v.x(), v.y(), plate.z_mm));
        }
      }
    }
    // The loft runs on half a plate spacing beyond each end plate.
    const size_t n = c.plates.size();
    const double below = n > 1 ? (c.plates[1].z_mm - c.plates[0].z_mm) / 2 : voxel_mm;
    const double above = n > 1 ? (c.plates[n - 1].z_mm - c.plates[n - 2].z_mm) / 2 : voxel_mm;
    lo->z() -= below;
    hi->z() += above;
  } else {
    for (const Eigen::Vector3d& p : loaded.surfaces[i].points) {
      *lo = lo->cwiseMin(p);
      *hi = hi->cwiseMax(p);
    }
  }
}

Status ComposeVolume(const StructureSet& set, const Loaded& loaded, const std::vector<int>& order,
                     const ComposeOptions& options, ComposedAtlas* atlas) {
  double v = options.voxel_size_mm;
  if (v == 0) {  // the masks' own voxels
    v = INFINITY;
    for (const LabelVolume& mask : loaded.masks) {
      if (mask.num_voxels() > 0) v = std::min(v, mask.spacing_mm().minCoeff());
    }
    if (!std::isfinite(v)) v = 1.0;
  }
  if (!(v > 0) || !std::isfinite(v)) {
    return Status::InvalidArgument("voxel_size_mm", "must be positive (or 0: the masks' own)");
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY);
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-INFINITY);
  for (size_t i = 0; i < set.structures.size(); ++i) {
    Eigen::Vector3d a, b;
    StructureBox(set.structures[i], loaded, i, v, &a, &b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
  }
  if (!(lo.array() <= hi.array()).all()) {
    return Status::InvalidArgument("structures", "no structure has a voxel, surface or contour");
  }
  // Two voxels of background around everything, voxel centres on multiples
  // of the voxel edge.
  const int margin = 2;
  const Eigen::Vector3d origin =
      ((lo / v).array().floor() * v).matrix() - Eigen::Vector3d::Constant(margin * v);
  std::array<int, 3> dims;
  double count = 1;
  for (int a = 0; a < 3; ++a) {
    dims[a] = static_cast<int>(std::ceil((hi[a] - origin[a]) / v)) + margin + 1;
    count *= dims[a];
  }
  if (count > 2e9) {
    return Status::InvalidArgument(
        "voxel_size_mm", Format("%g mm voxels over %g x %g x %g mm make too many voxels", v,
                                hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - lo.z()));
  }
  LabelVolume volume(dims, origin, Eigen::Vector3d::Constant(v));
  std::vector<uint16_t>& labels = volume.mutable_labels();
  std::vector<uint8_t> inside(labels.size());
  OverlapCounts overlaps;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    const uint16_t label = static_cast<uint16_t>(rank + 1);
    const int i = order[rank];
    const StructureEntry& e = set.structures[i];
    std::fill(inside.begin(), inside.end(), 0);
    // The voxels whose centres lie in the structure's box.
    Eigen::Vector3d box_lo, box_hi;
    StructureBox(e, loaded, i, v, &box_lo, &box_hi);
    std::array<int, 3> first, last;
    for (int a = 0; a < 3; ++a) {
      first[a] = std::max(0, static_cast<int>(std::floor((box_lo[a] - origin[a]) / v)));
      last[a] = std::min(dims[a] - 1, static_cast<int>(std::ceil((box_hi[a] - origin[a]) / v)));
    }
    if (e.format == StructureFormat::kNifti) {
      const LabelVolume& mask = loaded.masks[i];
      for (int k = first[2]; k <= last[2]; ++k) {
        for (int j = first[1]; j <= last[1]; ++j) {
          for (int x = first[0]; x <= last[0]; ++x) {
            if (mask.SampleNearest(volume.VoxelCentreMm(x, j, k)) != 0) {
              inside[volume.Index(x, j, k)] = 1;
            }
          }
        }
      }
    } else if (e.format == StructureFormat::kContours) {
      const Contours& contours = loaded.contours[i];
      PlateStack grid;
      CoverContours({&contours}, ContourPixelMm({&contours}, options.pixel_size_mm), 3, &grid);
      LoftField loft;
      PBA_RETURN_IF_ERROR(LoftOne(contours, grid, v, &loft));
      for (int k = first[2]; k <= last[2]; ++k) {
        for (int j = first[1]; j <= last[1]; ++j) {
          for (int x = first[0]; x <= last[0]; ++x) {
            const Eigen::Vector3d c = volume.VoxelCentreMm(x, j, k);
            if (loft.SignedDistance(1, c) < 0) inside[volume.Index(x, j, k)] = 1;
          }
        }
      }
    } else {
      SurfaceInside(loaded.surfaces[i], volume, &inside);
    }
    int64_t own = 0;
    for (size_t n = 0; n < labels.size(); ++n) {
      if (!inside[n]) continue;
      ++own;
      if (labels[n] == 0) {
        labels[n] = label;
      } else {
        ++overlaps[{-1, labels[n], label}];
      }
    }
    atlas->structure_mm3[e.name] = own * v * v * v;
  }
  ReportOverlaps(overlaps, atlas->colours, v * v * v, "mm^3", {}, &atlas->notes);
  for (const auto& [key, n] : overlaps) {
    const auto& [plate, kept, lost] = key;
    atlas->overlaps.push_back({atlas->colours.FindByLabel(kept)->name,
                               atlas->colours.FindByLabel(lost)->name, n * v * v * v});
  }
  atlas->volume = std::move(volume);
  return Status::Ok();
}

}  // namespace

bool IsStructureSetDir(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && fs::is_regular_file(dir / kStructureSetManifest, ec);
}

Status ReadStructureSet(const fs::path& dir, StructureSet* set) {
  const fs::path path = dir / kStructureSetManifest;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return Status::Io("missing " + path.string());
  const auto bad = [](const std::string& field, const std::string& what) {
    return Status::InvalidArgument(field, what);
  };
  StructureSet result;
  // Aliases refused and the size capped before loading (core/yaml_guard.h):
  // a set may come from anyone, and its manifest is walked entry by entry.
  std::string text;
  PBA_RETURN_IF_ERROR(ReadYamlFileText(path, kStructureSetManifest, &text));
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) return bad("manifest.json", "not a JSON object");
    if (root["format"] && root["format"].as<std::string>() != kManifestFormat) {
      return bad("format", std::string("expected \"") + kManifestFormat + "\"");
    }
    if (root["version"] && root["version"].as<int>() != 1) {
      return bad("version", "version " + root["version"].as<std::string>() +
                                " is not known (this reader knows 1)");
    }
    if (root["project"]) result.project = root["project"].as<std::string>();
    if (root["snapshot"]) result.snapshot = root["snapshot"].as<int64_t>();
    if (root["snapshot_name"]) result.snapshot_name = root["snapshot_name"].as<std::string>();
    const YAML::Node structures = root["structures"];
    if (!structures || !structures.IsSequence() || structures.size() == 0) {
      return bad("structures", "expected a non-empty list of structures");
    }
    std::set<std::string> names;
    std::map<std::array<uint8_t, 3>, std::string> colours;  // -> the structure that has it
    for (size_t i = 0; i < structures.size(); ++i) {
      const YAML::Node s = structures[i];
      const std::string at = Format("structures[%d]", static_cast<int>(i));
      if (!s.IsMap()) return bad(at, "expected an object");
      StructureEntry e;
      if (!s["name"] || !s["name"].IsScalar()) return bad(at + ".name", "missing");
      e.name = s["name"].as<std::string>();
      if (!GoodName(e.name)) {
        return bad(at + ".name", "'" + e.name +
                                     "' is not a structure name (empty, or with '/', '\\', ',' "
                                     "or a control character)");
      }
      if (!names.insert(e.name).second) {
        return bad(at + ".name", "'" + e.name + "' names another structure too");
      }
      const std::string who = "structure '" + e.name + "': ";
      if (!s["file"] || !s["file"].IsScalar()) return bad(at + ".file", who + "missing");
      e.file = s["file"].as<std::string>();
      if (!SafeFileName(e.file)) {
        return bad(at + ".file", who + "'" + e.file + "' is not a plain file name");
      }
      if (e.file == kStructureSetManifest) {
        return bad(at + ".file", who + "'" + e.file + "' is the manifest, not a structure's file");
      }
      if (!fs::is_regular_file(dir / e.file, ec)) {
        return bad(at + ".file", who + "no file '" + e.file + "' in the set's directory");
      }
      const std::string format = s["format"] ? s["format"].as<std::string>() : "";
      if (!ParseStructureFormat(format, &e.format)) {
        return bad(at + ".format",
                   who + "'" + format +
                       "' is not a format (contours_json, nifti, stl, obj, vtk, derived)");
      }
      uint8_t rgb[3] = {0, 0, 0};
      const std::string colour = s["colour"] ? s["colour"].as<std::string>() : "";
      if (!ParseColour(colour, rgb)) {
        return bad(at + ".colour", who + "'" + colour + "' is not \"r,g,b\" with values 0-255");
      }
      if (rgb[0] == 0 && rgb[1] == 0 && rgb[2] == 0) {
        return bad(at + ".colour", who + "black (0,0,0) is the background's colour");
      }
      if (const auto [it, first] =
              colours.emplace(std::array<uint8_t, 3>{rgb[0], rgb[1], rgb[2]}, e.name);
          !first) {
        return bad(at + ".colour", who + "colour " + colour + " is taken by structure '" +
                                       it->second + "' (each needs a colour of its own)");
      }
      e.r = rgb[0];
      e.g = rgb[1];
      e.b = rgb[2];
      if (s["sha256"]) {
        e.sha256 = s["sha256"].as<std::string>();
        if (e.sha256.size() != 64 ||
            e.sha256.find_first_not_of("0123456789abcdef") != std::string::npos) {
          return bad(at + ".sha256", who + "'" + e.sha256 + "' is not 64 lowercase hex digits");
        }
        std::string actual;
        PBA_RETURN_IF_ERROR(FileSha256Hex(dir / e.file, &actual));
        if (actual != e.sha256) {
          return bad(at + ".sha256", who + "file '" + e.file + "' has SHA-256 " + actual +
                                         ", the manifest says " + e.sha256);
        }
      }
      if (s["revision"]) e.revision = s["revision"].as<int64_t>();
      if (e.revision < 0) return bad(at + ".revision", who + "must not be negative");
      if (s["group_path"]) e.group_path = s["group_path"].as<std::string>();
      if (s["material_json"]) e.material_json = s["material_json"].as<std::string>();
      result.structures.push_back(std::move(e));
    }
  } catch (const YAML::Exception& e) {
    return bad("manifest.json", std::string("malformed: ") + e.what());
  }
  *set = std::move(result);
  return Status::Ok();
}

std::string StructureFileNames::Take(const std::string& stem, const std::string& extension) {
  for (int n = 1;; ++n) {
    const std::string candidate = (n == 1 ? stem : stem + "_" + std::to_string(n)) + extension;
    std::string folded = candidate;
    for (char& c : folded) {
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    }
    if (taken_.insert(folded).second) return candidate;
  }
}

Status WriteStructureSet(const StructureSet& set, const fs::path& dir) {
  for (size_t i = 0; i < set.structures.size(); ++i) {
    const StructureEntry& e = set.structures[i];
    if (e.file == kStructureSetManifest) {
      return Status::InvalidArgument(
          Format("structures[%d].file", static_cast<int>(i)),
          "structure '" + e.name + "': its file would be overwritten by the manifest");
    }
  }
  std::string out = std::string("{\"format\": \"") + kManifestFormat + "\", \"version\": 1";
  if (!set.project.empty()) out += ", \"project\": " + JsonQuoted(set.project);
  if (set.snapshot != 0)
    out += Format(", \"snapshot\": %lld", static_cast<long long>(set.snapshot));
  if (!set.snapshot_name.empty()) out += ", \"snapshot_name\": " + JsonQuoted(set.snapshot_name);
  out += ",\n \"structures\": [";
  for (size_t i = 0; i < set.structures.size(); ++i) {
    const StructureEntry& e = set.structures[i];
    out += i == 0 ? "\n  {" : ",\n  {";
    out += "\"name\": " + JsonQuoted(e.name) + ", \"file\": " + JsonQuoted(e.file) +
           ", \"format\": \"" + StructureFormatName(e.format) + "\"" +
           Format(", \"colour\": \"%d,%d,%d\"", e.r, e.g, e.b);
    if (!e.sha256.empty()) out += ", \"sha256\": " + JsonQuoted(e.sha256);
    if (e.revision != 0) out += Format(", \"revision\": %lld", static_cast<long long>(e.revision));
    if (!e.group_path.empty()) out += ", \"group_path\": " + JsonQuoted(e.group_path);
    if (!e.material_json.empty()) out += ", \"material_json\": " + JsonQuoted(e.material_json);
    out += "}";
  }
  out += "]}\n";
  return AtomicWriteText(dir / kStructureSetManifest, out);
}

namespace {

// The derived structures of `set` (their recipes read and parsed), in the
// order they are made; `base` gets the others.
Status SplitDerived(const fs::path& dir, const StructureSet& set, StructureSet* base,
                    std::vector<DerivedStructure>* derived) {
  base->structures.clear();
  std::vector<std::string> base_names;
  for (size_t i = 0; i < set.structures.size(); ++i) {
    const StructureEntry& e = set.structures[i];
    if (e.format != StructureFormat::kDerived) {
      base->structures.push_back(e);
      base_names.push_back(e.name);
      continue;
    }
    const std::string field = Format("structures[%zu]", i);
    // Read no further than a recipe may be: a set may come from anyone.
    std::string content;
    PBA_RETURN_IF_ERROR(ReadYamlFileText(dir / e.file, field, &content));
    DerivedStructure d;
    PBA_RETURN_IF_ERROR(ParseDerivedStructure(content, e.name, field, &d));
    d.field = field;
    derived->push_back(std::move(d));
  }
  if (base->structures.empty() && !derived->empty()) {
    return Status::InvalidArgument("structures",
                                   "every structure is derived: nothing to derive them from");
  }
  return OrderDerivedStructures(base_names, derived);
}

// Makes the derived structures on the composed volume, each in the colour
// the set gives it.
Status MakeDerived(const StructureSet& set, const std::vector<DerivedStructure>& derived,
                   ComposedAtlas* atlas) {
  LabelAtlas work{std::move(*atlas->volume), std::move(atlas->colours)};
  for (const DerivedStructure& d : derived) {
    std::vector<std::string> notes;
    if (Status s = ApplyLabelSteps({d.step}, &work, &notes); !s.ok()) {
      return Status::InvalidArgument(d.field, "derived structure '" + d.name + "': " + s.message());
    }
    for (const std::string& note : notes) {
      atlas->notes.push_back("derived structure '" + d.name + "' (" + LabelStepName(d.step.kind) +
                             "): " + note.substr(note.find(": ") + 2));
    }
    const StructureEntry& e =
        *std::find_if(set.structures.begin(), set.structures.end(),
                      [&](const StructureEntry& s) { return s.name == d.name; });
    std::vector<ColourEntry> entries = work.table.entries();
    int64_t voxels = 0;
    for (ColourEntry& c : entries) {
      if (c.name != d.name) continue;
      c.r = e.r;
      c.g = e.g;
      c.b = e.b;
      for (uint16_t l : work.volume.labels()) voxels += l == c.label;
    }
    PBA_RETURN_IF_ERROR(ColourTable::FromEntries(std::move(entries), &work.table));
    atlas->structure_mm3[d.name] = voxels * work.volume.voxel_volume_mm3();
  }
  atlas->volume = std::move(work.volume);
  atlas->colours = std::move(work.table);
  return Status::Ok();
}

}  // namespace

Status ComposeStructureSet(const fs::path& dir, const StructureSet& whole,
                           const ComposeOptions& options, ComposedAtlas* atlas) {
  if (whole.structures.empty()) return Status::InvalidArgument("structures", "no structures");
  if (whole.structures.size() > 65535) {
    return Status::InvalidArgument("structures", "more than 65535 structures");
  }
  if (options.pixel_size_mm < 0 || options.pixel_size_mm > 10) {
    return Status::InvalidArgument("pixel_size_mm", "must be 0 (default) or in (0, 10]");
  }
  // Derived structures are made on the voxels of the others.
  StructureSet set;
  std::vector<DerivedStructure> derived;
  PBA_RETURN_IF_ERROR(SplitDerived(dir, whole, &set, &derived));
  ComposedAtlas result;
  const std::vector<int> order = NameOrder(set);
  std::vector<ColourEntry> entries;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    const StructureEntry& e = set.structures[order[rank]];
    entries.push_back({static_cast<uint16_t>(rank + 1), e.name, e.r, e.g, e.b});
  }
  PBA_RETURN_IF_ERROR(ColourTable::FromEntries(std::move(entries), &result.colours));
  Loaded loaded;
  PBA_RETURN_IF_ERROR(LoadStructures(dir, set, &loaded));
  const bool all_contours =
      std::all_of(set.structures.begin(), set.structures.end(),
                  [](const StructureEntry& e) { return e.format == StructureFormat::kContours; });
  if (all_contours && !options.force_volume && derived.empty()) {
    PBA_RETURN_IF_ERROR(ComposePlates(set, loaded, order, options, &result));
  } else {
    PBA_RETURN_IF_ERROR(ComposeVolume(set, loaded, order, options, &result));
    PBA_RETURN_IF_ERROR(MakeDerived(whole, derived, &result));
  }
  *atlas = std::move(result);
  return Status::Ok();
}

}  // namespace pba
