#include "mesh/improve.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "mesh/quality.h"
#include "mesh/tet_angles.h"
#include "mesh/tet_topology.h"

namespace pba {
namespace {

using Vec3 = Eigen::Vector3d;
using Tet = TetTopology::Tet;
using Triangle = std::array<int, 3>;

constexpr double kRadiansPerDegree = std::numbers::pi / 180;
constexpr int kLargestRing = 10;
constexpr std::size_t kCompositeTrials = 3;
// The most tetrahedra a node insertion's cavity grows to.
constexpr std::size_t kLargestCavity = 16;
// Even permutations putting corner i first (the orientation kept).
constexpr int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};

// The faces of a tetrahedron opposite its corners 0..3, each anticlockwise
// seen from outside a positively oriented one (as label_mesher.cc).
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

Triangle SortedTriangle(int a, int b, int c) {
  Triangle t{a, b, c};
  std::sort(t.begin(), t.end());
  return t;
}

struct TriangleHash {
  std::size_t operator()(const Triangle& t) const {
    std::uint64_t h = static_cast<std::uint32_t>(t[0]);
    h = h * 0x9E3779B97F4A7C15ull + static_cast<std::uint32_t>(t[1]);
    h = h * 0x9E3779B97F4A7C15ull + static_cast<std::uint32_t>(t[2]);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

bool Contains(const Tet& t, int n) { return t[0] == n || t[1] == n || t[2] == n || t[3] == n; }

// A replacement of some tetrahedra by others filling the same space.
struct Plan {
  enum class Kind { kNone, kFlip23, kEdgeRemoval };
  Kind kind = Kind::kNone;
  double old_quality = 0;  // smallest angle of `old_tets` [rad]
  // Smallest dihedral angle of `old_tets` and of `new_tets` [rad] (the
  // quality itself for the angle alone).
  double old_angle = 0, new_angle = 0;
  double quality = kInvalidTet;
  std::vector<int> old_tets;
  std::vector<Tet> new_tets;
  // Smallest angle of each new tetrahedron [rad].
  std::vector<double> new_quality;
};

class Improver {
 public:
  Improver(const ImproveOptions& options, Mesh* mesh)
      : options_(options),
        mesh_(*mesh),
        measure_(
            TetMeasure::ForTargets(options.target_min_dihedral_deg, options.target_aspect_ratio)),
        topology_(mesh, measure_),
        target_(options.target_aspect_ratio > 0
                    ? 1 / options.target_aspect_ratio
                    : options.target_min_dihedral_deg * kRadiansPerDegree),
        angle_target_(options.target_min_dihedral_deg * kRadiansPerDegree) {}

  // Checks the mesh, builds the adjacency and finds the nodes that stay;
  // on error the mesh is untouched.
  Status Prepare();
  void Run(ImproveStats* stats);

 private:
  using Journal = TetTopology::Journal;

  // Works on tetrahedron e while its smallest angle is below `target`
  // [rad]; true when something changed.
  bool ImproveTet(int e, double target);
  // Steps 2 and 3 on tetrahedron e; true when a flip was taken.
  bool Flip(int e);
  // For a tetrahedron that ImproveTet left below the target: improves the
  // tetrahedra sharing an edge with it towards twice the target, which can
  // open a flip or a move for it, then tries it again.
  bool ImproveAround(int e);
  // Node insertion: a new node inside a cavity of tetrahedra of e's region
  // around e, joined to the cavity's boundary faces; true when done.
  bool InsertNode(int e);
  // Moves node v to raise the smallest angle of its tetrahedra; false when
  // it may not move or nothing helps.
  bool SmoothNode(int v, Journal* journal);
  // Plans for removing edge (a, b) and for the 2-3 flip across the face of
  // e opposite `corner`; with `improve`, only a plan better than what it
  // replaces, else the best valid one.
  void PlanEdgeRemoval(int a, int b, bool improve, Plan* plan) const;
  void PlanFlip23(int e, int corner, bool improve, Plan* plan) const;
  void Apply(const Plan& plan, Journal* journal);
  void Count(const Plan& plan);
  // Applies `plan` and smooths the free corners of its new tetrahedra;
  // true when the smallest angle over the tetrahedra that changed has
  // risen, else everything is undone.
  bool ApplyAndSmooth(const Plan& plan);
  // The smallest dihedral angle of tetrahedron t [rad].
  double Angle(const Tet& t) const {
    return TetQuality(topology_.node(t[0]), topology_.node(t[1]), topology_.node(t[2]),
                      topology_.node(t[3]));
  }
  // Of tetrahedra `tets` (slots), or of `new_tets` (corners), the smallest.
  double SmallestAngle(const std::vector<int>& tets) const {
    double smallest = kPi;
    for (int e : tets) smallest = std::min(smallest, Angle(topology_.tet(e)));
    return smallest;
  }
  // The smallest quality (the measure) of tetrahedra `tets` (slots).
  double SmallestQuality(const std::vector<int>& tets) const {
    double smallest = kPi;
    for (int e : tets) smallest = std::min(smallest, topology_.quality(e));
    return smallest;
  }
  double SmallestAngle(const std::vector<Tet>& tets) const {
    double smallest = kPi;
    for (const Tet& t : tets) smallest = std::min(smallest, Angle(t));
    return smallest;
  }
  // With the aspect ratio in the measure a change must also keep the
  // smallest dihedral angle of what it touches at or above the lower of
  // what it was and the angle target: the measure alone would trade a
  // sliver for a better aspect ratio nearby, and the mesh's smallest angle
  // could fall.
  bool KeepsAngles(double old_angle, double new_angle) const {
    return measure_.angle_scale == 0 || new_angle >= std::min(old_angle, angle_target_);
  }
  void SetAngles(Plan* plan) const {
    if (measure_.angle_scale == 0) {
      plan->old_angle = plan->old_quality;
      plan->new_angle = plan->quality;
      return;
    }
    plan->old_angle = SmallestAngle(plan->old_tets);
    plan->new_angle = SmallestAngle(plan->new_tets);
  }
  bool Protected(int a, int b, int c) const {
    return protected_faces_.count(SortedTriangle(a, b, c)) != 0;
  }

  const ImproveOptions& options_;
  const Mesh& mesh_;
  const TetMeasure measure_;
  TetTopology topology_;
  const double target_;                                         // of measure_
  const double angle_target_;                                   // [rad]
  std::vector<char> fixed_;                                     // node may not move
  std::unordered_set<Triangle, TriangleHash> protected_faces_;  // face set triangles, sorted
  // When each node last failed to move (TetTopology's clock): smoothing it
  // again before anything around it changes would fail again.
  std::vector<long> failed_at_;
  // The same for each tetrahedron slot (-1: never failed): ImproveTet on
  // it changed nothing then (its trials undone leave the corners' times as
  // they were), and would again while nothing around its corners changes.
  std::vector<long> failed_tet_at_;
  // The slivers whose neighbours ImproveAround has worked on (sorted corners).
  std::set<Tet> surrounded_;
  ImproveStats stats_;
};

Status Improver::Prepare() {
  // Nodes that stay: on a boundary face (one tetrahedron), on a face set, or
  // between regions.
  PBA_RETURN_IF_ERROR(topology_.Build(&fixed_));
  const int num_nodes = mesh_.num_nodes();
  for (const auto& [name, set] : mesh_.face_sets) {
    for (const Triangle& t : set.triangles) {
      for (int n : t) {
        if (n < 0 || n >= num_nodes) {
          return Status::InvalidArgument(
              "mesh.face_sets",
              "set \"" + name + "\" has node " + std::to_string(n) + ", out of range");
        }
        fixed_[n] = 1;
      }
      protected_faces_.insert(SortedTriangle(t[0], t[1], t[2]));
    }
  }
  for (int n = 0; n < num_nodes; ++n) {
    const std::vector<int>& around = topology_.around(n);
    for (int e : around) {
      if (topology_.region(e) != topology_.region(around.front())) fixed_[n] = 1;
    }
  }
  failed_at_.assign(num_nodes, -1);
  return Status::Ok();
}

// Edge removal (Shewchuk 2002): the tetrahedra around the edge
// (a, b) are (a, b, r_i, r_i+1) for the ring r_0 .. r_m-1, each positively
// oriented, so the ring runs anticlockwise seen from b. A triangulation of
// the ring's polygon gives, for each triangle (r_i, r_k, r_j), i < k < j, the
// tetrahedra (r_i, r_k, r_j, b) and (r_i, r_j, r_k, a). Q[i][j], the best
// smallest angle over the sub-polygon r_i .. r_j, is the maximum over k of
// min(Q[i][k], Q[k][j], quality of the two tetrahedra on (r_i, r_k, r_j)).
void Improver::PlanEdgeRemoval(int a, int b, bool improve, Plan* plan) const {
  plan->kind = Plan::Kind::kNone;
  int ring_tets[kLargestRing];
  int m = 0;
  for (int e : topology_.around(a)) {
    if (!Contains(topology_.tet(e), b)) continue;
    if (m == options_.max_ring_size) return;
    ring_tets[m++] = e;
  }
  if (m < 3) return;
  const int region = topology_.region(ring_tets[0]);
  // (x, y) of each tetrahedron with (a, b, x, y) an even permutation of it.
  int from[kLargestRing], to[kLargestRing];
  double old_quality = kPi;
  for (int i = 0; i < m; ++i) {
    const Tet& t = topology_.tet(ring_tets[i]);
    if (topology_.region(ring_tets[i]) != region) return;
    old_quality = std::min(old_quality, topology_.quality(ring_tets[i]));
    int order[4], rest = 2;
    for (int p = 0; p < 4; ++p) {
      if (t[p] == a) {
        order[0] = p;
      } else if (t[p] == b) {
        order[1] = p;
      } else {
        order[rest++] = p;
      }
    }
    int inversions = 0;
    for (int p = 0; p < 4; ++p) {
      for (int q = p + 1; q < 4; ++q) inversions += order[p] > order[q];
    }
    from[i] = t[order[inversions % 2 == 0 ? 2 : 3]];
    to[i] = t[order[inversions % 2 == 0 ? 3 : 2]];
  }
  // Chain the ring; an open one (a boundary edge) is left alone.
  const auto successor = [&](int r) { return to[std::find(from, from + m, r) - from]; };
  int ring[kLargestRing];
  ring[0] = from[0];
  for (int i = 1; i < m; ++i) {
    ring[i] = successor(ring[i - 1]);
    if (std::find(from, from + m, ring[i]) == from + m) return;
  }
  if (successor(ring[m - 1]) != ring[0]) return;
  for (int i = 0; i < m; ++i) {
    if (std::count(ring, ring + m, ring[i]) != 1) return;  // not a simple ring
    if (Protected(a, b, ring[i])) return;
  }

  // A diagonal of the polygon may not already be an edge of the mesh (it
  // would be, geometrically, only if the new tetrahedra overlapped others).
  bool diagonal_ok[kLargestRing][kLargestRing];
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) {
      const bool side = j == i + 1 || (i == 0 && j == m - 1);
      diagonal_ok[i][j] = side || !topology_.EdgeExists(ring[i], ring[j]);
    }
  }
  const double floor = improve ? old_quality : kInvalidTet;
  const Vec3 xa = topology_.node(a), xb = topology_.node(b);
  Vec3 x[kLargestRing];
  for (int i = 0; i < m; ++i) x[i] = topology_.node(ring[i]);
  double best[kLargestRing][kLargestRing];
  int split[kLargestRing][kLargestRing];
  for (int i = 0; i + 1 < m; ++i) best[i][i + 1] = kPi;
  for (int length = 2; length < m; ++length) {
    for (int i = 0; i + length < m; ++i) {
      const int j = i + length;
      best[i][j] = kInvalidTet;
      split[i][j] = -1;
      if (!diagonal_ok[i][j]) continue;
      for (int k = i + 1; k < j; ++k) {
        double q = std::min(best[i][k], best[k][j]);
        if (q <= best[i][j] || q <= floor) continue;
        q = std::min(q, measure_(x[i], x[k], x[j], xb));
        if (q <= best[i][j] || q <= floor) continue;
        q = std::min(q, measure_(x[i], x[j], x[k], xa));
        if (q > best[i][j]) {
          best[i][j] = q;
          split[i][j] = k;
        }
      }
    }
  }
  if (!(best[0][m - 1] > floor)) return;
  plan->kind = Plan::Kind::kEdgeRemoval;
  plan->old_quality = old_quality;
  plan->quality = best[0][m - 1];
  plan->old_tets.assign(ring_tets, ring_tets + m);
  plan->new_tets.clear();
  plan->new_quality.clear();
  std::pair<int, int> stack[2 * kLargestRing];
  int depth = 0;
  stack[depth++] = {0, m - 1};
  while (depth > 0) {
    const auto [i, j] = stack[--depth];
    if (j - i < 2) continue;
    const int k = split[i][j];
    plan->new_tets.push_back({ring[i], ring[k], ring[j], b});
    plan->new_tets.push_back({ring[i], ring[j], ring[k], a});
    plan->new_quality.push_back(measure_(x[i], x[k], x[j], xb));
    plan->new_quality.push_back(measure_(x[i], x[j], x[k], xa));
    stack[depth++] = {i, k};
    stack[depth++] = {k, j};
  }
  SetAngles(plan);
}

// The 2-3 flip across the face (p, q, r) of `e` opposite its corner a: with
// b the other tetrahedron's far corner, the three tetrahedra around the new
// edge (a, b), all positively oriented exactly when it crosses the face.
void Improver::PlanFlip23(int e, int corner, bool improve, Plan* plan) const {
  plan->kind = Plan::Kind::kNone;
  const Tet& t = topology_.tet(e);
  const int a = t[corner];
  // Anticlockwise seen from outside e, that is from b's side.
  const int p = t[kTetFaces[corner][0]], q = t[kTetFaces[corner][1]], r = t[kTetFaces[corner][2]];
  const int other = topology_.TetAcross(e, p, q, r);
  if (other < 0 || topology_.region(other) != topology_.region(e) || Protected(p, q, r)) return;
  int b = -1;
  for (int n : topology_.tet(other)) {
    if (n != p && n != q && n != r) b = n;
  }
  if (topology_.EdgeExists(a, b)) return;
  const double old_quality = std::min(topology_.quality(e), topology_.quality(other));
  const double floor = improve ? old_quality : kInvalidTet;
  const Tet news[3] = {{a, b, p, q}, {a, b, q, r}, {a, b, r, p}};
  double quality[3];
  for (int i = 0; i < 3; ++i) {
    quality[i] = topology_.Quality(news[i]);
    if (!(quality[i] > floor)) return;
  }
  plan->kind = Plan::Kind::kFlip23;
  plan->old_quality = old_quality;
  plan->quality = std::min({quality[0], quality[1], quality[2]});
  plan->old_tets = {e, other};
  plan->new_tets.assign(news, news + 3);
  plan->new_quality.assign(quality, quality + 3);
  SetAngles(plan);
}

void Improver::Apply(const Plan& plan, Journal* journal) {
  const int region = topology_.region(plan.old_tets.front());
  for (int e : plan.old_tets) topology_.Remove(e, journal);
  for (std::size_t i = 0; i < plan.new_tets.size(); ++i)
    topology_.Add(plan.new_tets[i], region, plan.new_quality[i], journal);
}

void Improver::Count(const Plan& plan) {
  if (plan.kind == Plan::Kind::kFlip23) {
    ++stats_.flips_23;
  } else if (plan.old_tets.size() == 3) {
    ++stats_.flips_32;
  } else if (plan.old_tets.size() == 4) {
    ++stats_.flips_44;
  } else {
    ++stats_.edge_removals;
  }
}

bool Improver::ApplyAndSmooth(const Plan& plan) {
  std::vector<int> free_nodes;
  for (const Tet& t : plan.new_tets) {
    for (int n : t) {
      if (!fixed_[n] && std::find(free_nodes.begin(), free_nodes.end(), n) == free_nodes.end())
        free_nodes.push_back(n);
    }
  }
  if (free_nodes.empty()) return false;
  // The smallest angle around each free node before: its tetrahedra change
  // if it moves.
  std::vector<double> star_before(free_nodes.size(), kPi), angle_before(free_nodes.size(), kPi);
  for (std::size_t i = 0; i < free_nodes.size(); ++i) {
    for (int e : topology_.around(free_nodes[i]))
      star_before[i] = std::min(star_before[i], topology_.quality(e));
    if (measure_.angle_scale > 0) angle_before[i] = SmallestAngle(topology_.around(free_nodes[i]));
  }
  Journal journal;
  Apply(plan, &journal);
  for (int round = 0; round < 2; ++round) {
    for (int v : free_nodes) SmoothNode(v, &journal);
  }
  // The smallest angle over what changed: the replaced tetrahedra and the
  // stars of the nodes that moved, before and after.
  double before = plan.old_quality, after = kPi;
  double old_angle = plan.old_angle, new_angle = kPi;
  for (int e : journal.added) after = std::min(after, topology_.quality(e));
  if (measure_.angle_scale > 0) new_angle = SmallestAngle(journal.added);
  for (std::size_t i = 0; i < free_nodes.size(); ++i) {
    const int v = free_nodes[i];
    if (std::none_of(journal.moved.begin(), journal.moved.end(),
                     [v](const auto& moved) { return moved.first == v; }))
      continue;
    before = std::min(before, star_before[i]);
    old_angle = std::min(old_angle, angle_before[i]);
    for (int e : topology_.around(v)) after = std::min(after, topology_.quality(e));
    if (measure_.angle_scale > 0)
      new_angle = std::min(new_angle, SmallestAngle(topology_.around(v)));
  }
  if (!(after > before) || !KeepsAngles(old_angle, new_angle)) {
    topology_.Undo(journal);
    return false;
  }
  Count(plan);
  ++stats_.smoothed_flips;
  stats_.smoothed_nodes += static_cast<int>(journal.moved.size());
  return true;
}

bool Improver::SmoothNode(int v, Journal* journal) {
  if (fixed_[v]) return false;
  // Nothing around it has changed since it last failed to move.
  if (failed_at_[v] >= topology_.changed_at(v)) return false;
  const std::vector<int>& around = topology_.around(v);
  if (around.empty()) return false;
  // The star: each tetrahedron with v put first by an even permutation (the
  // orientation kept), as the positions of its other corners.
  std::vector<std::array<Vec3, 3>> star(around.size());
  double old_quality = kPi;
  Vec3 centroid = Vec3::Zero();
  for (std::size_t s = 0; s < around.size(); ++s) {
    const Tet& t = topology_.tet(around[s]);
    const int p = static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
    for (int c = 0; c < 3; ++c) star[s][c] = topology_.node(t[kEven[p][c + 1]]);
    old_quality = std::min(old_quality, topology_.quality(around[s]));
    centroid += (star[s][0] + star[s][1] + star[s][2]) / 3;
  }
  centroid /= static_cast<double>(around.size());
  const StarObjective objective(star, measure_);
  Vec3 best_x = topology_.node(v);
  double best = old_quality;
  if (const double q = objective.Value(centroid, best); q > best) {
    best = q;
    best_x = centroid;
  }
  if (best > 0) best = objective.Ascend(&best_x, best);
  bool keeps = true;
  if (best > old_quality && measure_.angle_scale > 0) {
    const StarObjective angles(star);
    keeps = KeepsAngles(angles.Value(topology_.node(v)), angles.Value(best_x));
  }
  if (!(best > old_quality) || !keeps) {
    failed_at_[v] = topology_.clock();
    return false;
  }
  topology_.MoveNode(v, best_x, journal);
  if (journal == nullptr) ++stats_.smoothed_nodes;
  return true;
}

bool Improver::ImproveTet(int e, double target) {
  bool changed = false;
  if (options_.smooth) {
    const Tet t = topology_.tet(e);
    for (int v : t) {
      if (topology_.quality(e) >= target) break;
      changed |= SmoothNode(v, nullptr);
    }
  }
  if (topology_.quality(e) >= target) return changed;
  if (options_.flip && Flip(e)) return true;
  // Last, for a sliver (not a tetrahedron only its aspect ratio holds
  // back: there are many more of those, and flips and moves serve them).
  if (options_.insert && Angle(topology_.tet(e)) < angle_target_ && InsertNode(e)) return true;
  return changed;
}

bool Improver::Flip(int e) {
  // The best flip that improves on its own; failing that, flips that may
  // make things worse until the free corners of their new tetrahedra have
  // moved, best first.
  static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  const Tet t = topology_.tet(e);
  for (const bool improve : {true, false}) {
    if (!improve && !options_.smooth) break;
    std::vector<Plan> plans;
    Plan plan;
    // An improving plan is taken as it is, so it must keep the angles
    // now; another is judged after its smoothing (ApplyAndSmooth).
    const auto usable = [&](const Plan& p) {
      return p.kind != Plan::Kind::kNone && (!improve || KeepsAngles(p.old_angle, p.new_angle));
    };
    for (const auto& edge : kEdges) {
      PlanEdgeRemoval(t[edge[0]], t[edge[1]], improve, &plan);
      if (usable(plan)) plans.push_back(plan);
    }
    for (int corner = 0; corner < 4; ++corner) {
      PlanFlip23(e, corner, improve, &plan);
      if (usable(plan)) plans.push_back(plan);
    }
    std::stable_sort(plans.begin(), plans.end(),
                     [](const Plan& x, const Plan& y) { return x.quality > y.quality; });
    if (improve && !plans.empty()) {
      Apply(plans.front(), nullptr);
      Count(plans.front());
      return true;
    }
    // Each trial costs a few smoothings: only the most promising.
    for (std::size_t i = 0; i < plans.size() && i < kCompositeTrials; ++i) {
      if (ApplyAndSmooth(plans[i])) return true;
    }
  }
  return false;
}

bool Improver::InsertNode(int e) {
  const int region = topology_.region(e);
  struct Face {
    int tet, corner;  // the face of `tet` opposite its corner
  };
  // The cavity's boundary: the faces of its tetrahedra not shared with
  // another of them. Each joined to the new node x makes the tetrahedron
  // with that face's opposite corner moved to x (the same orientation).
  const auto boundary = [&](const std::vector<int>& cavity, std::vector<Face>* faces) {
    faces->clear();
    for (int c : cavity) {
      const Tet& t = topology_.tet(c);
      for (int i = 0; i < 4; ++i) {
        const int across =
            topology_.TetAcross(c, t[kTetFaces[i][0]], t[kTetFaces[i][1]], t[kTetFaces[i][2]]);
        if (across < 0 || std::find(cavity.begin(), cavity.end(), across) == cavity.end())
          faces->push_back({c, i});
      }
    }
  };
  std::vector<int> cavity = {e};
  std::vector<Face> faces;
  std::vector<std::array<Vec3, 3>> star;
  double best = kInvalidTet;
  Vec3 best_x;
  std::vector<int> best_cavity;
  for (;;) {
    boundary(cavity, &faces);
    star.clear();
    for (const Face& f : faces) {
      const Tet& t = topology_.tet(f.tet);
      star.push_back({topology_.node(t[kEven[f.corner][1]]), topology_.node(t[kEven[f.corner][2]]),
                      topology_.node(t[kEven[f.corner][3]])});
    }
    // Every corner must stay on the boundary: one inside would be lost.
    std::vector<int> corners;
    for (int c : cavity)
      corners.insert(corners.end(), topology_.tet(c).begin(), topology_.tet(c).end());
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    const bool keeps_corners = std::all_of(corners.begin(), corners.end(), [&](int n) {
      return std::any_of(faces.begin(), faces.end(), [&](const Face& f) {
        const Tet& t = topology_.tet(f.tet);
        return t[f.corner] != n && Contains(t, n);
      });
    });
    // Where the node goes: the better of the sliver's centroid and the
    // cavity corners', then the steepest ascent of the smallest measure
    // over its tetrahedra (all positive: the cavity is star-shaped from
    // it, and they fill it).
    const StarObjective objective(star, measure_);
    Vec3 x = Vec3::Zero();
    for (int n : topology_.tet(e)) x += topology_.node(n) / 4;
    Vec3 mean = Vec3::Zero();
    for (int n : corners) mean += topology_.node(n) / static_cast<double>(corners.size());
    double q = objective.Value(x);
    if (const double other = objective.Value(mean); other > q) {
      q = other;
      x = mean;
    }
    if (q > 0) q = objective.Ascend(&x, q, 20);
    if (keeps_corners && q > best) {
      best = q;
      best_x = x;
      best_cavity = cavity;
    }
    if (cavity.size() == kLargestCavity) break;
    // Grow across the face whose new tetrahedron is worst, where the
    // tetrahedron behind it is of the region and the face on no face set.
    int grow = -1;
    double worst = kPi;
    for (std::size_t k = 0; k < faces.size(); ++k) {
      const Tet& t = topology_.tet(faces[k].tet);
      const int* f = kTetFaces[faces[k].corner];
      const int across = topology_.TetAcross(faces[k].tet, t[f[0]], t[f[1]], t[f[2]]);
      if (across < 0 || topology_.region(across) != region || Protected(t[f[0]], t[f[1]], t[f[2]]))
        continue;
      const double w = measure_(x, star[k][0], star[k][1], star[k][2]);
      if (w < worst) {
        worst = w;
        grow = across;
      }
    }
    if (grow < 0) break;
    cavity.push_back(grow);
  }
  if (best_cavity.empty() || !(best > SmallestQuality(best_cavity))) return false;
  // The new tetrahedra; -1 stands for the new node until it is numbered.
  boundary(best_cavity, &faces);
  std::vector<Tet> news;
  for (const Face& f : faces) {
    Tet t = topology_.tet(f.tet);
    t[f.corner] = -1;
    news.push_back(t);
  }
  if (measure_.angle_scale > 0) {
    double new_angle = kPi;
    for (const Tet& t : news) {
      Vec3 x[4];
      for (int c = 0; c < 4; ++c) x[c] = t[c] < 0 ? best_x : topology_.node(t[c]);
      new_angle = std::min(new_angle, TetQuality(x[0], x[1], x[2], x[3]));
    }
    if (!KeepsAngles(SmallestAngle(best_cavity), new_angle)) return false;
  }
  const int node = topology_.AddNode(best_x);
  fixed_.push_back(0);
  failed_at_.push_back(-1);
  for (int c : best_cavity) topology_.Remove(c, nullptr);
  for (Tet& t : news) {
    std::replace(t.begin(), t.end(), -1, node);
    topology_.Add(t, region, topology_.Quality(t), nullptr);
  }
  ++stats_.inserted_nodes;
  return true;
}

bool Improver::ImproveAround(int e) {
  const Tet t = topology_.tet(e);
  // Once for each sliver (by its corners): the neighbours, if they could
  // be improved, now have been.
  Tet key = t;
  std::sort(key.begin(), key.end());
  if (!surrounded_.insert(key).second) return false;
  // The tetrahedra sharing an edge with it.
  std::vector<int> near;
  for (int i = 0; i < 4; ++i) {
    for (int other : topology_.around(t[i])) {
      if (other == e || std::find(near.begin(), near.end(), other) != near.end()) continue;
      const Tet& o = topology_.tet(other);
      int shared = 0;
      for (int n : t) shared += Contains(o, n);
      if (shared >= 2) near.push_back(other);
    }
  }
  bool changed = false;
  for (int other : near) {
    // Slots can be freed and reused meanwhile: whatever lives there now is
    // near (or was made from what was), and gets the same treatment.
    if (topology_.alive(other)) changed |= ImproveTet(other, 2 * target_);
  }
  if (changed && topology_.alive(e) && topology_.tet(e) == t) ImproveTet(e, target_);
  return changed;
}

void Improver::Run(ImproveStats* stats) {
  const auto measure = [&](double* smallest, double* largest_aspect, int* below) {
    *smallest = kPi;
    *largest_aspect = 0;
    *below = 0;
    for (int e = 0; e < topology_.num_slots(); ++e) {
      if (!topology_.alive(e)) continue;
      *below += topology_.quality(e) < target_;
      Eigen::Matrix<double, 4, 3> x;
      for (int c = 0; c < 4; ++c) x.row(c) = topology_.node(topology_.tet(e)[c]).transpose();
      *smallest = std::min(*smallest, TetQuality(x.row(0), x.row(1), x.row(2), x.row(3)));
      *largest_aspect = std::max(*largest_aspect, TetAspectRatio(x));
    }
    *smallest = std::max(*smallest, 0.0) / kRadiansPerDegree;
  };
  measure(&stats_.min_dihedral_before_deg, &stats_.max_aspect_ratio_before,
          &stats_.below_target_before);
  // Worst first: the order in which the slivers' neighbourhoods are taken.
  // A pass that lifts fewer than 5 % of the tetrahedra below the target it
  // found is followed by one over the neighbours of the slivers left
  // (ImproveAround); passes end when one of those changes nothing or lifts
  // fewer than 5 % too.
  const auto below = [&](std::vector<std::pair<double, int>>* work) {
    work->clear();
    for (int e = 0; e < topology_.num_slots(); ++e) {
      if (topology_.alive(e) && topology_.quality(e) < target_)
        work->emplace_back(topology_.quality(e), e);
    }
    std::sort(work->begin(), work->end());
  };
  std::vector<std::pair<double, int>> work;
  below(&work);
  bool around = false;
  for (int pass = 0; pass < options_.max_passes && !work.empty(); ++pass) {
    ++stats_.passes;
    const std::size_t found = work.size();
    bool changed = false;
    for (const auto& [quality, e] : work) {
      // A slot may have been freed, or reused by a newer tetrahedron.
      if (!topology_.alive(e) || topology_.quality(e) >= target_) continue;
      if (around) {
        // The neighbours are worked on for slivers (below the angle
        // target), not for a tetrahedron that only the aspect ratio holds
        // back: the cost is the same, the gain small.
        if (measure_.angle_scale == 0 || Angle(topology_.tet(e)) < angle_target_)
          changed |= ImproveAround(e);
        continue;
      }
      // Nothing has changed at its corners since it last failed.
      if (e < static_cast<int>(failed_tet_at_.size()) && failed_tet_at_[e] >= 0 &&
          std::all_of(topology_.tet(e).begin(), topology_.tet(e).end(),
                      [&](int n) { return topology_.changed_at(n) <= failed_tet_at_[e]; }))
        continue;
      if (ImproveTet(e, target_)) {
        changed = true;
      } else {
        if (e >= static_cast<int>(failed_tet_at_.size())) failed_tet_at_.resize(e + 1, -1);
        failed_tet_at_[e] = topology_.clock();
      }
    }
    below(&work);
    // Fewer than 5 % of them lifted above the target: the passes that are
    // left would lift fewer still.
    const bool stalled = 20 * (found - std::min(found, work.size())) < found;
    if (around && (!changed || stalled)) break;
    around = !around && stalled;
  }
  measure(&stats_.min_dihedral_after_deg, &stats_.max_aspect_ratio_after,
          &stats_.below_target_after);
  topology_.Compact();
  if (stats != nullptr) *stats = stats_;
}

Status ValidateOptions(const ImproveOptions& o) {
  if (!(o.target_min_dihedral_deg > 0 && o.target_min_dihedral_deg < 70.5)) {
    return Status::InvalidArgument("target_min_dihedral_deg",
                                   "must lie in (0, 70.5): a regular tetrahedron's is 70.53");
  }
  if (!(o.target_aspect_ratio == 0 ||
        (o.target_aspect_ratio >= 1.5 && std::isfinite(o.target_aspect_ratio)))) {
    return Status::InvalidArgument("target_aspect_ratio",
                                   "must be 0 (the dihedral angle alone) or at least 1.5: a "
                                   "regular tetrahedron's is 1");
  }
  if (o.max_passes < 0) return Status::InvalidArgument("max_passes", "must be >= 0");
  if (o.max_ring_size < 3 || o.max_ring_size > kLargestRing) {
    return Status::InvalidArgument("max_ring_size",
                                   "must lie in 3.." + std::to_string(kLargestRing));
  }
  return Status::Ok();
}

}  // namespace

Status ImproveTetMesh(const ImproveOptions& options, Mesh* mesh, ImproveStats* stats) {
  if (mesh == nullptr) return Status::InvalidArgument("mesh", "no mesh given");
  // The flips and the smoothing work on linear tetrahedra only.
  switch (mesh->shape()) {
    case ElementShape::kTet4:
      break;
    case ElementShape::kTet10:
      return Status::InvalidArgument("mesh",
                                     "a quadratic mesh cannot be improved: improve the "
                                     "linear mesh, then make it quadratic");
    case ElementShape::kHex8:
      return Status::InvalidArgument("mesh",
                                     "a hexahedral mesh cannot be improved: only linear "
                                     "tetrahedra");
  }
  PBA_RETURN_IF_ERROR(ValidateOptions(options));
  // Prepare only reads the mesh: a refused mesh stays as it was.
  Improver improver(options, mesh);
  PBA_RETURN_IF_ERROR(improver.Prepare());
  improver.Run(stats);
  return Status::Ok();
}

void AddLaterPass(const ImproveStats& later, ImproveStats* total) {
  total->flips_23 += later.flips_23;
  total->flips_32 += later.flips_32;
  total->flips_44 += later.flips_44;
  total->edge_removals += later.edge_removals;
  total->smoothed_nodes += later.smoothed_nodes;
  total->smoothed_flips += later.smoothed_flips;
  total->inserted_nodes += later.inserted_nodes;
  total->passes += later.passes;
  total->min_dihedral_after_deg = later.min_dihedral_after_deg;
  total->max_aspect_ratio_after = later.max_aspect_ratio_after;
  total->below_target_after = later.below_target_after;
}

}  // namespace pba
