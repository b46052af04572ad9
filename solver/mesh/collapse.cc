#include "mesh/collapse.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "mesh/region_faces.h"
#include "mesh/tet_angles.h"
#include "mesh/tet_topology.h"

namespace pba {
namespace {

using Tet = TetTopology::Tet;

constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180;
// The vertex at infinity that the boundary is coned to in the links.
constexpr int kInfinity = INT_MAX;
// All regions at once in Links.
constexpr int kAllRegions = -1;

bool Contains(const Tet& t, int n) { return t[0] == n || t[1] == n || t[2] == n || t[3] == n; }

// The other three corners of t, without n.
std::array<int, 3> Others(const Tet& t, int n) {
  std::array<int, 3> out{};
  int count = 0;
  for (int m : t) {
    if (m != n) out[count++] = m;
  }
  return out;
}

// A surface patch: the faces between region `inner` and region `outer`
// (-1: the outside), inner < outer unless outer is -1.
using Patch = std::pair<int, int>;

// The link of a node or an edge in a simplicial complex (the whole mesh or
// one region's tetrahedra) with its boundary coned to kInfinity: its
// vertices, edges and triangles, each sorted.
struct Link {
  std::vector<int> vertices;
  std::vector<std::array<int, 2>> edges;
  std::vector<std::array<int, 3>> triangles;

  void Finish() {
    Unique(&vertices);
    Unique(&edges);
    Unique(&triangles);
  }
  template <typename T>
  static void Unique(std::vector<T>* v) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
};

template <typename T>
std::vector<T> Intersection(const std::vector<T>& a, const std::vector<T>& b) {
  std::vector<T> out;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

std::array<int, 2> SortedPair(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

std::array<int, 3> SortedTriple(int a, int b, int c) {
  std::array<int, 3> t{a, b, c};
  std::sort(t.begin(), t.end());
  return t;
}

class Collapser {
 public:
  Collapser(const CollapseOptions& options, Mesh* mesh)
      : options_(options),
        face_sets_(mesh->face_sets),
        topology_(mesh, TetMeasure::ForTargets(options.target_min_dihedral_deg,
                                               options.target_aspect_ratio)) {}

  Status Prepare() {
    std::vector<char> on_boundary;
    PBA_RETURN_IF_ERROR(topology_.Build(&on_boundary));
    held_.assign(on_boundary.size(), 0);
    for (const auto& [name, set] : face_sets_) {
      if (name == "surface" || ParseRegionSetName(name)) continue;
      for (const auto& t : set.triangles) {
        for (int n : t) held_[n] = 1;
      }
    }
    for (int e = 0; e < topology_.num_slots(); ++e) {
      const int r = topology_.region(e);
      if (r >= static_cast<int>(region_count_.size())) region_count_.resize(r + 1, 0);
      ++region_count_[r];
    }
    return Status::Ok();
  }

  void Run(CollapseStats* stats) {
    stats->min_dihedral_before_deg = SmallestAngleDeg();
    const double target = options_.target_min_dihedral_deg * kRadiansPerDegree;
    for (int pass = 0; pass < options_.max_passes; ++pass) {
      std::vector<std::pair<double, int>> work;
      for (int e = 0; e < topology_.num_slots(); ++e) {
        if (!topology_.alive(e)) continue;
        const double angle = Angle(topology_.tet(e));
        if (angle < target) work.emplace_back(angle, e);
      }
      std::sort(work.begin(), work.end());
      int done = 0;
      for (const auto& [angle, e] : work) {
        // A slot freed by a collapse may hold a new tetrahedron by now.
        if (topology_.alive(e) && Angle(topology_.tet(e)) < target) done += CollapseIn(e, stats);
      }
      if (done == 0) break;
    }
    // (Over the living slots: Compact renumbers them.)
    stats->min_dihedral_after_deg = SmallestAngleDeg();
    topology_.Compact();
  }

 private:
  double Angle(const Tet& t) const {
    return TetQuality(topology_.node(t[0]), topology_.node(t[1]), topology_.node(t[2]),
                      topology_.node(t[3]));
  }

  double SmallestAngleDeg() const {
    double smallest = kInvalidTet;
    for (int e = 0; e < topology_.num_slots(); ++e) {
      if (!topology_.alive(e)) continue;
      const double angle = Angle(topology_.tet(e));
      if (smallest == kInvalidTet || angle < smallest) smallest = angle;
    }
    return smallest == kInvalidTet ? 0 : smallest / kRadiansPerDegree;
  }

  // Collapses the shortest edge of e that may go, either way round; 1 when
  // one did.
  int CollapseIn(int e, CollapseStats* stats) {
    const Tet t = topology_.tet(e);
    std::vector<std::pair<double, std::array<int, 2>>> edges;
    double longest = 0;
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        const double length = (topology_.node(t[i]) - topology_.node(t[j])).norm();
        longest = std::max(longest, length);
        edges.push_back({length, {t[i], t[j]}});
      }
    }
    std::sort(edges.begin(), edges.end());
    const double bound = options_.max_edge_ratio * longest;
    for (const auto& [length, ends] : edges) {
      if (!(length < bound)) break;
      // A node on a surface or an interface moves at most max_edge_m.
      const bool short_enough = length < options_.max_edge_m;
      std::vector<Tet> keep_first, keep_second;
      std::vector<int> regions_first, regions_second;
      const double first = Plan(ends[0], ends[1], short_enough, &keep_first, &regions_first);
      const double second = Plan(ends[1], ends[0], short_enough, &keep_second, &regions_second);
      if (first == kInvalidTet && second == kInvalidTet) continue;
      const int b = first >= second ? ends[1] : ends[0];
      if (!Patches(b).empty())
        stats->longest_surface_m = std::max(stats->longest_surface_m, length);
      if (first >= second) {
        Apply(b, keep_first, regions_first);
      } else {
        Apply(b, keep_second, regions_second);
      }
      ++stats->edges;
      stats->longest_m = std::max(stats->longest_m, length);
      return 1;
    }
    return 0;
  }

  // The patches node v is on.
  std::vector<Patch> Patches(int v) const {
    std::vector<Patch> patches;
    for (int e : topology_.around(v)) {
      const Tet& t = topology_.tet(e);
      const std::array<int, 3> others = Others(t, v);
      for (int skip = 0; skip < 3; ++skip) {
        const int x = others[skip == 0 ? 1 : 0], y = others[skip == 2 ? 1 : 2];
        patches.push_back(PatchOf(e, v, x, y));
      }
    }
    std::sort(patches.begin(), patches.end());
    patches.erase(std::unique(patches.begin(), patches.end()), patches.end());
    // Faces inside a region are on no patch.
    patches.erase(std::remove_if(patches.begin(), patches.end(),
                                 [](const Patch& p) { return p.first == p.second; }),
                  patches.end());
    return patches;
  }

  // The patch of face (u, x, y) of tetrahedron e ((r, r) inside region r).
  Patch PatchOf(int e, int u, int x, int y) const {
    const int other = topology_.TetAcross(e, u, x, y);
    const int r = topology_.region(e);
    if (other < 0) return {r, -1};
    const int s = topology_.region(other);
    return {std::min(r, s), std::max(r, s)};
  }

  // The link of node v (b = -1) or of edge (v, b), in region `region`'s
  // tetrahedra or in all of them (kAllRegions).
  Link LinkOf(int v, int b, int region) const {
    Link link;
    const auto in = [&](int e) { return region == kAllRegions || topology_.region(e) == region; };
    // A face of an element of the complex is on its boundary when the
    // element across it is not in the complex.
    const auto boundary = [&](int e, int u, int x, int y) {
      const int other = topology_.TetAcross(e, u, x, y);
      return other < 0 || !in(other);
    };
    for (int e : topology_.around(v)) {
      if (!in(e)) continue;
      const Tet& t = topology_.tet(e);
      if (b >= 0 && !Contains(t, b)) continue;
      const std::array<int, 3> o = Others(t, v);
      if (b < 0) {
        link.vertices.insert(link.vertices.end(), o.begin(), o.end());
        link.triangles.push_back(SortedTriple(o[0], o[1], o[2]));
        for (int skip = 0; skip < 3; ++skip) {
          const int x = o[skip == 0 ? 1 : 0], y = o[skip == 2 ? 1 : 2];
          link.edges.push_back(SortedPair(x, y));
          if (boundary(e, v, x, y)) {
            link.vertices.push_back(kInfinity);
            link.edges.push_back(SortedPair(x, kInfinity));
            link.edges.push_back(SortedPair(y, kInfinity));
            link.triangles.push_back(SortedTriple(x, y, kInfinity));
          }
        }
      } else {
        // The edge's link: the two corners across it, and each face on the
        // edge that is on the boundary gives its third corner joined to
        // infinity.
        std::array<int, 2> xy{};
        int count = 0;
        for (int n : t) {
          if (n != v && n != b) xy[count++] = n;
        }
        link.vertices.push_back(xy[0]);
        link.vertices.push_back(xy[1]);
        link.edges.push_back(SortedPair(xy[0], xy[1]));
        for (int x : xy) {
          if (boundary(e, v, b, x)) {
            link.vertices.push_back(kInfinity);
            link.edges.push_back(SortedPair(x, kInfinity));
          }
        }
      }
    }
    link.Finish();
    return link;
  }

  // The link condition for collapsing (a, b) within one complex.
  bool LinkConditionHolds(int a, int b, int region) const {
    const Link la = LinkOf(a, -1, region), lb = LinkOf(b, -1, region);
    const Link lab = LinkOf(a, b, region);
    return Intersection(la.vertices, lb.vertices) == lab.vertices &&
           Intersection(la.edges, lb.edges) == lab.edges &&
           Intersection(la.triangles, lb.triangles).empty();
  }

  // The plan for moving b onto a: the tetrahedra around b that do not have
  // a, with a in b's place, and their regions; the worst of their qualities,
  // or kInvalidTet when the collapse may not be made (b on a surface and the
  // edge not `short_enough` among the reasons) or does not raise the worst
  // quality around b.
  double Plan(int a, int b, bool short_enough, std::vector<Tet>* tets,
              std::vector<int>* regions) const {
    if (held_[b] != 0) return kInvalidTet;
    // b's patches must be a's, and the edge on each of them.
    const std::vector<Patch> pb = Patches(b);
    if (!pb.empty()) {
      if (!short_enough) return kInvalidTet;
      const std::vector<Patch> pa = Patches(a);
      if (!std::includes(pa.begin(), pa.end(), pb.begin(), pb.end())) return kInvalidTet;
      std::vector<Patch> on_edge;
      for (int e : topology_.around(b)) {
        const Tet& t = topology_.tet(e);
        if (!Contains(t, a)) continue;
        for (int x : t) {
          if (x != a && x != b) on_edge.push_back(PatchOf(e, a, b, x));
        }
      }
      std::sort(on_edge.begin(), on_edge.end());
      if (!std::includes(on_edge.begin(), on_edge.end(), pb.begin(), pb.end())) return kInvalidTet;
    }
    // No region loses its last tetrahedron; the worst quality before.
    double worst_before = 1e300;
    std::vector<int> regions_around;
    std::vector<std::pair<int, int>> lost;  // region, tetrahedra lost
    for (int e : topology_.around(b)) {
      worst_before = std::min(worst_before, topology_.quality(e));
      const int r = topology_.region(e);
      regions_around.push_back(r);
      if (Contains(topology_.tet(e), a)) lost.emplace_back(r, 1);
    }
    std::sort(lost.begin(), lost.end());
    for (std::size_t i = 0, j; i < lost.size(); i = j) {
      for (j = i; j < lost.size() && lost[j].first == lost[i].first; ++j) {
      }
      if (static_cast<int>(j - i) >= region_count_[lost[i].first]) return kInvalidTet;
    }
    Link::Unique(&regions_around);
    if (!LinkConditionHolds(a, b, kAllRegions)) return kInvalidTet;
    // (b inside one region can still pinch it: a may be on its surface.)
    if (region_count_.size() > 1) {
      for (int r : regions_around) {
        if (!LinkConditionHolds(a, b, r)) return kInvalidTet;
      }
    }
    // The new tetrahedra: all positive, and their worst better than before.
    tets->clear();
    regions->clear();
    double worst_after = 1e300;
    for (int e : topology_.around(b)) {
      Tet t = topology_.tet(e);
      if (Contains(t, a)) continue;
      for (int& n : t) {
        if (n == b) n = a;
      }
      const double quality = topology_.Quality(t);
      if (quality == kInvalidTet) return kInvalidTet;
      worst_after = std::min(worst_after, quality);
      tets->push_back(t);
      regions->push_back(topology_.region(e));
    }
    if (tets->empty() || !(worst_after > worst_before)) return kInvalidTet;
    return worst_after;
  }

  void Apply(int b, const std::vector<Tet>& tets, const std::vector<int>& regions) {
    const std::vector<int> around = topology_.around(b);
    for (int e : around) {
      --region_count_[topology_.region(e)];
      topology_.Remove(e, nullptr);
    }
    for (std::size_t i = 0; i < tets.size(); ++i) {
      ++region_count_[regions[i]];
      topology_.Add(tets[i], regions[i], topology_.Quality(tets[i]), nullptr);
    }
    removed_ += static_cast<int>(around.size() - tets.size());
  }

 public:
  int removed() const { return removed_; }

 private:
  CollapseOptions options_;
  const std::map<std::string, FaceSet>& face_sets_;
  TetTopology topology_;
  std::vector<char> held_;
  std::vector<int> region_count_;
  int removed_ = 0;
};

Status ValidateOptions(const CollapseOptions& o) {
  if (!(o.target_min_dihedral_deg > 0 && o.target_min_dihedral_deg < 70.5)) {
    return Status::InvalidArgument("target_min_dihedral_deg", "must be in (0, 70.5) degrees");
  }
  if (!(o.target_aspect_ratio == 0 || o.target_aspect_ratio >= 1.5)) {
    return Status::InvalidArgument("target_aspect_ratio", "must be 0 or at least 1.5");
  }
  if (!(o.max_edge_m > 0 && std::isfinite(o.max_edge_m))) {
    return Status::InvalidArgument("max_edge_m", "must be a positive length");
  }
  if (!(o.max_edge_ratio > 0 && o.max_edge_ratio <= 1)) {
    return Status::InvalidArgument("max_edge_ratio", "must be in (0, 1]");
  }
  if (o.max_passes < 1) return Status::InvalidArgument("max_passes", "must be at least 1");
  return Status::Ok();
}

}  // namespace

Status CollapseShortEdges(const CollapseOptions& options, Mesh* mesh, CollapseStats* stats) {
  if (mesh == nullptr || mesh->shape() != ElementShape::kTet4) {
    return Status::InvalidArgument("mesh", "must be a linear tetrahedral mesh");
  }
  PBA_RETURN_IF_ERROR(ValidateOptions(options));
  // The topology edits the mesh's elements in place: work on a copy, so that
  // an error leaves the mesh untouched.
  Mesh work = *mesh;
  Collapser collapser(options, &work);
  PBA_RETURN_IF_ERROR(collapser.Prepare());
  CollapseStats local;
  collapser.Run(&local);
  local.removed_tetrahedra = collapser.removed();
  if (local.edges > 0) {
    DropUnusedNodes(&work);
    RebuildRegionFaceSets(&work);
    *mesh = std::move(work);
  }
  if (stats != nullptr) *stats = local;
  return Status::Ok();
}

}  // namespace pba
