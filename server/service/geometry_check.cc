#include "service/geometry_check.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
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

// A closed triangulated surface read from STL, OBJ or legacy VTK: welded
// points and triangles by point index.
struct Surface {
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<int64_t, 3>> triangles;
};

// Welds points by their exact coordinates (STL repeats them per triangle).
class Welder {
 public:
  explicit Welder(Surface* surface) : surface_(surface) {}
  int64_t Add(const std::array<double, 3>& p) {
    Key key;
    std::memcpy(key.data(), p.data(), sizeof key);
    const auto [it, added] = index_.emplace(key, static_cast<int64_t>(surface_->points.size()));
    if (added) surface_->points.push_back(p);
    return it->second;
  }

 private:
  using Key = std::array<uint64_t, 3>;  // the coordinates' bits
  struct Hash {
    size_t operator()(const Key& k) const {
      uint64_t h = 1469598103934665603ull;
      for (uint64_t v : k) h = (h ^ v) * 1099511628211ull;
      return static_cast<size_t>(h);
    }
  };
  Surface* surface_;
  std::unordered_map<Key, int64_t, Hash> index_;
};

Status ReadStl(const std::string& f, std::string_view content, Surface* surface) {
  Welder welder(surface);
  // Binary: an 80-byte header, a triangle count, 50 bytes per triangle.
  if (content.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, content.data() + 80, 4);
    if (content.size() == 84 + 50 * static_cast<size_t>(count)) {
      for (uint32_t t = 0; t < count; ++t) {
        const char* facet = content.data() + 84 + 50 * static_cast<size_t>(t) + 12;
        std::array<int64_t, 3> triangle{};
        for (int k = 0; k < 3; ++k) {
          float xyz[3];
          std::memcpy(xyz, facet + 12 * k, 12);
          triangle[k] = welder.Add({xyz[0], xyz[1], xyz[2]});
        }
        surface->triangles.push_back(triangle);
      }
      return Status::Ok();
    }
  }
  // ASCII: "vertex x y z" three at a time.
  std::istringstream in{std::string(content)};
  std::string word;
  std::array<int64_t, 3> triangle{};
  int corner = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    std::array<double, 3> p{};
    if (!(in >> p[0] >> p[1] >> p[2])) {
      return Status::InvalidArgument(f, "STL: a vertex without three numbers");
    }
    triangle[corner++] = welder.Add(p);
    if (corner == 3) {
      surface->triangles.push_back(triangle);
      corner = 0;
    }
  }
  if (surface->triangles.empty()) {
    return Status::InvalidArgument(
        f, "is neither binary STL (84 + 50 bytes per triangle) nor ASCII STL with vertices");
  }
  return Status::Ok();
}

Status ReadObj(const std::string& f, std::string_view content, Surface* surface) {
  std::istringstream in{std::string(content)};
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    if (kind == "v") {
      std::array<double, 3> p{};
      if (!(words >> p[0] >> p[1] >> p[2])) {
        return Status::InvalidArgument(
            f, "OBJ line " + std::to_string(line_number) + ": a vertex needs x y z");
      }
      surface->points.push_back(p);
    } else if (kind == "f") {
      std::vector<int64_t> face;
      std::string item;
      while (words >> item) {
        // "i", "i/t", "i//n" or "i/t/n"; negative counts back from the end.
        int64_t index = 0;
        try {
          index = std::stoll(item.substr(0, item.find('/')));
        } catch (...) {
          index = 0;
        }
        if (index < 0) index += static_cast<int64_t>(surface->points.size()) + 1;
        if (index < 1 || index > static_cast<int64_t>(surface->points.size())) {
          return Status::InvalidArgument(f, "OBJ line " + std::to_string(line_number) +
                                                ": face index '" + item + "' names no vertex");
        }
        face.push_back(index - 1);
      }
      if (face.size() < 3) {
        return Status::InvalidArgument(
            f, "OBJ line " + std::to_string(line_number) + ": a face needs three vertices");
      }
      for (size_t k = 1; k + 1 < face.size(); ++k) {
        surface->triangles.push_back({face[0], face[k], face[k + 1]});
      }
    }
  }
  return Status::Ok();
}

// Legacy VTK, ASCII POLYDATA with POINTS and POLYGONS.
Status ReadVtk(const std::string& f, std::string_view content, Surface* surface) {
  std::istringstream in{std::string(content)};
  std::string line;
  std::getline(in, line);
  if (line.rfind("# vtk DataFile", 0) != 0) {
    return Status::InvalidArgument(f, "VTK: not a legacy VTK file (no '# vtk DataFile' line)");
  }
  std::getline(in, line);  // title
  std::string format, word;
  in >> format;
  if (format != "ASCII") {
    return Status::InvalidArgument(f, "VTK: only ASCII legacy files are read, not " + format);
  }
  while (in >> word) {
    if (word == "POINTS") {
      int64_t n = 0;
      std::string type;
      in >> n >> type;
      for (int64_t i = 0; i < n; ++i) {
        std::array<double, 3> p{};
        if (!(in >> p[0] >> p[1] >> p[2])) {
          return Status::InvalidArgument(f, "VTK: fewer POINTS than announced");
        }
        surface->points.push_back(p);
      }
    } else if (word == "POLYGONS") {
      int64_t n = 0, size = 0;
      in >> n >> size;
      for (int64_t i = 0; i < n; ++i) {
        int64_t k = 0;
        if (!(in >> k) || k < 3) {
          return Status::InvalidArgument(f, "VTK: a polygon needs three or more points");
        }
        std::vector<int64_t> face(static_cast<size_t>(k));
        for (int64_t& index : face) {
          if (!(in >> index) || index < 0 ||
              index >= static_cast<int64_t>(surface->points.size())) {
            return Status::InvalidArgument(f, "VTK: a polygon names a point that does not exist");
          }
        }
        for (size_t j = 1; j + 1 < face.size(); ++j) {
          surface->triangles.push_back({face[0], face[j], face[j + 1]});
        }
      }
    }
  }
  return Status::Ok();
}

// A surface a structure can be: at least four triangles, every point within
// kMaxCoordinateMm of the origin, every edge shared by exactly two triangles
// (closed and manifold), and a non-zero enclosed volume.
Status CheckClosedSurface(const std::string& f, const char* format, const Surface& surface) {
  const std::string what = std::string(format) + ": ";
  if (surface.triangles.size() < 4) {
    return Status::InvalidArgument(f, what +
                                          "a closed surface needs at least four triangles, not " +
                                          std::to_string(surface.triangles.size()));
  }
  for (const auto& p : surface.points) {
    for (double c : p) {
      if (!std::isfinite(c) || std::abs(c) > kMaxCoordinateMm) {
        return Status::InvalidArgument(
            f, what + "a point lies farther than 500 mm from the origin (or is not a number)");
      }
    }
  }
  // Each edge as (smaller, larger) point index; sorted, a closed manifold
  // surface has every edge exactly twice.
  std::vector<std::pair<int64_t, int64_t>> edges;
  edges.reserve(3 * surface.triangles.size());
  for (const auto& t : surface.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int64_t a = t[k], b = t[(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  int64_t open = 0, shared = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    open += j - i == 1;
    shared += j - i > 2;
    i = j;
  }
  if (open > 0 || shared > 0) {
    return Status::InvalidArgument(f, what + "not a closed surface: " + std::to_string(open) +
                                          " edges belong to one triangle only and " +
                                          std::to_string(shared) + " to more than two");
  }
  double six_volume = 0;
  for (const auto& t : surface.triangles) {
    const auto& a = surface.points[t[0]];
    const auto& b = surface.points[t[1]];
    const auto& c = surface.points[t[2]];
    six_volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                  a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  if (six_volume == 0) return Status::InvalidArgument(f, what + "encloses no volume");
  return Status::Ok();
}

Status CheckSurface(std::string_view field, GeometryFormat format, std::string_view content) {
  const std::string f(field);
  Surface surface;
  const char* name = format == GeometryFormat::kStl   ? "STL"
                     : format == GeometryFormat::kObj ? "OBJ"
                                                      : "VTK";
  const Status read = format == GeometryFormat::kStl   ? ReadStl(f, content, &surface)
                      : format == GeometryFormat::kObj ? ReadObj(f, content, &surface)
                                                       : ReadVtk(f, content, &surface);
  if (!read.ok()) return read;
  return CheckClosedSurface(f, name, surface);
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
      return CheckSurface(field, format, content);
  }
  return Status::InvalidArgument(std::string(field), "unknown geometry format");
}

}  // namespace pba
