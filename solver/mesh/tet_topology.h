// A linear tetrahedral mesh under local change, for mesh improvement
// (mesh/improve.h): element slots that are freed and reused, the elements
// around each node, each element's region and shape (TetMeasure, kept up to
// date), and a journal that undoes a trial change.
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "mesh/mesh.h"
#include "mesh/tet_angles.h"
#include "pba/status.h"

namespace pba {

class TetTopology {
 public:
  using Tet = std::array<int, 4>;

  // What a series of changes did, so that Undo can reverse it.
  struct Journal {
    struct Removed {
      int slot;
      Tet tet;
      int region;
      double quality;
    };
    std::vector<Removed> removed;
    std::vector<int> added;                              // slots
    std::vector<std::pair<int, Eigen::Vector3d>> moved;  // node, former position
    std::vector<std::pair<int, long>> touched;           // node, former changed_at
  };

  // Edits mesh->tets and mesh->nodes in place (the mesh is borrowed and
  // must outlive this); Compact writes the elements back. `measure` is the
  // elements' quality.
  explicit TetTopology(Mesh* mesh, TetMeasure measure = {})
      : mesh_(*mesh), measure_(measure), tets_(mesh->tets) {}

  // Checks the mesh and builds the adjacency: InvalidArgument
  // "mesh.element_region" when it is neither empty nor one entry per
  // element, "mesh.tets" for a node index out of range, an inverted element
  // (negative volume) or a face of three or more elements. Sets
  // (*on_boundary)[n] for the nodes on a face of a single element. Only
  // reads the mesh.
  Status Build(std::vector<char>* on_boundary);

  int num_slots() const { return static_cast<int>(tets_.size()); }
  bool alive(int e) const { return alive_[e] != 0; }
  const Tet& tet(int e) const { return tets_[e]; }
  int region(int e) const { return region_[e]; }
  double quality(int e) const { return quality_[e]; }
  // The elements with node n, in no particular order.
  const std::vector<int>& around(int n) const { return node_tets_[n]; }
  Eigen::Vector3d node(int n) const { return mesh_.nodes.row(n).transpose(); }
  double Quality(const Tet& t) const;

  bool EdgeExists(int a, int b) const;
  // The element other than `e` with the face (a, b, c), or -1.
  int TetAcross(int e, int a, int b, int c) const;

  // Changes, recorded in `journal` (may be null). Add takes the element's
  // quality as computed by the caller (the planner has it).
  int Add(const Tet& t, int region, double quality, Journal* journal);
  void Remove(int e, Journal* journal);
  void MoveNode(int n, const Eigen::Vector3d& x, Journal* journal);
  // A new node at x, appended to the mesh's nodes, in no element yet (the
  // caller adds its elements at once); its index. Not journalled: a node
  // is added only for a change already decided.
  int AddNode(const Eigen::Vector3d& x);
  void Undo(const Journal& journal);

  // A clock that ticks at every change, and when the elements around each
  // node last changed (an element with it added, removed or reshaped). A
  // change undone (Undo) leaves the nodes' times as they were: nothing
  // around them has changed.
  long clock() const { return clock_; }
  long changed_at(int n) const { return changed_at_[n]; }

  // Writes the living elements back to the mesh, in slot order, with their
  // regions (element_region stays empty if it was).
  void Compact();

 private:
  void Touch(const Tet& t, Journal* journal) {
    ++clock_;
    for (int n : t) {
      if (journal != nullptr) journal->touched.emplace_back(n, changed_at_[n]);
      changed_at_[n] = clock_;
    }
  }

  Mesh& mesh_;
  TetMeasure measure_;
  std::vector<Tet>& tets_;
  std::vector<int> region_;
  std::vector<char> alive_;
  std::vector<double> quality_;  // measure_ of each slot
  std::vector<int> free_;        // freed slots, reused last freed first
  std::vector<std::vector<int>> node_tets_;
  long clock_ = 0;
  std::vector<long> changed_at_;
};

}  // namespace pba
