#include "atlas/midside_projection.h"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>

#include "mesh/quadratic.h"
#include "mesh/quality.h"

namespace pba {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMmPerM = 1e3;

// The level-set functions of the face sets (see the header).
class Separators {
 public:
  Separators(const LoftField& loft, const std::vector<std::vector<int>>& region_labels)
      : loft_(loft), regions_(region_labels) {
    std::vector<char> kept(65536, 0);
    for (const std::vector<int>& labels : region_labels) {
      for (int l : labels) kept[l] = 1;
    }
    for (int l : loft.labels()) (kept[l] ? kept_ : dropped_).push_back(l);
  }

  // phi of the interface between regions a and b (negative on a's side).
  double Interface(int a, int b, const Eigen::Vector3d& x) const {
    return Min(regions_[a], x) - Min(regions_[b], x);
  }

  // phi of the body's outer surface (negative inside).
  double Surface(const Eigen::Vector3d& x) const {
    const double fg = loft_.SignedDistance(LoftField::kForeground, x);
    if (dropped_.empty()) return fg;
    const double kept = Min(kept_, x), dropped = Min(dropped_, x);
    if (dropped == kInf) return fg;  // no dropped label near: the foreground's edge
    return std::max(fg, kept - dropped);
  }

 private:
  double Min(const std::vector<int>& labels, const Eigen::Vector3d& x) const {
    double m = kInf;
    for (int l : labels) m = std::min(m, loft_.SignedDistance(l, x));
    return m;
  }

  const LoftField& loft_;
  const std::vector<std::vector<int>>& regions_;
  std::vector<int> kept_, dropped_;
};

// A face set's constraint: the surface (a = -1) or the interface a|b.
struct Constraint {
  int a = -1, b = -1;
};

// A boundary mid-edge node: its edge's corners and its constraints.
struct BoundaryNode {
  int node = 0;
  std::array<int, 2> corners{};
  std::vector<Constraint> constraints;
};

Eigen::Vector3d Position(const Mesh& mesh, int node) { return mesh.nodes.row(node).transpose(); }

// A node's constraints at a point [mm]: their values and gradients (central
// differences); false when one is not finite there or has no slope.
bool Evaluate(const Separators& separators, const std::vector<Constraint>& constraints,
              const Eigen::Vector3d& x, double h, Eigen::VectorXd* value,
              Eigen::MatrixXd* jacobian) {
  const auto phi = [&](const Constraint& c, const Eigen::Vector3d& p) {
    return c.a < 0 ? separators.Surface(p) : separators.Interface(c.a, c.b, p);
  };
  const int k = static_cast<int>(constraints.size());
  value->resize(k);
  jacobian->resize(k, 3);
  for (int i = 0; i < k; ++i) {
    (*value)[i] = phi(constraints[i], x);
    if (!std::isfinite((*value)[i])) return false;
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3d plus = x, minus = x;
      plus[axis] += h;
      minus[axis] -= h;
      (*jacobian)(i, axis) = (phi(constraints[i], plus) - phi(constraints[i], minus)) / (2 * h);
    }
    const double slope = jacobian->row(i).norm();
    if (!std::isfinite(slope) || slope == 0) return false;
  }
  return true;
}

// The distance from x to the constraints' level sets to first order: the
// largest |phi| / |grad phi|; +infinity where they are not evaluated.
double Gap(const Eigen::VectorXd& value, const Eigen::MatrixXd& jacobian) {
  double gap = 0;
  for (int i = 0; i < value.size(); ++i) {
    gap = std::max(gap, std::abs(value[i]) / jacobian.row(i).norm());
  }
  return gap;
}

// Mean, median and 90th percentile of the gaps; zeros for none.
GapStats Summarise(std::vector<double> gaps) {
  GapStats stats;
  if (gaps.empty()) return stats;
  double sum = 0;
  for (double g : gaps) sum += g;
  stats.mean_mm = sum / static_cast<double>(gaps.size());
  const auto at = [&](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(gaps.size() - 1));
    std::nth_element(gaps.begin(), gaps.begin() + k, gaps.end());
    return gaps[static_cast<size_t>(k)];
  };
  stats.median_mm = at(0.5);
  stats.p90_mm = at(0.9);
  return stats;
}

// Newton from the midpoint `mid` [mm] onto the constraints' common zero
// level; false when it fails (see the header), *x the result and *gap_mid
// the midpoint's Gap (+infinity when not evaluated).
bool Project(const Separators& separators, const std::vector<Constraint>& constraints,
             const Eigen::Vector3d& mid, double max_move, const MidsideProjectionOptions& options,
             Eigen::Vector3d* x, double* gap_mid) {
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd value;
  *x = mid;
  *gap_mid = std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
    if (!Evaluate(separators, constraints, *x, options.difference_step_mm, &value, &jacobian)) {
      return false;
    }
    const double gap = Gap(value, jacobian);
    if (iteration == 0) *gap_mid = gap;
    if (gap < options.tolerance_mm) return true;
    if (iteration == options.max_iterations) break;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(jacobian, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-6);
    *x -= svd.solve(value);
    if (!x->allFinite() || (*x - mid).norm() > max_move) return false;
  }
  return false;
}

}  // namespace

MidsideProjectionReport ProjectMidsideNodes(const LoftField& loft,
                                            const std::vector<std::vector<int>>& region_labels,
                                            const MidsideProjectionOptions& options, Mesh* mesh) {
  MidsideProjectionReport report;
  if (mesh->shape() != ElementShape::kTet10 || region_labels.size() != mesh->region_names.size()) {
    std::fprintf(stderr,
                 "pba: ProjectMidsideNodes needs a quadratic mesh and one label set per region\n");
    std::abort();
  }
  const int n = mesh->num_nodes(), ne = mesh->num_elements();
  // Every mid-edge node's corners, from the elements.
  std::vector<std::array<int, 2>> corners(n, {-1, -1});
  for (int e = 0; e < ne; ++e) {
    for (int k = 0; k < 6; ++k) {
      corners[mesh->midside[e][k]] = {mesh->tets[e][kTet10Edges[k][0]],
                                      mesh->tets[e][kTet10Edges[k][1]]};
    }
  }

  // The face sets' constraints, by name.
  std::map<std::string, Constraint> constraint_of;
  constraint_of["surface"] = Constraint();
  const std::vector<std::string>& names = mesh->region_names;
  for (int a = 0; a < static_cast<int>(names.size()); ++a) {
    for (int b = 0; b < static_cast<int>(names.size()); ++b) {
      if (a != b) constraint_of["interface:" + names[a] + "|" + names[b]] = {a, b};
    }
  }
  std::vector<int> index_of(n, -1);
  std::vector<BoundaryNode> boundary;
  for (const auto& [name, set] : mesh->face_sets) {
    const auto it = constraint_of.find(name);
    if (it == constraint_of.end()) continue;
    for (const std::array<int, 3>& mid : set.triangle_midside) {
      for (int node : mid) {
        if (index_of[node] < 0) {
          index_of[node] = static_cast<int>(boundary.size());
          boundary.push_back({node, corners[node], {}});
        }
        std::vector<Constraint>& c = boundary[index_of[node]].constraints;
        if (c.empty() || c.back().a != it->second.a || c.back().b != it->second.b) {
          c.push_back(it->second);
        }
      }
    }
  }
  report.boundary_nodes = static_cast<int64_t>(boundary.size());

  const Separators separators(loft, region_labels);
  const auto midpoint = [&](const BoundaryNode& b) -> Eigen::Vector3d {
    return 0.5 * (Position(*mesh, b.corners[0]) + Position(*mesh, b.corners[1]));
  };
  // Per node: its move [m] from the midpoint (the full one), and the
  // fraction of it kept (1, halved by the element check, 0 at the midpoint).
  std::vector<Eigen::Vector3d> move(n, Eigen::Vector3d::Zero());
  std::vector<double> kept(n, 0);
  std::vector<double> gaps_before, gaps_after;
  for (const BoundaryNode& b : boundary) {
    const Eigen::Vector3d mid = kMmPerM * midpoint(b);
    const double length =
        kMmPerM * (Position(*mesh, b.corners[0]) - Position(*mesh, b.corners[1])).norm();
    Eigen::Vector3d x;
    double gap = 0;
    const bool ok = Project(separators, b.constraints, mid, options.max_move_fraction * length,
                            options, &x, &gap);
    if (std::isfinite(gap)) gaps_before.push_back(gap);
    if (!ok) {
      ++report.unprojected;
      continue;
    }
    move[b.node] = (x - mid) / kMmPerM;
    kept[b.node] = 1;
    mesh->nodes.row(b.node) = (x / kMmPerM).transpose();
  }
  report.gap_midpoints_mm = Summarise(std::move(gaps_before));

  // The element check: the elements of each moved node, then rounds.
  std::vector<std::vector<int>> elements_of(boundary.size());
  std::vector<int> check;
  for (int e = 0; e < ne; ++e) {
    bool any = false;
    for (int node : mesh->midside[e]) {
      if (kept[node] == 0) continue;
      elements_of[index_of[node]].push_back(e);
      any = true;
    }
    if (any) check.push_back(e);
  }
  const double last = std::ldexp(1.0, -options.halvings);  // the smallest fraction kept
  std::vector<int> pass_of(n, 0);  // the pass that last changed a node: once per pass
  while (!check.empty()) {
    const int pass = ++report.check_passes;
    std::vector<int> changed;
    for (int e : check) {
      const double ratio = Tet10MaxJacobianRatio(Tet10Coordinates(*mesh, e));
      if (ratio <= options.max_jacobian_ratio) continue;  // also catches +infinity (inverted)
      for (int node : mesh->midside[e]) {
        if (kept[node] == 0 || pass_of[node] == pass) continue;
        pass_of[node] = pass;
        kept[node] = kept[node] > last ? 0.5 * kept[node] : 0;
        mesh->nodes.row(node) =
            (midpoint(boundary[index_of[node]]) + kept[node] * move[node]).transpose();
        changed.push_back(node);
      }
    }
    check.clear();
    for (int node : changed) {
      const std::vector<int>& elements = elements_of[index_of[node]];
      check.insert(check.end(), elements.begin(), elements.end());
    }
    std::sort(check.begin(), check.end());
    check.erase(std::unique(check.begin(), check.end()), check.end());
  }

  double move_sum = 0;
  for (const BoundaryNode& b : boundary) {
    if (kept[b.node] == 1) ++report.projected;
    if (kept[b.node] > 0 && kept[b.node] < 1) ++report.shortened;
    if (kept[b.node] == 0 && move[b.node] != Eigen::Vector3d::Zero()) ++report.reset;
    if (kept[b.node] > 0) {
      const double m = kMmPerM * kept[b.node] * move[b.node].norm();
      move_sum += m;
      report.max_move_mm = std::max(report.max_move_mm, m);
    }
    Eigen::MatrixXd jacobian;
    Eigen::VectorXd value;
    if (Evaluate(separators, b.constraints, kMmPerM * Position(*mesh, b.node),
                 options.difference_step_mm, &value, &jacobian)) {
      gaps_after.push_back(Gap(value, jacobian));
    }
  }
  const int64_t moved = report.projected + report.shortened;
  if (moved > 0) report.mean_move_mm = move_sum / static_cast<double>(moved);
  report.gap_mm = Summarise(std::move(gaps_after));
  return report;
}

}  // namespace pba
