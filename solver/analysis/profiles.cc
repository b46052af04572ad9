// Line profiles: point location on a grid of element boxes, interpolation
// with the element's shape functions, components of the element's tensors
// along the line.
#include "analysis/profiles.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "fem/hex8.h"
#include "fem/tet10.h"
#include "scene/problem.h"

namespace pba {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// How far outside an element (in natural coordinates) a point may lie and
// still count as inside: a point on a face or on the body's surface is found.
constexpr double kInsideTolerance = 1e-7;

// Column order of a profile table; kColumns names them with their units.
enum Column {
  kDistance = 0,
  kX = 1,
  kUx = 4,
  kStressAlong = 7,
  kMeanStress = 8,
  kVonMises = 9,
  kStrainAlong = 10,
  kColumnCount = 11,
};
const char* const kColumns[kColumnCount] = {
    "distance_mm",     "x_mm",           "y_mm",         "z_mm",        "ux_mm", "uy_mm", "uz_mm",
    "stress_along_pa", "mean_stress_pa", "von_mises_pa", "strain_along"};

// t . A . t of a symmetric tensor in Voigt order xx yy zz yz xz xy whose
// shear entries are `shear` times the tensor's (1: stress; 2: engineering
// shear strain).
double AlongLine(const double* v, const Eigen::Vector3d& t, double shear) {
  const double off = 2 / shear;
  return v[0] * t.x() * t.x() + v[1] * t.y() * t.y() + v[2] * t.z() * t.z() +
         off * (v[3] * t.y() * t.z() + v[4] * t.x() * t.z() + v[5] * t.x() * t.y());
}

// Volume coordinates (r, s, t) = (L1, L2, L3) of x in the straight
// tetrahedron of corners c0..c3; false when it is degenerate.
bool Barycentric(const Eigen::Vector3d& c0, const Eigen::Vector3d& c1, const Eigen::Vector3d& c2,
                 const Eigen::Vector3d& c3, const Eigen::Vector3d& x, Eigen::Vector3d* xi) {
  Eigen::Matrix3d j;
  j.col(0) = c1 - c0;
  j.col(1) = c2 - c0;
  j.col(2) = c3 - c0;
  const double det = j.determinant();
  if (!(std::abs(det) > 0)) return false;
  *xi = j.inverse() * (x - c0);
  return true;
}

bool InsideTetrahedron(const Eigen::Vector3d& xi, double tolerance) {
  return xi.minCoeff() >= -tolerance && xi.sum() <= 1 + tolerance;
}

}  // namespace

int ProfilePointCount(const ProfileSpec& profile) {
  return profile.points == 0 ? OutputOptions::kProfilePoints : profile.points;
}

ElementLocator::ElementLocator(const std::vector<double>& nodes_mm,
                               const std::vector<int64_t>& elements, int nodes_per_element)
    : nodes_(nodes_mm), elements_(elements), per_element_(nodes_per_element) {
  num_elements_ = per_element_ > 0 ? static_cast<int64_t>(elements.size()) / per_element_ : 0;
  if (num_elements_ == 0 || nodes_mm.empty()) return;
  // Boxes. A 10-node element's faces may bulge past its nodes (by a third
  // of a mid-edge node's offset from the straight edge at most): its box
  // grows by a tenth of its size. Every box grows by a hair so that points
  // on faces are not lost to rounding.
  boxes_.resize(6 * static_cast<std::size_t>(num_elements_));
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d high = -low;
  double size_sum = 0;
  for (int64_t e = 0; e < num_elements_; ++e) {
    Eigen::Vector3d lo = Node(e, 0), hi = lo;
    for (int a = 1; a < per_element_; ++a) {
      lo = lo.cwiseMin(Node(e, a));
      hi = hi.cwiseMax(Node(e, a));
    }
    const double size = (hi - lo).maxCoeff();
    const double pad = (per_element_ == 10 ? 0.1 : 1e-6) * size;
    lo.array() -= pad;
    hi.array() += pad;
    for (int c = 0; c < 3; ++c) {
      boxes_[6 * e + c] = std::nextafter(static_cast<float>(lo[c]), -INFINITY);
      boxes_[6 * e + 3 + c] = std::nextafter(static_cast<float>(hi[c]), INFINITY);
    }
    low = low.cwiseMin(lo);
    high = high.cwiseMax(hi);
    size_sum += size;
  }
  // Cells about one mean element box wide, at most 8 per element.
  origin_ = low;
  const Eigen::Vector3d extent = (high - low).cwiseMax(1e-12);
  cell_mm_ = std::max(size_sum / static_cast<double>(num_elements_), 1e-12);
  for (;;) {
    double cells = 1;
    for (int c = 0; c < 3; ++c) {
      dims_[c] = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(extent[c] / cell_mm_)));
      cells *= static_cast<double>(dims_[c]);
    }
    if (cells <= 8.0 * static_cast<double>(num_elements_) + 64) break;
    cell_mm_ *= 1.25;
  }
  const auto cell_range = [&](int64_t e, std::array<int64_t, 3>* from, std::array<int64_t, 3>* to) {
    for (int c = 0; c < 3; ++c) {
      const auto index = [&](double x) {
        return std::clamp<int64_t>(static_cast<int64_t>(std::floor((x - origin_[c]) / cell_mm_)), 0,
                                   dims_[c] - 1);
      };
      (*from)[c] = index(boxes_[6 * e + c]);
      (*to)[c] = index(boxes_[6 * e + 3 + c]);
    }
  };
  // Two passes into a compressed layout: count per cell, then fill.
  const int64_t cells = dims_[0] * dims_[1] * dims_[2];
  cell_start_.assign(cells + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int64_t> next;
    if (pass == 1) {
      for (int64_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
      cell_elements_.resize(cell_start_[cells]);
      next.assign(cell_start_.begin(), cell_start_.end() - 1);
    }
    for (int64_t e = 0; e < num_elements_; ++e) {
      std::array<int64_t, 3> from, to;
      cell_range(e, &from, &to);
      for (int64_t k = from[2]; k <= to[2]; ++k) {
        for (int64_t j = from[1]; j <= to[1]; ++j) {
          for (int64_t i = from[0]; i <= to[0]; ++i) {
            const int64_t cell = (k * dims_[1] + j) * dims_[0] + i;
            if (pass == 0) {
              ++cell_start_[cell + 1];
            } else {
              cell_elements_[next[cell]++] = e;
            }
          }
        }
      }
    }
  }
}

Eigen::Vector3d ElementLocator::Node(int64_t e, int a) const {
  const int64_t node = elements_[per_element_ * e + a];
  return Eigen::Vector3d(nodes_[3 * node], nodes_[3 * node + 1], nodes_[3 * node + 2]);
}

bool ElementLocator::Inside(int64_t e, const Eigen::Vector3d& x, Eigen::Vector3d* xi) const {
  if (per_element_ == 4 || per_element_ == 10) {
    if (!Barycentric(Node(e, 0), Node(e, 1), Node(e, 2), Node(e, 3), x, xi)) return false;
    if (per_element_ == 4) return InsideTetrahedron(*xi, kInsideTolerance);
    // Far outside the straight element: not in the curved one either.
    if (!InsideTetrahedron(*xi, 0.5)) return false;
  } else {
    xi->setZero();
  }
  // Newton on x = sum N_a(xi) X_a from the straight element's coordinates
  // (10-node) or the centre (brick); a straight 10-node element or a
  // parallelepiped needs one step.
  Eigen::MatrixXd nodes(per_element_, 3);
  for (int a = 0; a < per_element_; ++a) nodes.row(a) = Node(e, a).transpose();
  const double scale = (nodes.colwise().maxCoeff() - nodes.colwise().minCoeff()).maxCoeff();
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::VectorXd n;
    Eigen::MatrixXd dn;
    if (per_element_ == 10) {
      n = Tet10ShapeFunctions(*xi);
      dn = Tet10NaturalGradients(*xi);
    } else {
      n = Hex8ShapeFunctions(*xi);
      dn = Hex8NaturalGradients(*xi);
    }
    const Eigen::Vector3d residual = x - nodes.transpose() * n;
    const Eigen::Matrix3d jacobian = nodes.transpose() * dn;
    const double det = jacobian.determinant();
    if (!(std::abs(det) > 0)) return false;
    const Eigen::Vector3d step = jacobian.inverse() * residual;
    *xi += step;
    if (!xi->allFinite() || xi->cwiseAbs().maxCoeff() > 10) return false;
    if (step.norm() < 1e-12 && residual.norm() < 1e-9 * scale) break;
  }
  // The map's image of xi must be x itself (Newton may stall outside).
  const Eigen::VectorXd n = ShapeFunctions(*xi);
  if ((x - nodes.transpose() * n).norm() > 1e-7 * scale) return false;
  if (per_element_ == 10) return InsideTetrahedron(*xi, kInsideTolerance);
  return xi->cwiseAbs().maxCoeff() <= 1 + kInsideTolerance;
}

std::vector<ElementLocator::Hit> ElementLocator::LocateAll(const Eigen::Vector3d& x_mm) const {
  std::vector<Hit> hits;
  if (num_elements_ == 0 || !x_mm.allFinite()) return hits;
  std::array<int64_t, 3> cell;
  for (int c = 0; c < 3; ++c) {
    const double index = std::floor((x_mm[c] - origin_[c]) / cell_mm_);
    if (index < 0 || index >= static_cast<double>(dims_[c])) return hits;
    cell[c] = static_cast<int64_t>(index);
  }
  const int64_t k = (cell[2] * dims_[1] + cell[1]) * dims_[0] + cell[0];
  for (int64_t i = cell_start_[k]; i < cell_start_[k + 1]; ++i) {
    const int64_t e = cell_elements_[i];
    const float* box = &boxes_[6 * e];
    bool in_box = true;
    for (int c = 0; c < 3 && in_box; ++c) in_box = x_mm[c] >= box[c] && x_mm[c] <= box[3 + c];
    Hit hit;
    if (in_box && Inside(e, x_mm, &hit.xi)) {
      hit.element = e;
      hits.push_back(hit);
    }
  }
  return hits;
}

int64_t ElementLocator::Locate(const Eigen::Vector3d& x_mm, Eigen::Vector3d* xi) const {
  const std::vector<Hit> hits = LocateAll(x_mm);
  if (hits.empty()) return -1;
  *xi = hits[0].xi;
  return hits[0].element;
}

Eigen::VectorXd ElementLocator::ShapeFunctions(const Eigen::Vector3d& xi) const {
  if (per_element_ == 10) return Tet10ShapeFunctions(xi);
  if (per_element_ == 8) return Hex8ShapeFunctions(xi);
  Eigen::VectorXd n(4);
  n << 1 - xi.sum(), xi.x(), xi.y(), xi.z();
  return n;
}

Status SampleProfiles(const std::vector<ProfileSpec>& profiles, const Solution& solution,
                      std::vector<ProfileTable>* tables) {
  tables->clear();
  if (profiles.empty()) return Status::Ok();
  const int npe = solution.nodes_per_element;
  const std::size_t nodes = solution.nodes_mm.size() / 3;
  if ((npe != 4 && npe != 10 && npe != 8) || solution.tets.size() % npe != 0 ||
      solution.displacement_mm.size() != 3 * nodes) {
    return Status::Internal("profiles: malformed solution mesh or displacement");
  }
  for (int64_t node : solution.tets) {
    if (node < 0 || static_cast<std::size_t>(node) >= nodes) {
      return Status::Internal("profiles: a node index out of range");
    }
  }
  const std::size_t ne = solution.tets.size() / npe;
  // Finite-strain analyses: the Euler-Almansi strain; linear ones: the small strain.
  const std::vector<double>& strain =
      solution.almansi_strain.size() == 6 * ne ? solution.almansi_strain : solution.strain;
  const bool has_stress = solution.stress_pa.size() == 6 * ne;
  const bool has_strain = strain.size() == 6 * ne;
  const bool has_von_mises = solution.von_mises_pa.size() == ne;

  const ElementLocator locator(solution.nodes_mm, solution.tets, npe);
  for (const ProfileSpec& profile : profiles) {
    ProfileTable table;
    table.name = profile.name;
    table.columns.assign(kColumns, kColumns + kColumnCount);
    const Eigen::Vector3d from(profile.from_mm.data()), to(profile.to_mm.data());
    const double length = (to - from).norm();
    const Eigen::Vector3d t = (to - from) / length;
    const int n = ProfilePointCount(profile);
    for (int i = 0; i < n; ++i) {
      const double f = static_cast<double>(i) / (n - 1);
      const Eigen::Vector3d x = i + 1 == n ? to : Eigen::Vector3d(from + f * (to - from));
      std::vector<double> row(kColumnCount, kNaN);
      row[kDistance] = f * length;
      for (int c = 0; c < 3; ++c) row[kX + c] = x[c];
      const std::vector<ElementLocator::Hit> hits = locator.LocateAll(x);
      if (!hits.empty()) {
        // The displacement is continuous: any holding element gives it.
        const Eigen::VectorXd shape = locator.ShapeFunctions(hits[0].xi);
        for (int c = 0; c < 3; ++c) row[kUx + c] = 0;
        for (int a = 0; a < npe; ++a) {
          const int64_t node = solution.tets[npe * hits[0].element + a];
          for (int c = 0; c < 3; ++c) {
            row[kUx + c] += shape[a] * solution.displacement_mm[3 * node + c];
          }
        }
        // Element fields: the mean over the holding elements.
        const double share = 1.0 / static_cast<double>(hits.size());
        row[kStressAlong] = row[kMeanStress] = has_stress ? 0 : kNaN;
        row[kVonMises] = has_von_mises ? 0 : kNaN;
        row[kStrainAlong] = has_strain ? 0 : kNaN;
        for (const ElementLocator::Hit& hit : hits) {
          const int64_t e = hit.element;
          if (has_stress) {
            const double* s = &solution.stress_pa[6 * e];
            row[kStressAlong] += share * AlongLine(s, t, 1);
            row[kMeanStress] += share * (s[0] + s[1] + s[2]) / 3;
          }
          if (has_von_mises) row[kVonMises] += share * solution.von_mises_pa[e];
          if (has_strain) row[kStrainAlong] += share * AlongLine(&strain[6 * e], t, 2);
        }
      }
      table.rows.push_back(std::move(row));
    }
    tables->push_back(std::move(table));
  }
  return Status::Ok();
}

std::vector<ProfileSummary> SummariseProfiles(const std::vector<ProfileTable>& tables) {
  std::vector<ProfileSummary> out;
  for (const ProfileTable& table : tables) {
    ProfileSummary s;
    s.name = table.name;
    s.points = static_cast<int>(table.rows.size());
    double largest = -1;
    for (const std::vector<double>& row : table.rows) {
      if (row.size() < kColumnCount || !std::isfinite(row[kUx])) continue;
      ++s.inside;
      const double stress = row[kStressAlong];
      if (std::isfinite(stress) && std::abs(stress) > largest) {
        largest = std::abs(stress);
        s.max_stress_along_pa = stress;
        s.at_distance_mm = row[kDistance];
        for (int c = 0; c < 3; ++c) s.at_mm[c] = row[kX + c];
      }
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace pba
