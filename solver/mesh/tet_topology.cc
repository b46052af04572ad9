#include "mesh/tet_topology.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <string>

#include "mesh/tet_angles.h"

namespace pba {
namespace {

bool Contains(const TetTopology::Tet& t, int n) {
  return t[0] == n || t[1] == n || t[2] == n || t[3] == n;
}

}  // namespace

Status TetTopology::Build(std::vector<char>* on_boundary) {
  const int num_nodes = mesh_.num_nodes();
  const int num_tets = static_cast<int>(tets_.size());
  if (!mesh_.element_region.empty() && mesh_.element_region.size() != tets_.size()) {
    return Status::InvalidArgument("mesh.element_region",
                                   "has " + std::to_string(mesh_.element_region.size()) +
                                       " entries for " + std::to_string(num_tets) + " tetrahedra");
  }
  std::vector<int> degree(num_nodes, 0);
  for (int e = 0; e < num_tets; ++e) {
    for (int n : tets_[e]) {
      if (n < 0 || n >= num_nodes) {
        return Status::InvalidArgument("mesh.tets", "element " + std::to_string(e) + " has node " +
                                                        std::to_string(n) + ", out of range");
      }
      ++degree[n];
    }
  }
  node_tets_.assign(num_nodes, {});
  for (int n = 0; n < num_nodes; ++n) node_tets_[n].reserve(degree[n] + 4);
  for (int e = 0; e < num_tets; ++e) {
    for (int n : tets_[e]) node_tets_[n].push_back(e);
  }
  region_ = mesh_.element_region;
  if (region_.empty()) region_.assign(num_tets, 0);
  alive_.assign(num_tets, 1);
  quality_.resize(num_tets);
  for (int e = 0; e < num_tets; ++e) {
    const Tet& t = tets_[e];
    const Eigen::Vector3d x0 = node(t[0]);
    if ((node(t[1]) - x0).dot((node(t[2]) - x0).cross(node(t[3]) - x0)) < 0) {
      return Status::InvalidArgument(
          "mesh.tets", "element " + std::to_string(e) + " is inverted (negative volume)");
    }
    quality_[e] = Quality(t);
  }
  changed_at_.assign(num_nodes, 0);

  // Each face is counted at its smallest node, among that node's elements
  // (few, and near in memory): a face of one element is on the boundary,
  // of three or more the mesh does not conform.
  on_boundary->assign(num_nodes, 0);
  std::vector<std::pair<int, int>> faces;  // the other two nodes, sorted
  for (int a = 0; a < num_nodes; ++a) {
    faces.clear();
    for (int e : node_tets_[a]) {
      // The three faces on a, each without one of the other corners.
      int others[3], count = 0;
      for (int n : tets_[e]) {
        if (n != a) others[count++] = n;
      }
      for (int skip = 0; skip < 3; ++skip) {
        const int b = others[skip == 0 ? 1 : 0], c = others[skip == 2 ? 1 : 2];
        if (b > a && c > a) faces.emplace_back(std::min(b, c), std::max(b, c));
      }
    }
    std::sort(faces.begin(), faces.end());
    for (std::size_t i = 0, j; i < faces.size(); i = j) {
      for (j = i + 1; j < faces.size() && faces[j] == faces[i]; ++j) {
      }
      const auto [b, c] = faces[i];
      if (j - i > 2) {
        return Status::InvalidArgument(
            "mesh.tets", "the face on nodes " + std::to_string(a) + ", " + std::to_string(b) +
                             ", " + std::to_string(c) + " belongs to " + std::to_string(j - i) +
                             " elements: the mesh does not conform");
      }
      if (j - i == 1) (*on_boundary)[a] = (*on_boundary)[b] = (*on_boundary)[c] = 1;
    }
  }
  return Status::Ok();
}

double TetTopology::Quality(const Tet& t) const {
  return measure_(node(t[0]), node(t[1]), node(t[2]), node(t[3]));
}

bool TetTopology::EdgeExists(int a, int b) const {
  for (int e : node_tets_[a]) {
    if (Contains(tets_[e], b)) return true;
  }
  return false;
}

int TetTopology::TetAcross(int e, int a, int b, int c) const {
  for (int other : node_tets_[a]) {
    if (other != e && Contains(tets_[other], b) && Contains(tets_[other], c)) return other;
  }
  return -1;
}

int TetTopology::Add(const Tet& t, int region, double quality, Journal* journal) {
  int e;
  if (free_.empty()) {
    e = static_cast<int>(tets_.size());
    tets_.push_back(t);
    region_.push_back(region);
    alive_.push_back(1);
    quality_.push_back(quality);
  } else {
    e = free_.back();
    free_.pop_back();
    tets_[e] = t;
    region_[e] = region;
    alive_[e] = 1;
    quality_[e] = quality;
  }
  for (int n : t) node_tets_[n].push_back(e);
  Touch(t, journal);
  if (journal != nullptr) journal->added.push_back(e);
  return e;
}

void TetTopology::Remove(int e, Journal* journal) {
  if (journal != nullptr) journal->removed.push_back({e, tets_[e], region_[e], quality_[e]});
  Touch(tets_[e], journal);
  for (int n : tets_[e]) {
    std::vector<int>& list = node_tets_[n];
    list.erase(std::find(list.begin(), list.end(), e));
  }
  alive_[e] = 0;
  free_.push_back(e);
}

void TetTopology::MoveNode(int n, const Eigen::Vector3d& x, Journal* journal) {
  if (journal != nullptr) journal->moved.emplace_back(n, node(n));
  mesh_.nodes.row(n) = x.transpose();
  for (int e : node_tets_[n]) {
    quality_[e] = Quality(tets_[e]);
    Touch(tets_[e], journal);
  }
}

int TetTopology::AddNode(const Eigen::Vector3d& x) {
  const int n = static_cast<int>(mesh_.nodes.rows());
  mesh_.nodes.conservativeResize(n + 1, Eigen::NoChange);
  mesh_.nodes.row(n) = x.transpose();
  node_tets_.emplace_back();
  changed_at_.push_back(++clock_);
  return n;
}

void TetTopology::Undo(const Journal& journal) {
  for (auto it = journal.moved.rbegin(); it != journal.moved.rend(); ++it)
    mesh_.nodes.row(it->first) = it->second.transpose();
  for (auto it = journal.added.rbegin(); it != journal.added.rend(); ++it) Remove(*it, nullptr);
  for (auto it = journal.removed.rbegin(); it != journal.removed.rend(); ++it) {
    // Back into its own slot, so that indices held by the caller stay
    // right; it was freed lately, so is found from the back.
    free_.erase(std::find(free_.rbegin(), free_.rend(), it->slot).base() - 1);
    tets_[it->slot] = it->tet;
    region_[it->slot] = it->region;
    quality_[it->slot] = it->quality;
    alive_[it->slot] = 1;
    for (int n : it->tet) node_tets_[n].push_back(it->slot);
  }
  for (const auto& [n, position] : journal.moved) {
    for (int e : node_tets_[n]) quality_[e] = Quality(tets_[e]);
  }
  for (auto it = journal.touched.rbegin(); it != journal.touched.rend(); ++it)
    changed_at_[it->first] = it->second;
}

void TetTopology::Compact() {
  std::vector<Tet> tets;
  std::vector<int> regions;
  tets.reserve(tets_.size());
  for (std::size_t e = 0; e < tets_.size(); ++e) {
    if (!alive_[e]) continue;
    tets.push_back(tets_[e]);
    regions.push_back(region_[e]);
  }
  tets_ = std::move(tets);
  if (!mesh_.element_region.empty()) mesh_.element_region = std::move(regions);
}

}  // namespace pba
