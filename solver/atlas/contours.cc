// The JSON form of plate contours (contours.h). TraceContourPlate,
// TraceContours and RasterizeContourPlate live in contour_trace.cc.
#include "atlas/contours.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/number_format.h"
#include "core/yaml_guard.h"

namespace pba {
namespace {

// A plain (unquoted) scalar that reads as a finite or infinite double. JSON
// strings come out of yaml-cpp with the non-plain tag "!", so "1.5" quoted
// is not taken for a number.
bool ReadNumber(const YAML::Node& node, double* value) {
  if (!node || !node.IsScalar() || node.Tag() == "!") return false;
  return YAML::convert<double>::decode(node, *value);
}

// Twice the signed area of a closed polygon.
double TwiceArea(const std::vector<Eigen::Vector2d>& points) {
  double area = 0;
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = points[i];
    const Eigen::Vector2d& b = points[(i + 1) % n];
    area += a.x() * b.y() - b.x() * a.y();
  }
  return area;
}

}  // namespace

Status ParseContoursJson(std::string_view text, const std::string& field, Contours* contours) {
  const auto fail = [&field](const std::string& where, const std::string& what) {
    return Status::InvalidArgument(field, "contours JSON: " + where + ": " + what);
  };
  // JSON has no aliases, but the parser is YAML's: a contours file of
  // nested aliases kept the server busy for minutes (yaml_guard.h).
  const Status bounded = CheckYamlText(text, field);
  if (!bounded.ok()) return Status::InvalidArgument(field, "contours JSON: " + bounded.message());
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    return Status::InvalidArgument(field, std::string("is not valid JSON: ") + e.what());
  }
  Contours result;
  if (!root.IsMap()) return fail("top level", "expected an object {\"plates\": [...]}");
  if (const YAML::Node pixel = root["pixel_size_mm"]) {
    double h = 0;
    if (!ReadNumber(pixel, &h) || !(h > 0 && h <= 10)) {
      return fail("pixel_size_mm", "expected a pixel edge in mm in (0, 10]");
    }
    result.pixel_size_mm = h;
  }
  const YAML::Node plates = root["plates"];
  if (!plates || !plates.IsSequence() || plates.size() == 0) {
    return fail("plates", "expected a non-empty list of {\"z_mm\": ..., \"polygons\": [...]}");
  }
  for (size_t p = 0; p < plates.size(); ++p) {
    const std::string at = "plates[" + std::to_string(p) + "]";
    const YAML::Node plate = plates[p];
    if (!plate.IsMap()) return fail(at, "expected an object");
    ContourPlate out;
    if (!ReadNumber(plate["z_mm"], &out.z_mm) || !std::isfinite(out.z_mm) ||
        std::abs(out.z_mm) > kMaxAtlasCoordinateMm) {
      return fail(at + ".z_mm", "expected a height in mm within 500 mm of the origin");
    }
    for (const ContourPlate& other : result.plates) {
      if (other.z_mm == out.z_mm) return fail(at + ".z_mm", "another plate has this height");
    }
    const YAML::Node polygons = plate["polygons"];
    if (!polygons || !polygons.IsSequence() || polygons.size() == 0) {
      return fail(at + ".polygons", "expected a non-empty list of polygons");
    }
    for (size_t k = 0; k < polygons.size(); ++k) {
      const std::string poly = at + ".polygons[" + std::to_string(k) + "]";
      const YAML::Node points = polygons[k];
      if (!points.IsSequence() || points.size() < 3) {
        return fail(poly, "expected a list of at least three [x_mm, y_mm] points");
      }
      std::vector<Eigen::Vector2d> polygon;
      polygon.reserve(points.size());
      for (size_t i = 0; i < points.size(); ++i) {
        const YAML::Node point = points[i];
        double x = 0, y = 0;
        const bool ok = point.IsSequence() && point.size() == 2 && ReadNumber(point[0], &x) &&
                        ReadNumber(point[1], &y) && std::abs(x) <= kMaxAtlasCoordinateMm &&
                        std::abs(y) <= kMaxAtlasCoordinateMm;
        if (!ok) {
          return fail(poly + "[" + std::to_string(i) + "]",
                      "expected [x_mm, y_mm], numbers within 500 mm of the origin");
        }
        polygon.emplace_back(x, y);
      }
      if (TwiceArea(polygon) == 0) return fail(poly, "has no area (its points are collinear)");
      out.polygons.push_back(std::move(polygon));
    }
    result.plates.push_back(std::move(out));
  }
  std::sort(result.plates.begin(), result.plates.end(),
            [](const ContourPlate& a, const ContourPlate& b) { return a.z_mm < b.z_mm; });
  *contours = std::move(result);
  return Status::Ok();
}

std::string FormatContoursJson(const Contours& contours) {
  std::string out = "{\"format\": \"pba-contours\", \"version\": 1";
  if (contours.pixel_size_mm > 0)
    out += ", \"pixel_size_mm\": " + RoundTripNumber(contours.pixel_size_mm);
  out += ",\n \"plates\": [";
  for (size_t p = 0; p < contours.plates.size(); ++p) {
    const ContourPlate& plate = contours.plates[p];
    out += p == 0 ? "\n  " : ",\n  ";
    out += "{\"z_mm\": " + RoundTripNumber(plate.z_mm) + ", \"polygons\": [";
    for (size_t k = 0; k < plate.polygons.size(); ++k) {
      out += k == 0 ? "\n    [" : ",\n    [";
      for (size_t i = 0; i < plate.polygons[k].size(); ++i) {
        const Eigen::Vector2d& v = plate.polygons[k][i];
        if (i > 0) out += ", ";
        out += "[" + RoundTripNumber(v.x()) + ", " + RoundTripNumber(v.y()) + "]";
      }
      out += "]";
    }
    out += "]}";
  }
  out += "]}\n";
  return out;
}

}  // namespace pba
