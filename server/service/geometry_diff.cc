#include "service/geometry_diff.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <tuple>

#include "store/atomic_file.h"

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

Status CompareRevisionShapes(GeometryFormat format_a, std::string_view a, GeometryFormat format_b,
                             std::string_view b, double voxel_mm, ShapeComparison* comparison) {
  std::string pattern = (fs::temp_directory_path() / "pba-diff-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) return Status::Io("cannot create a scratch directory");
  const fs::path dir = pattern;
  StructureGeometry ga, gb;
  Status status = Status::Ok();
  for (auto [name, format, bytes, geometry] :
       {std::tuple{"a", format_a, a, &ga}, std::tuple{"b", format_b, b, &gb}}) {
    geometry->file = dir / name;
    ParseStructureFormat(GeometryFormatName(format), &geometry->format);
    if (status.ok()) status = WriteFileAtomically(geometry->file, bytes);
  }
  if (status.ok()) status = CompareShapes(ga, gb, voxel_mm, comparison);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  return status;
}

}  // namespace pba
