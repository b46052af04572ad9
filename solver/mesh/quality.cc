#include "mesh/quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "mesh/quadratic.h"

namespace pba {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The measures of one element, before they are gathered per region.
struct ElementQuality {
  double aspect_ratio = 0;
  std::array<double, 2> dihedral_deg{};
  double jacobian_ratio = 1;
  double volume = 0;
};

QualityStats Gather(std::vector<ElementQuality> elements) {
  QualityStats s;
  s.count = static_cast<int>(elements.size());
  if (elements.empty()) return s;
  s.min_aspect_ratio = kInfinity;
  s.min_dihedral_deg = 180;
  s.max_jacobian_ratio = 1;
  for (const ElementQuality& q : elements) {
    s.min_aspect_ratio = std::min(s.min_aspect_ratio, q.aspect_ratio);
    s.max_aspect_ratio = std::max(s.max_aspect_ratio, q.aspect_ratio);
    s.min_dihedral_deg = std::min(s.min_dihedral_deg, q.dihedral_deg[0]);
    s.max_dihedral_deg = std::max(s.max_dihedral_deg, q.dihedral_deg[1]);
    s.max_jacobian_ratio = std::max(s.max_jacobian_ratio, q.jacobian_ratio);
    s.volume += q.volume;
  }
  // The median: the middle element, or the mean of the two middle ones.
  const std::size_t mid = elements.size() / 2;
  const auto by_aspect = [](const ElementQuality& a, const ElementQuality& b) {
    return a.aspect_ratio < b.aspect_ratio;
  };
  std::nth_element(elements.begin(), elements.begin() + mid, elements.end(), by_aspect);
  s.median_aspect_ratio = elements[mid].aspect_ratio;
  if (elements.size() % 2 == 0) {
    const double below =
        std::max_element(elements.begin(), elements.begin() + mid, by_aspect)->aspect_ratio;
    s.median_aspect_ratio = 0.5 * (s.median_aspect_ratio + below);
  }
  const std::size_t p99 =
      static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(elements.size()))) - 1;
  std::nth_element(elements.begin(), elements.begin() + p99, elements.end(), by_aspect);
  s.p99_aspect_ratio = elements[p99].aspect_ratio;
  return s;
}

}  // namespace

double TetAspectRatio(const Eigen::Matrix<double, 4, 3>& x) {
  double sum_squares = 0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) sum_squares += (x.row(a) - x.row(b)).squaredNorm();
  }
  const Eigen::Vector3d e1 = (x.row(1) - x.row(0)).transpose();
  const Eigen::Vector3d e2 = (x.row(2) - x.row(0)).transpose();
  const Eigen::Vector3d e3 = (x.row(3) - x.row(0)).transpose();
  const double volume = e1.dot(e2.cross(e3)) / 6;
  if (!(volume > 0)) return kInfinity;
  return std::pow(sum_squares / 6, 1.5) / (6 * std::numbers::sqrt2 * volume);
}

std::array<double, 2> TetDihedralRangeDegrees(const Eigen::Matrix<double, 4, 3>& x) {
  // The angle along edge (a, b) between the faces (a, b, c) and (a, b, d):
  // the angle between c and d projected onto the plane normal to the edge.
  static constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                       {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  std::array<double, 2> range{180, 0};
  for (const auto& k : kEdges) {
    const Eigen::Vector3d axis = (x.row(k[1]) - x.row(k[0])).transpose().normalized();
    Eigen::Vector3d c = (x.row(k[2]) - x.row(k[0])).transpose();
    Eigen::Vector3d d = (x.row(k[3]) - x.row(k[0])).transpose();
    c -= c.dot(axis) * axis;
    d -= d.dot(axis) * axis;
    // atan2 of |c x d| and c . d: accurate near 0 and 180 degrees, where
    // acos of the cosine loses half the digits.
    const double angle = std::atan2(c.cross(d).norm(), c.dot(d)) * 180 / std::numbers::pi;
    range[0] = std::min(range[0], angle);
    range[1] = std::max(range[1], angle);
  }
  return range;
}

double Tet10MaxJacobianRatio(const Tet10Nodes& x) {
  const double ratio = Tet10JacobianRatio(x);  // min / max
  if (!(ratio > 0)) return kInfinity;
  return 1 / ratio;
}

namespace {

// The measures of element e of `mesh`, whose elements are of `shape`: of a
// brick only its volume, of a tetrahedron also those of its corners.
ElementQuality Measure(const Mesh& mesh, ElementShape shape, int e) {
  ElementQuality q;
  const auto measure_corners = [&](const Eigen::Matrix<double, 4, 3>& x) {
    q.aspect_ratio = TetAspectRatio(x);
    q.dihedral_deg = TetDihedralRangeDegrees(x);
  };
  switch (shape) {
    case ElementShape::kHex8:
      q.volume = HexVolume(mesh, e);
      break;
    case ElementShape::kTet10: {
      measure_corners(TetCorners(mesh, e));
      const Tet10Nodes x10 = Tet10Coordinates(mesh, e);
      q.jacobian_ratio = Tet10MaxJacobianRatio(x10);
      q.volume = Tet10Volume(x10);
      break;
    }
    case ElementShape::kTet4: {
      const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
      measure_corners(x);
      const Eigen::Vector3d e1 = (x.row(1) - x.row(0)).transpose();
      const Eigen::Vector3d e2 = (x.row(2) - x.row(0)).transpose();
      const Eigen::Vector3d e3 = (x.row(3) - x.row(0)).transpose();
      q.volume = e1.dot(e2.cross(e3)) / 6;
      break;
    }
  }
  return q;
}

}  // namespace

QualitySummary Summarise(const Mesh& mesh) {
  QualitySummary summary;
  const int n = mesh.num_elements();
  const bool by_region = !mesh.element_region.empty();
  std::vector<ElementQuality> all(n);
  const ElementShape shape = mesh.shape();
  for (int e = 0; e < n; ++e) all[e] = Measure(mesh, shape, e);
  if (by_region) {
    std::vector<std::vector<ElementQuality>> per_region(mesh.region_names.size());
    for (int e = 0; e < n; ++e) per_region.at(mesh.element_region[e]).push_back(all[e]);
    for (auto& elements : per_region) summary.regions.push_back(Gather(std::move(elements)));
  }
  summary.overall = Gather(std::move(all));
  if (shape == ElementShape::kHex8) {
    // Only count and volume mean anything for bricks.
    const auto keep_count_and_volume = [](QualityStats* s) {
      QualityStats kept;
      kept.count = s->count;
      kept.volume = s->volume;
      *s = kept;
    };
    keep_count_and_volume(&summary.overall);
    for (QualityStats& s : summary.regions) keep_count_and_volume(&s);
  }
  return summary;
}

}  // namespace pba
