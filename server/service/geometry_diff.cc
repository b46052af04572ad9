#include "service/geometry_diff.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <tuple>

#include "atlas/label_volume.h"
#include "atlas/label_volume_io.h"
#include "atlas/surface_io.h"
#include "core/atomic_write.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

using Point = Eigen::Vector2d;
using Polygons = std::vector<std::vector<Point>>;

double SegmentDistance(const Point& p, const Point& a, const Point& b) {
  const Point ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double DistanceToContours(const Point& p, const Polygons& polygons) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& polygon : polygons) {
    for (size_t i = 0; i < polygon.size(); ++i) {
      best = std::min(best, SegmentDistance(p, polygon[i], polygon[(i + 1) % polygon.size()]));
    }
  }
  return best;
}

// Samples of `from`'s edges: their distances to `to`, accumulated.
void Accumulate(const Polygons& from, const Polygons& to, double step, double* largest, double* sum,
                int64_t* count) {
  for (const auto& polygon : from) {
    for (size_t i = 0; i < polygon.size(); ++i) {
      const Point& a = polygon[i];
      const Point& b = polygon[(i + 1) % polygon.size()];
      const double length = (b - a).norm();
      const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
      for (int k = 0; k < n; ++k) {  // the edge's end is the next edge's start
        const double t = static_cast<double>(k) / n;
        const Point p = a + t * (b - a);
        const double d = DistanceToContours(p, to);
        *largest = std::max(*largest, d);
        *sum += d;
        ++*count;
      }
    }
  }
}

}  // namespace

double PlateArea(const ContourPlate& plate) {
  double total = 0;
  for (const auto& polygon : plate.polygons) {
    double twice = 0;
    for (size_t i = 0; i < polygon.size(); ++i) {
      const Point& a = polygon[i];
      const Point& b = polygon[(i + 1) % polygon.size()];
      twice += a.x() * b.y() - b.x() * a.y();
    }
    total += std::abs(twice) / 2;
  }
  return total;
}

double ContoursVolume(const Contours& contours) {
  const std::vector<ContourPlate>& plates = contours.plates;
  if (plates.size() < 2) return 0;
  double volume = 0;
  for (size_t i = 0; i < plates.size(); ++i) {
    const double below =
        i > 0 ? (plates[i].z_mm - plates[i - 1].z_mm) / 2 : (plates[1].z_mm - plates[0].z_mm) / 2;
    const double above = i + 1 < plates.size() ? (plates[i + 1].z_mm - plates[i].z_mm) / 2
                                               : (plates[i].z_mm - plates[i - 1].z_mm) / 2;
    volume += PlateArea(plates[i]) * (below + above);
  }
  return volume;
}

ContoursDistance DistanceBetween(const Contours& contours_a, const Contours& contours_b,
                                 double step_mm) {
  const std::vector<ContourPlate>& a = contours_a.plates;
  const std::vector<ContourPlate>& b = contours_b.plates;
  constexpr double kSameHeight = 1e-6;
  ContoursDistance result;
  double sum = 0;
  int64_t count = 0;
  std::vector<bool> matched_b(b.size(), false);
  for (const ContourPlate& pa : a) {
    const auto match = std::find_if(b.begin(), b.end(), [&](const ContourPlate& pb) {
      return std::abs(pb.z_mm - pa.z_mm) <= kSameHeight;
    });
    if (match == b.end()) {
      result.only_in_a_z_mm.push_back(pa.z_mm);
      continue;
    }
    matched_b[match - b.begin()] = true;
    ++result.plates_compared;
    Accumulate(pa.polygons, match->polygons, step_mm, &result.hausdorff_mm, &sum, &count);
    Accumulate(match->polygons, pa.polygons, step_mm, &result.hausdorff_mm, &sum, &count);
  }
  for (size_t i = 0; i < b.size(); ++i) {
    if (!matched_b[i]) result.only_in_b_z_mm.push_back(b[i].z_mm);
  }
  result.mean_mm = count > 0 ? sum / static_cast<double>(count) : 0;
  return result;
}

namespace {

// The box of one geometry [mm], grown to take it in.
Status AddBox(StructureFormat format, std::string_view bytes, const char* field,
              Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  const auto add = [&](const Eigen::Vector3d& p) {
    *lo = lo->cwiseMin(p);
    *hi = hi->cwiseMax(p);
  };
  switch (format) {
    case StructureFormat::kContours: {
      Contours contours;
      PBA_RETURN_IF_ERROR(ParseContoursJson(bytes, field, &contours));
      for (const ContourPlate& plate : contours.plates) {
        for (const auto& polygon : plate.polygons) {
          for (const Point& p : polygon) add({p.x(), p.y(), plate.z_mm});
        }
      }
      return Status::Ok();
    }
    case StructureFormat::kNifti: {
      // The header's grid is enough, but the reader takes a file and reads
      // it whole; a mask's bytes were bounded by the upload.
      std::string pattern = (fs::temp_directory_path() / "pba-diff-box-XXXXXX").string();
      if (::mkdtemp(pattern.data()) == nullptr) {
        return Status::Io("cannot create a scratch directory");
      }
      const bool gzip = bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f &&
                        static_cast<unsigned char>(bytes[1]) == 0x8b;
      const fs::path file = fs::path(pattern) / (gzip ? "mask.nii.gz" : "mask.nii");
      Status status = AtomicWriteText(file, bytes);
      LabelVolume mask;
      if (status.ok()) status = ReadNifti(file, &mask);
      std::error_code ignored;
      fs::remove_all(pattern, ignored);
      if (!status.ok()) return Status::InvalidArgument(field, status.message());
      const Eigen::Vector3d half = mask.spacing_mm().cwiseAbs() / 2;
      for (int corner = 0; corner < 8; ++corner) {
        Eigen::Vector3d p;
        for (int axis = 0; axis < 3; ++axis) {
          p[axis] = (corner >> axis & 1) ? mask.dims()[axis] - 1 : 0;
        }
        add(mask.origin_mm() + mask.spacing_mm().cwiseProduct(p) - half);
        add(mask.origin_mm() + mask.spacing_mm().cwiseProduct(p) + half);
      }
      return Status::Ok();
    }
    case StructureFormat::kStl:
    case StructureFormat::kObj:
    case StructureFormat::kVtk: {
      TriangleSurface surface;
      PBA_RETURN_IF_ERROR(ReadSurface(bytes, format, field, &surface));
      for (const Eigen::Vector3d& p : surface.points) add(p);
      return Status::Ok();
    }
    case StructureFormat::kDerived:
      return Status::InvalidArgument(field, "a derived structure has no shape of its own");
  }
  return Status::Internal("unknown geometry format");
}

}  // namespace

Status DiffGridVoxels(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                      std::string_view b, double voxel_mm, double* voxels) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  PBA_RETURN_IF_ERROR(AddBox(format_a, a, "from", &lo, &hi));
  PBA_RETURN_IF_ERROR(AddBox(format_b, b, "to", &lo, &hi));
  if (!(lo.array() <= hi.array()).all()) {
    *voxels = 0;
    return Status::Ok();
  }
  // As ComposeStructureSet lays its grid: two voxels of margin each side,
  // one more for the rounding of either end (and one for a plate's loft).
  constexpr int kMargin = 2;
  *voxels = 1;
  for (int axis = 0; axis < 3; ++axis) {
    *voxels *= std::ceil((hi[axis] - lo[axis]) / voxel_mm) + 2 * kMargin + 3;
  }
  return Status::Ok();
}

Status ChooseDiffVoxel(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                       std::string_view b, double voxel_mm, int64_t max_voxels, double* chosen_mm) {
  double at_base = 0;
  PBA_RETURN_IF_ERROR(DiffGridVoxels(format_a, a, format_b, b, voxel_mm, &at_base));
  *chosen_mm = voxel_mm;
  if (at_base <= static_cast<double>(max_voxels)) return Status::Ok();
  static constexpr double kSteps[] = {1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8};
  for (double decade = 1; decade <= 1e6; decade *= 10) {
    for (double step : kSteps) {
      const double v = voxel_mm * step * decade;
      if (v <= voxel_mm) continue;
      double voxels = 0;
      PBA_RETURN_IF_ERROR(DiffGridVoxels(format_a, a, format_b, b, v, &voxels));
      if (voxels <= static_cast<double>(max_voxels)) {
        *chosen_mm = v;
        return Status::Ok();
      }
    }
  }
  return Status::Internal("no voxel size fits the comparison's voxel budget");
}

Status CompareRevisionShapes(StructureFormat format_a, std::string_view a, StructureFormat format_b,
                             std::string_view b, double base_voxel_mm, int64_t max_voxels,
                             const std::function<bool()>& cancelled, ShapeComparison* comparison) {
  const auto stop = [&](const char* phase) {
    return Status::Cancelled(std::string("the comparison was cancelled ") + phase);
  };
  if (cancelled && cancelled()) return stop("before it started");
  double voxel_mm = base_voxel_mm;
  PBA_RETURN_IF_ERROR(
      ChooseDiffVoxel(format_a, a, format_b, b, base_voxel_mm, max_voxels, &voxel_mm));
  if (cancelled && cancelled()) return stop("after sizing its grid");
  std::string pattern = (fs::temp_directory_path() / "pba-diff-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) return Status::Io("cannot create a scratch directory");
  const fs::path dir = pattern;
  StructureGeometry ga, gb;
  Status status = Status::Ok();
  for (auto [name, format, bytes, geometry] :
       {std::tuple{"a", format_a, a, &ga}, std::tuple{"b", format_b, b, &gb}}) {
    geometry->file = dir / name;
    geometry->format = format;
    if (status.ok()) status = AtomicWriteText(geometry->file, bytes);
  }
  if (status.ok() && cancelled && cancelled()) status = stop("before voxelising");
  if (status.ok()) status = CompareShapes(ga, gb, voxel_mm, comparison);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  return status;
}

}  // namespace pba
