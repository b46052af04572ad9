// Closed triangulated surfaces (surface_io.h): the readers of STL, OBJ and
// legacy VTK, and the check that a surface can bound a structure.
#include "atlas/surface_io.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "atlas/contours.h"

namespace pba {
namespace {

// Welds points by their exact coordinates (STL repeats them per triangle).
class Welder {
 public:
  explicit Welder(TriangleSurface* surface) : surface_(surface) {}
  int Add(const Eigen::Vector3d& p) {
    Key key;
    std::memcpy(key.data(), p.data(), sizeof key);
    const auto [it, added] = index_.emplace(key, static_cast<int>(surface_->points.size()));
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
  TriangleSurface* surface_;
  std::unordered_map<Key, int, Hash> index_;
};

Status ReadStl(const std::string& f, std::string_view content, TriangleSurface* surface) {
  Welder welder(surface);
  // Binary: an 80-byte header, a triangle count, 50 bytes per triangle.
  if (content.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, content.data() + 80, 4);
    if (content.size() == 84 + 50 * static_cast<size_t>(count)) {
      for (uint32_t t = 0; t < count; ++t) {
        const char* facet = content.data() + 84 + 50 * static_cast<size_t>(t) + 12;
        std::array<int, 3> triangle{};
        for (int k = 0; k < 3; ++k) {
          float xyz[3];
          std::memcpy(xyz, facet + 12 * k, 12);
          triangle[k] = welder.Add(Eigen::Vector3d(xyz[0], xyz[1], xyz[2]));
        }
        surface->triangles.push_back(triangle);
      }
      return Status::Ok();
    }
  }
  // ASCII: "vertex x y z" three at a time.
  std::istringstream in{std::string(content)};
  std::string word;
  std::array<int, 3> triangle{};
  int corner = 0;
  while (in >> word) {
    if (word != "vertex") continue;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
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

Status ReadObj(const std::string& f, std::string_view content, TriangleSurface* surface) {
  std::istringstream in{std::string(content)};
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    if (kind == "v") {
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      if (!(words >> p[0] >> p[1] >> p[2])) {
        return Status::InvalidArgument(
            f, "OBJ line " + std::to_string(line_number) + ": a vertex needs x y z");
      }
      surface->points.push_back(p);
    } else if (kind == "f") {
      std::vector<int> face;
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
        face.push_back(static_cast<int>(index - 1));
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
Status ReadVtk(const std::string& f, std::string_view content, TriangleSurface* surface) {
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
        Eigen::Vector3d p = Eigen::Vector3d::Zero();
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
        if (!(in >> k)) {
          return Status::InvalidArgument(f, "VTK: fewer POLYGONS than announced (" +
                                                std::to_string(i) + " of " + std::to_string(n) +
                                                ")");
        }
        if (k < 3) return Status::InvalidArgument(f, "VTK: a polygon needs three or more points");
        // The announced size is checked against what exists before it is
        // used: a 125-byte file announcing a polygon of 2^28 points cost
        // gigabytes when the polygon was allocated up front.
        if (k > static_cast<int64_t>(surface->points.size())) {
          return Status::InvalidArgument(f, "VTK: a polygon of " + std::to_string(k) +
                                                " points, but the file has only " +
                                                std::to_string(surface->points.size()) + " points");
        }
        std::vector<int> face;
        for (int64_t j = 0; j < k; ++j) {
          int index = 0;
          if (!(in >> index) || index < 0 || index >= static_cast<int>(surface->points.size())) {
            return Status::InvalidArgument(f, "VTK: a polygon names a point that does not exist");
          }
          face.push_back(index);
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
// kMaxAtlasCoordinateMm of the origin, every edge shared by exactly two triangles
// (closed and manifold), and a non-zero enclosed volume.
Status CheckClosedSurface(const std::string& f, const char* format,
                          const TriangleSurface& surface) {
  const std::string what = std::string(format) + ": ";
  if (surface.triangles.size() < 4) {
    return Status::InvalidArgument(f, what +
                                          "a closed surface needs at least four triangles, not " +
                                          std::to_string(surface.triangles.size()));
  }
  for (const Eigen::Vector3d& p : surface.points) {
    for (int axis = 0; axis < 3; ++axis) {
      const double c = p[axis];
      if (!std::isfinite(c) || std::abs(c) > kMaxAtlasCoordinateMm) {
        return Status::InvalidArgument(
            f, what + "a point lies farther than 500 mm from the origin (or is not a number)");
      }
    }
  }
  // Each edge as (smaller, larger) point index; sorted, a closed manifold
  // surface has every edge exactly twice.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * surface.triangles.size());
  for (const auto& t : surface.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
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
  if (EnclosedVolume(surface) == 0) return Status::InvalidArgument(f, what + "encloses no volume");
  return Status::Ok();
}

}  // namespace

Status ReadSurface(std::string_view content, StructureFormat format, const std::string& field,
                   TriangleSurface* surface) {
  TriangleSurface read;
  const char* name = nullptr;
  Status status;
  switch (format) {
    case StructureFormat::kStl:
      name = "STL";
      status = ReadStl(field, content, &read);
      break;
    case StructureFormat::kObj:
      name = "OBJ";
      status = ReadObj(field, content, &read);
      break;
    case StructureFormat::kVtk:
      name = "VTK";
      status = ReadVtk(field, content, &read);
      break;
    default:
      return Status::InvalidArgument(field, "a surface is STL, OBJ or VTK");
  }
  PBA_RETURN_IF_ERROR(status);
  PBA_RETURN_IF_ERROR(CheckClosedSurface(field, name, read));
  *surface = std::move(read);
  return Status::Ok();
}

double EnclosedVolume(const TriangleSurface& surface) {
  // Sum of the signed volumes of the tetrahedra (origin, a, b, c).
  double six_volume = 0;
  for (const auto& t : surface.triangles) {
    six_volume += surface.points[t[0]].dot(surface.points[t[1]].cross(surface.points[t[2]]));
  }
  return six_volume / 6;
}

}  // namespace pba
