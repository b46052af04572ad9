#include "service/geometry_check.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace pba {
namespace {

constexpr size_t kNiftiHeaderBytes = 348;

// The first `want` bytes of gzip data, or fewer if it is shorter or broken.
std::string Gunzip(std::string_view gz, size_t want) {
  std::string out(want, '\0');
  z_stream stream{};
  // 16 + MAX_WBITS: expect a gzip header.
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return "";
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  stream.avail_in = static_cast<uInt>(std::min<size_t>(gz.size(), UINT32_MAX));
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(want);
  int result = Z_OK;
  while (stream.avail_out > 0 && result == Z_OK) result = inflate(&stream, Z_NO_FLUSH);
  out.resize(want - stream.avail_out);
  inflateEnd(&stream);
  return out;
}

Status CheckNifti(std::string_view field, std::string_view content) {
  std::string inflated;
  if (content.size() >= 2 && static_cast<unsigned char>(content[0]) == 0x1f &&
      static_cast<unsigned char>(content[1]) == 0x8b) {
    inflated = Gunzip(content, kNiftiHeaderBytes);
    content = inflated;
  }
  if (content.size() < kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: shorter than the 348-byte header");
  }
  uint32_t sizeof_hdr = 0;
  std::memcpy(&sizeof_hdr, content.data(), 4);
  const uint32_t swapped = __builtin_bswap32(sizeof_hdr);
  if (sizeof_hdr != kNiftiHeaderBytes && swapped != kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field), "is not NIfTI-1: sizeof_hdr is not 348");
  }
  const std::string_view magic = content.substr(344, 4);
  if (magic != std::string_view("n+1\0", 4) && magic != std::string_view("ni1\0", 4)) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: the magic is not \"n+1\" or \"ni1\"");
  }
  return Status::Ok();
}

// Coordinates farther than this from the atlas origin are refused: an atlas
// spans at most a metre (pba-atlas refuses larger ones), so such a value is
// a unit mistake (metres, micrometres) or garbage.
constexpr double kMaxCoordinateMm = 500;

bool IsNumber(const google::protobuf::Value& v) {
  return v.kind_case() == google::protobuf::Value::kNumberValue;
}

// Twice the signed area of a polygon given as [[x, y], ...].
double TwiceArea(const google::protobuf::ListValue& points) {
  double area = 0;
  const int n = points.values_size();
  for (int i = 0; i < n; ++i) {
    const auto& a = points.values(i).list_value();
    const auto& b = points.values((i + 1) % n).list_value();
    area += a.values(0).number_value() * b.values(1).number_value() -
            b.values(0).number_value() * a.values(1).number_value();
  }
  return area;
}

// The plate-contour form of a structure:
//   {"plates": [{"z_mm": Z, "polygons": [[[x_mm, y_mm], ...], ...]}, ...]}
// at least one plate, plates at distinct heights, each with at least one
// polygon of at least three points and non-zero area, every coordinate a
// finite number within kMaxCoordinateMm of the origin. A polygon is closed
// by its last point joining its first. Other keys are allowed (comments,
// provenance).
Status CheckContoursJson(std::string_view field, std::string_view content) {
  google::protobuf::Value value;
  const auto parsed = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(content.data(), content.size()), &value);
  const std::string f(field);
  if (!parsed.ok()) return Status::InvalidArgument(f, "is not valid JSON: " + parsed.ToString());
  const auto fail = [&f](const std::string& where, const std::string& what) {
    return Status::InvalidArgument(f, "contours JSON: " + where + ": " + what);
  };
  if (!value.has_struct_value()) {
    return fail("top level", "expected an object {\"plates\": [...]}");
  }
  const auto& top = value.struct_value().fields();
  const auto plates_it = top.find("plates");
  if (plates_it == top.end() || !plates_it->second.has_list_value() ||
      plates_it->second.list_value().values_size() == 0) {
    return fail("plates", "expected a non-empty list of {\"z_mm\": ..., \"polygons\": [...]}");
  }
  const auto& plates = plates_it->second.list_value();
  std::vector<double> heights;
  for (int p = 0; p < plates.values_size(); ++p) {
    const std::string at = "plates[" + std::to_string(p) + "]";
    if (!plates.values(p).has_struct_value()) return fail(at, "expected an object");
    const auto& plate = plates.values(p).struct_value().fields();
    const auto z = plate.find("z_mm");
    if (z == plate.end() || !IsNumber(z->second) || !std::isfinite(z->second.number_value()) ||
        std::abs(z->second.number_value()) > kMaxCoordinateMm) {
      return fail(at + ".z_mm", "expected a height in mm within 500 mm of the origin");
    }
    for (double h : heights) {
      if (h == z->second.number_value()) {
        return fail(at + ".z_mm", "another plate has this height");
      }
    }
    heights.push_back(z->second.number_value());
    const auto polygons = plate.find("polygons");
    if (polygons == plate.end() || !polygons->second.has_list_value() ||
        polygons->second.list_value().values_size() == 0) {
      return fail(at + ".polygons", "expected a non-empty list of polygons");
    }
    const auto& list = polygons->second.list_value();
    for (int k = 0; k < list.values_size(); ++k) {
      const std::string poly = at + ".polygons[" + std::to_string(k) + "]";
      if (!list.values(k).has_list_value() || list.values(k).list_value().values_size() < 3) {
        return fail(poly, "expected a list of at least three [x_mm, y_mm] points");
      }
      const auto& points = list.values(k).list_value();
      for (int i = 0; i < points.values_size(); ++i) {
        const auto& pt = points.values(i);
        const bool ok = pt.has_list_value() && pt.list_value().values_size() == 2 &&
                        IsNumber(pt.list_value().values(0)) &&
                        IsNumber(pt.list_value().values(1)) &&
                        std::abs(pt.list_value().values(0).number_value()) <= kMaxCoordinateMm &&
                        std::abs(pt.list_value().values(1).number_value()) <= kMaxCoordinateMm;
        if (!ok) {
          return fail(poly + "[" + std::to_string(i) + "]",
                      "expected [x_mm, y_mm], numbers within 500 mm of the origin");
        }
      }
      if (TwiceArea(points) == 0) return fail(poly, "has no area (its points are collinear)");
    }
  }
  return Status::Ok();
}

}  // namespace

Status CheckGeometryContent(std::string_view field, GeometryFormat format,
                            std::string_view content) {
  if (content.empty()) return Status::InvalidArgument(std::string(field), "must not be empty");
  switch (format) {
    case GeometryFormat::kContoursJson:
      return CheckContoursJson(field, content);
    case GeometryFormat::kNifti:
      return CheckNifti(field, content);
    case GeometryFormat::kStl:
    case GeometryFormat::kObj:
    case GeometryFormat::kVtk:
      return Status::Ok();
  }
  return Status::InvalidArgument(std::string(field), "unknown geometry format");
}

}  // namespace pba
