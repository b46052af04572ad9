#include "mesh/primitive_mesher.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>

namespace pba {
namespace {

constexpr double kMm = 1e-3;  // metres per millimetre

// A meshed cross-section in the xy plane [mm].
struct Section {
  std::vector<Eigen::Vector2d> points;
  std::vector<std::array<int, 4>> quads;
};

int Divisions(double length, double h) {
  return std::max(1, static_cast<int>(std::ceil(length / h - 1e-9)));
}

// Cells along each edge of a shell patch: a patch edge spans a quarter
// circle's half (pi / 4 of arc) at the mean radius.
double ShellDivisions(const SphericalShellSpec& s, double h) {
  const double arc = std::numbers::pi / 4 * 0.5 * (s.inner_radius_mm + s.outer_radius_mm);
  return std::max(1.0, std::ceil(arc / h - 1e-9));
}

Section RectangleSection(double lx, double ly, int nx, int ny) {
  Section s;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) s.points.emplace_back(lx * i / nx, ly * j / ny);
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      s.quads.push_back({a, a + 1, a + nx + 2, a + nx + 1});
    }
  }
  return s;
}

// O-grid of a disk: a central square of side R cut n x n, and a ring of m
// layers between the square's boundary and the circle.
struct DiskDivisions {
  int n;  // central cells per side
  int m;  // ring layers
};

DiskDivisions DiskCounts(double radius, double h) {
  return {std::max(2, Divisions(radius, h)), Divisions(0.5 * radius, h)};
}

// The quads of `s` whose centroid lies at y <= 0, the points renumbered
// (a disk cut with an even n: along grid lines).
Section LowerHalf(const Section& s) {
  Section half;
  std::vector<int> index(s.points.size(), -1);
  for (const auto& q : s.quads) {
    double y = 0;
    for (int a : q) y += s.points[a].y();
    if (y > 0) continue;
    std::array<int, 4> kept;
    for (int k = 0; k < 4; ++k) {
      if (index[q[k]] < 0) {
        index[q[k]] = static_cast<int>(half.points.size());
        half.points.push_back(s.points[q[k]]);
      }
      kept[k] = index[q[k]];
    }
    half.quads.push_back(kept);
  }
  return half;
}

Section DiskSection(double radius, DiskDivisions d) {
  Section s;
  const int n = d.n;
  const double a = 0.5 * radius;  // half width of the central square
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) s.points.emplace_back(-a + 2 * a * i / n, -a + 2 * a * j / n);
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int c = j * (n + 1) + i;
      s.quads.push_back({c, c + 1, c + n + 2, c + n + 1});
    }
  }
  // The square's boundary, counter-clockwise from the corner (-a, -a).
  const int loop = 4 * n;
  std::vector<int> ring(loop);
  std::vector<double> angle(loop);
  for (int k = 0; k < loop; ++k) {
    const int edge = k / n;
    const int t = k % n;
    int i = 0, j = 0;
    switch (edge) {
      case 0:
        i = t, j = 0;
        break;
      case 1:
        i = n, j = t;
        break;
      case 2:
        i = n - t, j = n;
        break;
      default:
        i = 0, j = n - t;
        break;
    }
    ring[k] = j * (n + 1) + i;
    angle[k] = -0.75 * std::numbers::pi + edge * 0.5 * std::numbers::pi +
               (static_cast<double>(t) / n) * 0.5 * std::numbers::pi;
  }
  std::vector<int> previous = ring;
  for (int l = 1; l <= d.m; ++l) {
    const double f = static_cast<double>(l) / d.m;
    std::vector<int> layer(loop);
    for (int k = 0; k < loop; ++k) {
      const Eigen::Vector2d inner = s.points[ring[k]];
      const Eigen::Vector2d outer(radius * std::cos(angle[k]), radius * std::sin(angle[k]));
      layer[k] = static_cast<int>(s.points.size());
      s.points.push_back((1 - f) * inner + f * outer);
    }
    for (int k = 0; k < loop; ++k) {
      const int k1 = (k + 1) % loop;
      s.quads.push_back({previous[k], previous[k1], layer[k1], layer[k]});
    }
    previous = std::move(layer);
  }
  return s;
}

double SignedVolume(const Mesh& mesh, const std::array<int, 4>& t) {
  const Eigen::Vector3d a = mesh.nodes.row(t[0]).transpose();
  const Eigen::Vector3d b = mesh.nodes.row(t[1]).transpose();
  const Eigen::Vector3d c = mesh.nodes.row(t[2]).transpose();
  const Eigen::Vector3d d = mesh.nodes.row(t[3]).transpose();
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

// Cuts the prism with bottom (v[0], v[1], v[2]) and top (v[3], v[4], v[5]),
// v[i + 3] above v[i], into three tetrahedra. Each quadrilateral face is
// split through its smallest global index (Dompierre et al. 1999), so
// neighbours agree on shared faces.
void SplitPrism(const std::array<int, 6>& v, std::vector<std::array<int, 4>>* tets) {
  const int m = static_cast<int>(std::min_element(v.begin(), v.end()) - v.begin());
  int a, b, c, d, e, f;
  if (m < 3) {
    a = v[m], b = v[(m + 1) % 3], c = v[(m + 2) % 3];
    d = v[m + 3], e = v[(m + 1) % 3 + 3], f = v[(m + 2) % 3 + 3];
  } else {
    const int k = m - 3;
    a = v[m], b = v[(k + 1) % 3 + 3], c = v[(k + 2) % 3 + 3];
    d = v[k], e = v[(k + 1) % 3], f = v[(k + 2) % 3];
  }
  if (std::min(b, f) < std::min(c, e)) {
    tets->push_back({a, b, c, f});
    tets->push_back({a, b, f, e});
  } else {
    tets->push_back({a, b, c, e});
    tets->push_back({a, e, c, f});
  }
  tets->push_back({a, e, f, d});
}

// Turns every brick of `mesh` positively: a negative one (its section quad
// clockwise seen from the extrusion direction) is mirrored by swapping
// natural xi and eta, nodes 1 <-> 3 and 5 <-> 7, which keeps the C3D8 order.
void OrientHexes(Mesh* mesh) {
  for (int e = 0; e < static_cast<int>(mesh->hexes.size()); ++e) {
    if (HexVolume(*mesh, e) < 0) {
      auto& h = mesh->hexes[e];
      std::swap(h[1], h[3]);
      std::swap(h[5], h[7]);
    }
  }
}

// The layer between node layers `lo` and `hi` (offsets of the first node of
// each) over the quads of a surface: bricks when `hex`, else prisms cut into
// tetrahedra.
void AddLayer(const std::vector<std::array<int, 4>>& quads, int lo, int hi, bool hex, Mesh* mesh) {
  for (const auto& q : quads) {
    if (hex) {
      mesh->hexes.push_back(
          {lo + q[0], lo + q[1], lo + q[2], lo + q[3], hi + q[0], hi + q[1], hi + q[2], hi + q[3]});
      continue;
    }
    for (const auto& tri :
         {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      SplitPrism({lo + tri[0], lo + tri[1], lo + tri[2], hi + tri[0], hi + tri[1], hi + tri[2]},
                 &mesh->tets);
    }
  }
}

void Orient(Mesh* mesh) {
  for (auto& t : mesh->tets) {
    if (SignedVolume(*mesh, t) < 0) std::swap(t[2], t[3]);
  }
  OrientHexes(mesh);
}

Mesh Extrude(const Section& section, double height, int nz, bool hex) {
  Mesh mesh;
  const int np = static_cast<int>(section.points.size());
  mesh.nodes.resize(static_cast<Eigen::Index>(np) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k) {
    const double z = height * k / nz;
    for (int p = 0; p < np; ++p) {
      mesh.nodes.row(k * np + p) << section.points[p].x() * kMm, section.points[p].y() * kMm,
          z * kMm;
    }
  }
  if (hex) {
    mesh.hexes.reserve(section.quads.size() * nz);
  } else {
    mesh.tets.reserve(section.quads.size() * 6 * nz);
  }
  for (int k = 0; k < nz; ++k) AddLayer(section.quads, k * np, (k + 1) * np, hex, &mesh);
  Orient(&mesh);
  return mesh;
}

// Octant of a spherical shell, radii a < b [mm]: the octant of the unit
// sphere is covered by three patches, the central projections of the cube
// faces x = 1, y = 1, z = 1 over [0, 1]^2 (a cubed sphere, with equiangular
// spacing so the cells are nearly uniform), each cut n x n; the surface
// quadrilaterals are split into triangles and extruded radially in nr
// layers into prisms, cut into tetrahedra as in Extrude, or (`hex`) the
// quadrilaterals themselves extruded into bricks.
Mesh SphericalShellOctant(double a, double b, int n, int nr, bool hex) {
  std::vector<Eigen::Vector3d> directions;
  std::map<std::array<int, 3>, int> index;  // integer cube-surface coordinates -> point
  const auto point = [&](std::array<int, 3> key) {
    const auto [it, added] = index.emplace(key, static_cast<int>(directions.size()));
    if (added) {
      Eigen::Vector3d x;
      for (int c = 0; c < 3; ++c) x(c) = std::tan(std::numbers::pi / 4 * key[c] / n);
      directions.push_back(x.normalized());
    }
    return it->second;
  };
  std::vector<std::array<int, 4>> quads;
  for (int face = 0; face < 3; ++face) {
    const int u = (face + 1) % 3, v = (face + 2) % 3;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        std::array<int, 4> q;
        const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; ++k) {
          std::array<int, 3> key;
          key[face] = n;
          key[u] = i + di[k];
          key[v] = j + dj[k];
          q[k] = point(key);
        }
        quads.push_back(q);
      }
    }
  }
  Mesh mesh;
  const int np = static_cast<int>(directions.size());
  mesh.nodes.resize(static_cast<Eigen::Index>(np) * (nr + 1), 3);
  for (int k = 0; k <= nr; ++k) {
    const double r = (a + (b - a) * k / nr) * kMm;
    for (int p = 0; p < np; ++p) mesh.nodes.row(k * np + p) = r * directions[p].transpose();
  }
  for (int k = 0; k < nr; ++k) AddLayer(quads, k * np, (k + 1) * np, hex, &mesh);
  Orient(&mesh);
  return mesh;
}

// Cuts a brick into six tetrahedra coned from its smallest-index node over
// the three faces that do not hold it, each split through its own
// smallest-index node. A face holding the apex is then split through the
// apex, which is also that face's smallest node: every face is split
// through its smallest global index whichever brick it is seen from
// (Dompierre et al. 1999's rule), so neighbours agree and the mesh is
// conforming. Orient() turns the tetrahedra positively afterwards.
void SplitHex(const std::array<int, 8>& h, std::vector<std::array<int, 4>>* tets) {
  const int apex = *std::min_element(h.begin(), h.end());
  for (const auto& f : kHex8Faces) {
    std::array<int, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = h[f[k]];
    if (std::find(q.begin(), q.end(), apex) != q.end()) continue;
    const int k = static_cast<int>(std::min_element(q.begin(), q.end()) - q.begin());
    const int a = q[k], b = q[(k + 1) % 4], c = q[(k + 2) % 4], d = q[(k + 3) % 4];
    tets->push_back({apex, a, b, c});
    tets->push_back({apex, a, c, d});
  }
}

// Half the edge of the unit ball's central cube. Its corners then lie at
// 0.69 of the radius, leaving the corner cells of the outer blocks room: a
// larger core flattens them. primitive_mesher_test prints the smallest
// dihedral angle of the tetrahedra of a 70 x 60 x 50 mm ellipsoid at 20, 10
// and 5 mm (12 to 14 degrees).
constexpr double kCoreHalfWidth = 0.4;

// Solid ellipsoid with semi-axes `axes` [mm]: the image under x -> (a x,
// b y, c z) of a unit ball meshed as a three-dimensional O-grid, a central
// cube [-0.4, 0.4]^3 cut n x n x n and six blocks of n x n x m cells
// between its faces and the sphere. A block's cells run along straight
// lines from a point of the cube's face to the equiangular central
// projection of the same point onto the sphere (the cubed sphere of
// SphericalShellOctant), so every cell on the surface has one face on it
// and none is flattened at the cube's edges. The surface nodes lie exactly
// on the ellipsoid. Bricks when `hex`, else each cut into six tetrahedra
// (SplitHex).
Mesh Ellipsoid(const std::array<double, 3>& axes, int n, int m, bool hex) {
  std::vector<Eigen::Vector3d> points;
  // (i, j, k) on the cube's lattice [0, n]^3 and the layer l (0 = the cube)
  std::map<std::array<int, 4>, int> index;
  const auto node = [&](int i, int j, int k, int l) {
    const std::array<int, 4> key{i, j, k, l};
    const auto [it, added] = index.emplace(key, static_cast<int>(points.size()));
    if (added) {
      const Eigen::Vector3d c(2.0 * i / n - 1, 2.0 * j / n - 1, 2.0 * k / n - 1);
      Eigen::Vector3d d;
      for (int e = 0; e < 3; ++e) d(e) = std::tan(std::numbers::pi / 4 * c(e));
      const double f = static_cast<double>(l) / m;
      points.push_back((1 - f) * kCoreHalfWidth * c + f * d.normalized());
    }
    return it->second;
  };
  std::vector<std::array<int, 8>> cells;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        cells.push_back({node(i, j, k, 0), node(i + 1, j, k, 0), node(i + 1, j + 1, k, 0),
                         node(i, j + 1, k, 0), node(i, j, k + 1, 0), node(i + 1, j, k + 1, 0),
                         node(i + 1, j + 1, k + 1, 0), node(i, j + 1, k + 1, 0)});
      }
    }
  }
  // The six blocks: the cube face normal to `axis` at lattice coordinate
  // `side` (0 or n), its quads (u, v) extruded outwards layer by layer.
  for (int axis = 0; axis < 3; ++axis) {
    for (const int side : {0, n}) {
      const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
      const auto at = [&](int u, int v, int l) {
        std::array<int, 3> ijk;
        ijk[axis] = side;
        ijk[ua] = u;
        ijk[va] = v;
        return node(ijk[0], ijk[1], ijk[2], l);
      };
      for (int l = 0; l < m; ++l) {
        for (int v = 0; v < n; ++v) {
          for (int u = 0; u < n; ++u) {
            cells.push_back({at(u, v, l), at(u + 1, v, l), at(u + 1, v + 1, l), at(u, v + 1, l),
                             at(u, v, l + 1), at(u + 1, v, l + 1), at(u + 1, v + 1, l + 1),
                             at(u, v + 1, l + 1)});
          }
        }
      }
    }
  }
  Mesh mesh;
  mesh.nodes.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t p = 0; p < points.size(); ++p) {
    for (int e = 0; e < 3; ++e)
      mesh.nodes(static_cast<Eigen::Index>(p), e) = points[p](e) * axes[e] * kMm;
  }
  if (hex) {
    mesh.hexes = std::move(cells);
  } else {
    mesh.tets.reserve(6 * cells.size());
    for (const auto& h : cells) SplitHex(h, &mesh.tets);
  }
  Orient(&mesh);
  return mesh;
}

struct EllipsoidDivisions {
  int n;  // cells along each edge of the central cube and of each surface patch
  int m;  // layers between the cube and the surface
};

// A surface patch spans a quarter of a great circle, pi R / 2 of arc on the
// largest semi-axis R; the layers span 0.6 R at most.
EllipsoidDivisions EllipsoidCounts(const EllipsoidSpec& e, double h) {
  const double r = *std::max_element(e.semi_axes_mm.begin(), e.semi_axes_mm.end());
  return {std::max(2, Divisions(std::numbers::pi / 2 * r, h)),
          Divisions((1 - kCoreHalfWidth) * r, h)};
}

// Fills mesh.face_sets: a tetrahedron face (brick face) belongs to a set
// when its three (four) nodes lie on that set's surface. Only boundary faces
// can: the bodies are convex, or (the shell) their curved surfaces are the
// first and last layer of an extrusion, whose faces within a layer are prism
// or brick ends. A set's quads are numbered anticlockwise seen from outside.
void ClassifyFaces(const std::vector<std::string>& names,
                   const std::vector<std::function<bool(const Eigen::Vector3d&)>>& on_surface,
                   Mesh* mesh) {
  const int n = mesh->num_nodes();
  std::vector<uint32_t> mask(n, 0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = mesh->nodes.row(i).transpose();
    for (std::size_t s = 0; s < on_surface.size(); ++s) {
      if (on_surface[s](x)) mask[i] |= 1u << s;
    }
  }
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<FaceSet> sets(names.size());
  for (const auto& h : mesh->hexes) {
    for (const auto& f : kHex8Faces) {
      const uint32_t common = mask[h[f[0]]] & mask[h[f[1]]] & mask[h[f[2]]] & mask[h[f[3]]];
      if (common == 0) continue;
      for (std::size_t s = 0; s < names.size(); ++s) {
        // kHex8Faces lists each face as seen from inside: reversed.
        if (common & (1u << s)) sets[s].quads.push_back({h[f[0]], h[f[3]], h[f[2]], h[f[1]]});
      }
    }
  }
  for (const auto& t : mesh->tets) {
    for (const auto& f : kFaces) {
      const uint32_t common = mask[t[f[0]]] & mask[t[f[1]]] & mask[t[f[2]]];
      if (common == 0) continue;
      for (std::size_t s = 0; s < names.size(); ++s) {
        if (common & (1u << s)) sets[s].triangles.push_back({t[f[0]], t[f[1]], t[f[2]]});
      }
    }
  }
  for (std::size_t s = 0; s < names.size(); ++s) {
    CollectFaceSetNodes(&sets[s]);
    mesh->face_sets[names[s]] = std::move(sets[s]);
  }
}

}  // namespace

double EffectiveElementSize(const GeometrySpec& geometry, const MeshSpec& options) {
  if (options.element_size_mm > 0) return options.element_size_mm;
  if (geometry.kind == GeometrySpec::Kind::kAtlas) return kDefaultAtlasElementSizeMm;
  double largest = 0;
  if (geometry.kind == GeometrySpec::Kind::kBox) {
    largest = *std::max_element(geometry.box.size_mm.begin(), geometry.box.size_mm.end());
  } else if (geometry.kind == GeometrySpec::Kind::kCylinder) {
    largest = std::max(2 * geometry.cylinder.radius_mm, geometry.cylinder.height_mm);
  } else if (geometry.kind == GeometrySpec::Kind::kSphericalShell) {
    largest = geometry.spherical_shell.outer_radius_mm;
  } else if (geometry.kind == GeometrySpec::Kind::kEllipsoid) {
    const auto& a = geometry.ellipsoid.semi_axes_mm;
    largest = 2 * *std::max_element(a.begin(), a.end());
  }
  return largest / 20.0;
}

int64_t EstimateElementCount(const GeometrySpec& geometry, const MeshSpec& options) {
  const double h = EffectiveElementSize(geometry, options);
  if (!(h > 0)) return 0;
  // Counted in doubles: an absurd size must not overflow the count. Each
  // cell is one brick, or 6 tetrahedra (two prisms of 3).
  const double per_cell = IsHexahedral(options.element) ? 1.0 : 6.0;
  double count = 0;
  if (geometry.kind == GeometrySpec::Kind::kBox) {
    const auto& s = geometry.box.size_mm;
    count = per_cell * std::ceil(s[0] / h) * std::ceil(s[1] / h) * std::ceil(s[2] / h);
  } else if (geometry.kind == GeometrySpec::Kind::kCylinder) {
    const double n = std::max(2.0, std::ceil(geometry.cylinder.radius_mm / h));
    const double m = std::ceil(0.5 * geometry.cylinder.radius_mm / h);
    count = per_cell * (n * n + 4 * n * m) * std::ceil(geometry.cylinder.height_mm / h) *
            (geometry.cylinder.half ? 0.5 : 1.0);
  } else if (geometry.kind == GeometrySpec::Kind::kSphericalShell) {
    const SphericalShellSpec& s = geometry.spherical_shell;
    const double n = ShellDivisions(s, h),
                 nr = std::ceil((s.outer_radius_mm - s.inner_radius_mm) / h);
    count = per_cell * 3 * n * n * nr;
  } else if (geometry.kind == GeometrySpec::Kind::kEllipsoid) {
    const EllipsoidDivisions d = EllipsoidCounts(geometry.ellipsoid, h);
    const double n = d.n, m = d.m;
    count = per_cell * (n * n * n + 6 * n * n * m);
  } else if (geometry.kind == GeometrySpec::Kind::kAtlas) {
    // Measured on the synthetic atlas (pba-atlas build, docs/atlas.md):
    // 460,799 tetrahedra at 4 mm, so about 2.9e7 / h^3 (h in mm).
    count = 2.9e7 / (h * h * h);
  }
  return count > 9e18 ? INT64_MAX : static_cast<int64_t>(count);
}

Mesh BuildPrimitiveMesh(const GeometrySpec& geometry, const MeshSpec& options, MeshStats* stats) {
  const double h = EffectiveElementSize(geometry, options);
  const bool hex = IsHexahedral(options.element);
  Mesh mesh;
  if (geometry.kind == GeometrySpec::Kind::kBox) {
    const auto& s = geometry.box.size_mm;
    const int nx = Divisions(s[0], h), ny = Divisions(s[1], h), nz = Divisions(s[2], h);
    mesh = Extrude(RectangleSection(s[0], s[1], nx, ny), s[2], nz, hex);
    const double eps = 1e-9 * std::max({s[0], s[1], s[2]}) * kMm;
    const double lx = s[0] * kMm, ly = s[1] * kMm, lz = s[2] * kMm;
    ClassifyFaces({"bottom", "top", "x_min", "x_max", "y_min", "y_max"},
                  {[=](const Eigen::Vector3d& x) { return x.z() < eps; },
                   [=](const Eigen::Vector3d& x) { return x.z() > lz - eps; },
                   [=](const Eigen::Vector3d& x) { return x.x() < eps; },
                   [=](const Eigen::Vector3d& x) { return x.x() > lx - eps; },
                   [=](const Eigen::Vector3d& x) { return x.y() < eps; },
                   [=](const Eigen::Vector3d& x) { return x.y() > ly - eps; }},
                  &mesh);
    stats->description = "structured grid of " + std::to_string(nx) + " x " + std::to_string(ny) +
                         " x " + std::to_string(nz) +
                         (hex ? " hexahedra" : " cells, each cut into 6 tetrahedra");
  } else if (geometry.kind == GeometrySpec::Kind::kSphericalShell) {
    const SphericalShellSpec& s = geometry.spherical_shell;
    const int n = static_cast<int>(ShellDivisions(s, h));
    const int nr = Divisions(s.outer_radius_mm - s.inner_radius_mm, h);
    mesh = SphericalShellOctant(s.inner_radius_mm, s.outer_radius_mm, n, nr, hex);
    const double a = s.inner_radius_mm * kMm, b = s.outer_radius_mm * kMm;
    const double eps = 1e-9 * b;
    ClassifyFaces({"inner", "outer", "x0", "y0", "z0"},
                  {[=](const Eigen::Vector3d& x) { return x.norm() < a + eps; },
                   [=](const Eigen::Vector3d& x) { return x.norm() > b - eps; },
                   [=](const Eigen::Vector3d& x) { return x.x() < eps; },
                   [=](const Eigen::Vector3d& x) { return x.y() < eps; },
                   [=](const Eigen::Vector3d& x) { return x.z() < eps; }},
                  &mesh);
    stats->description =
        "cubed-sphere octant: 3 patches of " + std::to_string(n) + " x " + std::to_string(n) +
        " cells, extruded radially in " + std::to_string(nr) +
        (hex ? " layers of hexahedra" : " layers, each prism cut into 3 tetrahedra");
  } else if (geometry.kind == GeometrySpec::Kind::kEllipsoid) {
    const EllipsoidSpec& e = geometry.ellipsoid;
    const EllipsoidDivisions d = EllipsoidCounts(e, h);
    mesh = Ellipsoid(e.semi_axes_mm, d.n, d.m, hex);
    const Eigen::Vector3d inverse(1 / (e.semi_axes_mm[0] * kMm), 1 / (e.semi_axes_mm[1] * kMm),
                                  1 / (e.semi_axes_mm[2] * kMm));
    ClassifyFaces({"surface"}, {[=](const Eigen::Vector3d& x) {
                    return std::abs(x.cwiseProduct(inverse).squaredNorm() - 1) < 1e-9;
                  }},
                  &mesh);
    stats->description = "ellipsoidal O-grid: a central block of " + std::to_string(d.n) + " x " +
                         std::to_string(d.n) + " x " + std::to_string(d.n) +
                         " cells and 6 blocks of " + std::to_string(d.n) + " x " +
                         std::to_string(d.n) + " cells in " + std::to_string(d.m) +
                         (hex ? " layers, hexahedra" : " layers, each cell cut into 6 tetrahedra");
  } else {
    const double r = geometry.cylinder.radius_mm, height = geometry.cylinder.height_mm;
    const bool half = geometry.cylinder.half;
    DiskDivisions d = DiskCounts(r, h);
    if (half) d.n += d.n % 2;  // the cut y = 0 then runs along grid lines
    const int nz = Divisions(height, h);
    const Section disk = DiskSection(r, d);
    mesh = Extrude(half ? LowerHalf(disk) : disk, height, nz, hex);
    const double eps = 1e-9 * std::max(r, height) * kMm;
    const double rm = r * kMm, hm = height * kMm;
    std::vector<std::string> names = {"bottom", "top", "side"};
    std::vector<std::function<bool(const Eigen::Vector3d&)>> tests = {
        [=](const Eigen::Vector3d& x) { return x.z() < eps; },
        [=](const Eigen::Vector3d& x) { return x.z() > hm - eps; },
        [=](const Eigen::Vector3d& x) { return x.head<2>().norm() > rm - eps; }};
    if (half) {
      names.push_back("cut");
      tests.push_back([=](const Eigen::Vector3d& x) { return x.y() > -eps; });
    }
    ClassifyFaces(names, tests, &mesh);
    stats->description =
        std::string(half ? "half " : "") + "O-grid cross-section (central square " +
        std::to_string(d.n) + " x " + std::to_string(d.n) + ", ring of " + std::to_string(d.m) +
        " layers) extruded in " + std::to_string(nz) +
        (hex ? " layers of hexahedra" : " layers, each prism cut into 3 tetrahedra");
  }
  return mesh;
}

}  // namespace pba
