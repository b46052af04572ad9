#include "mesh/quadratic.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace pba {
namespace {

// An edge as one sortable key: (smaller corner, larger corner).
uint64_t EdgeKey(int a, int b) {
  const auto lo = static_cast<uint64_t>(std::min(a, b)), hi = static_cast<uint64_t>(std::max(a, b));
  return lo << 32 | hi;
}

}  // namespace

Mesh MakeQuadratic(const Mesh& linear, const MidsideProjection& project) {
  switch (linear.shape()) {
    case ElementShape::kTet4:
      break;
    case ElementShape::kTet10:
      std::fprintf(stderr, "pba: MakeQuadratic called with a mesh that is already quadratic\n");
      std::abort();
    case ElementShape::kHex8:
      std::fprintf(stderr, "pba: MakeQuadratic called with a hexahedral mesh\n");
      std::abort();
  }
  const int n = linear.num_nodes(), ne = linear.num_elements();

  // Unique edges in key order; the position in `edges` numbers the node.
  std::vector<uint64_t> edges;
  edges.reserve(6 * static_cast<std::size_t>(ne));
  for (const auto& t : linear.tets) {
    for (const auto& e : kTet10Edges) edges.push_back(EdgeKey(t[e[0]], t[e[1]]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  const auto node_of = [&](int a, int b) {
    const uint64_t key = EdgeKey(a, b);
    const auto it = std::lower_bound(edges.begin(), edges.end(), key);
    if (it == edges.end() || *it != key) {
      // Face sets are built from element faces; anything else is a broken mesh.
      std::fprintf(stderr, "pba: MakeQuadratic: face edge (%d, %d) is no element's edge\n", a, b);
      std::abort();
    }
    return n + static_cast<int>(it - edges.begin());
  };

  // A copy, so that whatever else the mesh carries comes along.
  Mesh mesh = linear;
  mesh.nodes.conservativeResize(n + static_cast<Eigen::Index>(edges.size()), 3);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const int a = static_cast<int>(edges[k] >> 32), b = static_cast<int>(edges[k] & 0xffffffffu);
    mesh.nodes.row(n + static_cast<Eigen::Index>(k)) =
        0.5 * (linear.nodes.row(a) + linear.nodes.row(b));
  }
  mesh.midside.resize(ne);
  for (int e = 0; e < ne; ++e) {
    const auto& t = linear.tets[e];
    for (int k = 0; k < 6; ++k)
      mesh.midside[e][k] = node_of(t[kTet10Edges[k][0]], t[kTet10Edges[k][1]]);
  }

  // std::map iterates in name order, which fixes the order of projections.
  for (auto& [name, set] : mesh.face_sets) {
    set.triangle_midside.clear();
    set.triangle_midside.reserve(set.triangles.size());
    std::vector<int> mid;
    for (const auto& tri : set.triangles) {
      const std::array<int, 3> m = {node_of(tri[0], tri[1]), node_of(tri[1], tri[2]),
                                    node_of(tri[2], tri[0])};
      set.triangle_midside.push_back(m);
      mid.insert(mid.end(), m.begin(), m.end());
    }
    std::sort(mid.begin(), mid.end());
    mid.erase(std::unique(mid.begin(), mid.end()), mid.end());
    if (project) {
      for (int node : mid) {
        const Eigen::Vector3d moved = project(mesh.nodes.row(node).transpose(), name);
        mesh.nodes.row(node) = moved.transpose();
      }
    }
    CollectFaceSetNodes(&set);
  }
  return mesh;
}

std::array<int, 10> Tet10NodeIndices(const Mesh& mesh, int e) {
  std::array<int, 10> nodes;
  std::copy(mesh.tets[e].begin(), mesh.tets[e].end(), nodes.begin());
  std::copy(mesh.midside[e].begin(), mesh.midside[e].end(), nodes.begin() + 4);
  return nodes;
}

Tet10Nodes Tet10Coordinates(const Mesh& mesh, int e) {
  Tet10Nodes x;
  const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
  for (int a = 0; a < 10; ++a) x.row(a) = mesh.nodes.row(nodes[a]);
  return x;
}

}  // namespace pba
