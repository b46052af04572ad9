#include "mesh/refine.h"

#include <algorithm>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>

#include "core/format.h"

namespace pba {
namespace {

using Tet = std::array<int, 4>;
using Triangle = std::array<int, 3>;

constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
constexpr int kTriangleEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};

// The cut edges and their midpoints, the nodes growing as edges are cut.
class Cuts {
 public:
  // The mesh's nodes are its coarse ones; midpoints are appended (its rows
  // grow by doubling, Trim drops the spare ones).
  explicit Cuts(Mesh* mesh) : mesh_(*mesh), count_(mesh->num_nodes()) {}

  // Whether edge (a, b) comes after edge (c, d) in the order "longest"
  // means: squared length, then the sorted node indices.
  bool Longer(int a, int b, int c, int d) const {
    const double ab = Length2(a, b), cd = Length2(c, d);
    if (ab != cd) return ab > cd;
    return std::minmax(a, b) > std::minmax(c, d);
  }

  // The midpoint node of edge (a, b), or -1 when it is not cut.
  int Midpoint(int a, int b) const {
    const auto it = midpoints_.find(Key(a, b));
    return it == midpoints_.end() ? -1 : it->second;
  }

  // Cuts edge (a, b), if it is not cut yet; returns its midpoint.
  int Cut(int a, int b) {
    const auto [it, added] = midpoints_.try_emplace(Key(a, b), count_);
    if (!added) return it->second;
    if (count_ == mesh_.nodes.rows()) {
      mesh_.nodes.conservativeResize(std::max<Eigen::Index>(16, 2 * mesh_.nodes.rows()), 3);
    }
    mesh_.nodes.row(count_) = 0.5 * (mesh_.nodes.row(a) + mesh_.nodes.row(b));
    return count_++;
  }

  int64_t cut_edges() const { return static_cast<int64_t>(midpoints_.size()); }
  // Drops the spare rows Cut reserved.
  void Trim() { mesh_.nodes.conservativeResize(count_, 3); }

 private:
  static uint64_t Key(int a, int b) {
    const auto [lo, hi] = std::minmax(a, b);
    return (static_cast<uint64_t>(static_cast<uint32_t>(lo)) << 32) | static_cast<uint32_t>(hi);
  }
  // Always from the smaller index, so the same edge gives the same bits.
  double Length2(int a, int b) const {
    const auto [lo, hi] = std::minmax(a, b);
    return (mesh_.nodes.row(hi) - mesh_.nodes.row(lo)).squaredNorm();
  }

  Mesh& mesh_;
  Eigen::Index count_ = 0;
  std::unordered_map<uint64_t, int> midpoints_;
};

// The local edge (index into `edges`) that is longest.
template <std::size_t N, std::size_t E>
int LongestEdge(const Cuts& cuts, const std::array<int, N>& v, const int (&edges)[E][2]) {
  int longest = 0;
  for (int k = 1; k < static_cast<int>(E); ++k) {
    if (cuts.Longer(v[edges[k][0]], v[edges[k][1]], v[edges[longest][0]], v[edges[longest][1]]))
      longest = k;
  }
  return longest;
}

// The two halves of `v` cut through edge (i, j)'s midpoint m: v with its
// j-th node replaced by m, and with its i-th. Replacing a corner by a point
// between it and another corner keeps the orientation.
template <std::size_t N>
std::pair<std::array<int, N>, std::array<int, N>> Halves(const std::array<int, N>& v, int i, int j,
                                                         int m) {
  std::array<int, N> first = v, second = v;
  first[j] = m;
  second[i] = m;
  return {first, second};
}

}  // namespace

Status RefineTets(const Mesh& coarse, const std::vector<char>& marked, Mesh* fine,
                  RefineReport* report, std::vector<int>* parent) {
  if (coarse.hexahedral() || coarse.quadratic()) {
    return Status::InvalidArgument(
        "mesh", "only a 4-node tetrahedral mesh is refined (a 10-node one through its corners)");
  }
  const int ne = coarse.num_elements();
  if (static_cast<int>(marked.size()) != ne) {
    return Status::InvalidArgument("marked",
                                   Format("%zu entries for %d elements", marked.size(), ne));
  }
  const bool regions = !coarse.element_region.empty();
  if (regions && static_cast<int>(coarse.element_region.size()) != ne) {
    return Status::InvalidArgument("mesh.element_region", "not one entry per element");
  }
  Mesh out;
  out.nodes = coarse.nodes;
  out.region_names = coarse.region_names;
  Cuts cuts(&out);
  RefineReport r;
  for (int e = 0; e < ne; ++e) {
    if (!marked[e]) continue;
    ++r.marked;
    const Tet& t = coarse.tets[e];
    const int k = LongestEdge(cuts, t, kTetEdges);
    cuts.Cut(t[kTetEdges[k][0]], t[kTetEdges[k][1]]);
  }
  const int64_t asked = cuts.cut_edges();

  // Passes over the elements until one cuts no new edge. An element with a
  // cut edge is halved through its longest edge, cutting it if need be, and
  // its halves are looked at in turn. The result depends only on the set of
  // cut edges, so the elements a pass leaves whole are those of the final
  // mesh unless a later cut reaches them; each pass takes up where the
  // last one ended. Termination: every new cut is the longest edge of an
  // element with a shorter cut edge, and the lengths halve.
  std::vector<Tet> current = coarse.tets;
  // Each element's coarse element, carried through the passes.
  std::vector<int> origin(ne);
  std::iota(origin.begin(), origin.end(), 0);
  const int64_t bound = 64 * static_cast<int64_t>(std::max(ne, 1)) + 1000000;
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<Tet> next;
    std::vector<int> next_origin;
    next.reserve(current.size() + current.size() / 2);
    next_origin.reserve(next.capacity());
    std::vector<Tet> stack;
    for (std::size_t e = 0; e < current.size(); ++e) {
      stack.assign(1, current[e]);
      while (!stack.empty()) {
        const Tet t = stack.back();
        stack.pop_back();
        const int k = LongestEdge(cuts, t, kTetEdges);
        const int i = kTetEdges[k][0], j = kTetEdges[k][1];
        int m = cuts.Midpoint(t[i], t[j]);
        if (m < 0) {
          bool any = false;
          for (const auto& edge : kTetEdges)
            any = any || cuts.Midpoint(t[edge[0]], t[edge[1]]) >= 0;
          if (!any) {
            next.push_back(t);
            next_origin.push_back(origin[e]);
            continue;
          }
          m = cuts.Cut(t[i], t[j]);
          changed = true;
        }
        const auto [first, second] = Halves(t, i, j, m);
        stack.push_back(second);
        stack.push_back(first);
      }
      if (static_cast<int64_t>(next.size()) > bound) {
        return Status::Internal(Format("refinement of %d elements grew past %lld without ending",
                                       ne, static_cast<long long>(bound)));
      }
    }
    current = std::move(next);
    origin = std::move(next_origin);
  }
  r.cut_edges = cuts.cut_edges();
  r.propagated = r.cut_edges - asked;

  // Face-set triangles, cut by the same rule; a triangle of an element is
  // cut through its own longest edge whenever it is cut at all (the
  // element's longest edge, when it lies on the face, is the face's). A
  // triangle of no element may have a cut edge that is not its longest:
  // it is then cut through its longest cut edge.
  for (const auto& [name, set] : coarse.face_sets) {
    if (!set.quads.empty()) {
      return Status::InvalidArgument("mesh", "face set \"" + name + "\" has quadrilaterals");
    }
    FaceSet refined;
    std::vector<Triangle> stack;
    for (const Triangle& triangle : set.triangles) {
      stack.assign(1, triangle);
      while (!stack.empty()) {
        const Triangle t = stack.back();
        stack.pop_back();
        int k = -1;
        for (int q = 0; q < 3; ++q) {
          const int a = t[kTriangleEdges[q][0]], b = t[kTriangleEdges[q][1]];
          if (cuts.Midpoint(a, b) < 0) continue;
          if (k < 0 || cuts.Longer(a, b, t[kTriangleEdges[k][0]], t[kTriangleEdges[k][1]])) k = q;
        }
        if (k < 0) {
          refined.triangles.push_back(t);
          continue;
        }
        const int i = kTriangleEdges[k][0], j = kTriangleEdges[k][1];
        const auto [first, second] = Halves(t, i, j, cuts.Midpoint(t[i], t[j]));
        stack.push_back(second);
        stack.push_back(first);
      }
    }
    CollectFaceSetNodes(&refined);
    out.face_sets.emplace(name, std::move(refined));
  }
  cuts.Trim();
  out.tets = std::move(current);
  if (regions) {
    out.element_region.resize(origin.size());
    for (std::size_t f = 0; f < origin.size(); ++f)
      out.element_region[f] = coarse.element_region[origin[f]];
  }
  if (parent != nullptr) *parent = std::move(origin);
  r.elements = static_cast<int64_t>(out.tets.size());
  *fine = std::move(out);
  if (report != nullptr) *report = r;
  return Status::Ok();
}

Status RefineTetsRepeatedly(const Mesh& coarse, const std::vector<char>& marked, int times,
                            Mesh* fine, RefineReport* report, int64_t max_elements) {
  Mesh mesh = coarse;
  std::vector<char> mark = marked;
  // The coarse element of each element of `mesh`.
  std::vector<int> origin(coarse.num_elements());
  std::iota(origin.begin(), origin.end(), 0);
  RefineReport total;
  for (int pass = 0; pass < times; ++pass) {
    Mesh next;
    RefineReport r;
    std::vector<int> parent;
    PBA_RETURN_IF_ERROR(RefineTets(mesh, mark, &next, &r, &parent));
    if (pass == 0) total.marked = r.marked;
    total.cut_edges += r.cut_edges;
    total.propagated += r.propagated;
    total.elements = r.elements;
    std::vector<int> next_origin(parent.size());
    mark.assign(parent.size(), 0);
    for (std::size_t f = 0; f < parent.size(); ++f) {
      next_origin[f] = origin[parent[f]];
      mark[f] = marked[next_origin[f]];
    }
    origin = std::move(next_origin);
    mesh = std::move(next);
    if (max_elements > 0 && total.elements > max_elements) break;
  }
  *fine = std::move(mesh);
  if (report != nullptr) *report = total;
  return Status::Ok();
}

std::vector<char> MarkLargestShare(const std::vector<double>& share, double fraction) {
  std::vector<char> marked(share.size(), 0);
  double total = 0;
  for (const double s : share) total += std::max(s, 0.0);
  if (!(total > 0) || !(fraction > 0)) return marked;
  std::vector<std::size_t> order(share.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return share[a] > share[b]; });
  const double wanted = std::min(fraction, 1.0) * total;
  double carried = 0, last = 0;
  for (const std::size_t e : order) {
    // Past the fraction, only what ties with the last one taken.
    if (carried >= wanted && share[e] < last * (1 - kShareTie)) break;
    marked[e] = 1;
    carried += std::max(share[e], 0.0);
    last = share[e];
  }
  return marked;
}

}  // namespace pba
