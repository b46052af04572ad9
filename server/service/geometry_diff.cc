#include "service/geometry_diff.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {
namespace {

using Point = std::array<double, 2>;
using Polygons = std::vector<std::vector<Point>>;

double SegmentDistance(const Point& p, const Point& a, const Point& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double length2 = dx * dx + dy * dy;
  double t = length2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double x = a[0] + t * dx - p[0], y = a[1] + t * dy - p[1];
  return std::sqrt(x * x + y * y);
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
      const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
      const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
      for (int k = 0; k < n; ++k) {  // the edge's end is the next edge's start
        const double t = static_cast<double>(k) / n;
        const Point p{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
        const double d = DistanceToContours(p, to);
        *largest = std::max(*largest, d);
        *sum += d;
        ++*count;
      }
    }
  }
}

}  // namespace

Status ParseContours(std::string_view json, std::vector<ContourPlate>* plates) {
  google::protobuf::Value value;
  const auto parsed = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), &value);
  if (!parsed.ok()) return Status::InvalidArgument("contours", parsed.ToString());
  plates->clear();
  const auto& top = value.struct_value().fields();
  const auto it = top.find("plates");
  if (it == top.end()) return Status::InvalidArgument("contours", "no plates");
  for (const auto& p : it->second.list_value().values()) {
    const auto& fields = p.struct_value().fields();
    ContourPlate plate;
    plate.z_mm = fields.at("z_mm").number_value();
    for (const auto& polygon : fields.at("polygons").list_value().values()) {
      plate.polygons.emplace_back();
      for (const auto& point : polygon.list_value().values()) {
        plate.polygons.back().push_back({point.list_value().values(0).number_value(),
                                         point.list_value().values(1).number_value()});
      }
    }
    plates->push_back(std::move(plate));
  }
  std::sort(plates->begin(), plates->end(),
            [](const ContourPlate& a, const ContourPlate& b) { return a.z_mm < b.z_mm; });
  return Status::Ok();
}

double PlateArea(const ContourPlate& plate) {
  double total = 0;
  for (const auto& polygon : plate.polygons) {
    double twice = 0;
    for (size_t i = 0; i < polygon.size(); ++i) {
      const Point& a = polygon[i];
      const Point& b = polygon[(i + 1) % polygon.size()];
      twice += a[0] * b[1] - b[0] * a[1];
    }
    total += std::abs(twice) / 2;
  }
  return total;
}

double ContoursVolume(const std::vector<ContourPlate>& plates) {
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

ContoursDistance DistanceBetween(const std::vector<ContourPlate>& a,
                                 const std::vector<ContourPlate>& b, double step_mm) {
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

}  // namespace pba
