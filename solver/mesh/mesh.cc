#include "mesh/mesh.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace pba {

NodeList Mesh::ElementNodes(int e) const {
  NodeList list;
  switch (shape()) {
    case ElementShape::kTet4:
      std::copy(tets[e].begin(), tets[e].end(), list.node.begin());
      break;
    case ElementShape::kTet10:
      std::copy(tets[e].begin(), tets[e].end(), list.node.begin());
      std::copy(midside[e].begin(), midside[e].end(), list.node.begin() + 4);
      break;
    case ElementShape::kHex8:
      std::copy(hexes[e].begin(), hexes[e].end(), list.node.begin());
      break;
  }
  list.count = ShapeInfo(shape()).nodes;
  return list;
}

NodeList Mesh::ElementCorners(int e) const {
  NodeList list = ElementNodes(e);
  list.count = ShapeInfo(shape()).corners;
  return list;
}

Eigen::Matrix<double, 4, 3> TetCorners(const Mesh& mesh, int e) {
  Eigen::Matrix<double, 4, 3> x;
  for (int a = 0; a < 4; ++a) x.row(a) = mesh.nodes.row(mesh.tets[e][a]);
  return x;
}

Eigen::Matrix<double, 8, 3> HexCorners(const Mesh& mesh, int e) {
  Eigen::Matrix<double, 8, 3> x;
  for (int a = 0; a < 8; ++a) x.row(a) = mesh.nodes.row(mesh.hexes[e][a]);
  return x;
}

double HexVolume(const Mesh& mesh, int e) {
  static constexpr int kCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                        {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  const Eigen::Matrix<double, 8, 3> x = HexCorners(mesh, e);
  const double g = 1 / std::sqrt(3.0);  // 2-point Gauss abscissa, weight 1
  double volume = 0;
  for (int q = 0; q < 8; ++q) {
    const double p[3] = {kCorner[q][0] * g, kCorner[q][1] * g, kCorner[q][2] * g};
    // dN_a/dxi_i of the trilinear N_a = prod_j (1 + xi_j c_aj) / 8.
    Eigen::Matrix<double, 8, 3> dn;
    for (int a = 0; a < 8; ++a) {
      const double f[3] = {1 + p[0] * kCorner[a][0], 1 + p[1] * kCorner[a][1],
                           1 + p[2] * kCorner[a][2]};
      dn(a, 0) = kCorner[a][0] * f[1] * f[2] / 8;
      dn(a, 1) = kCorner[a][1] * f[0] * f[2] / 8;
      dn(a, 2) = kCorner[a][2] * f[0] * f[1] / 8;
    }
    volume += (x.transpose() * dn).determinant();
  }
  return volume;
}

double FaceSetArea(const Mesh& mesh, const FaceSet& set) {
  double area = 0;
  for (const auto& t : set.triangles) {
    const Eigen::Vector3d a = mesh.nodes.row(t[0]).transpose();
    const Eigen::Vector3d b = mesh.nodes.row(t[1]).transpose();
    const Eigen::Vector3d c = mesh.nodes.row(t[2]).transpose();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  const double g = 1 / std::sqrt(3.0);
  for (const auto& quad : set.quads) {
    Eigen::Vector3d x[4];
    for (int k = 0; k < 4; ++k) x[k] = mesh.nodes.row(quad[k]).transpose();
    for (const double xi : {-g, g}) {
      for (const double eta : {-g, g}) {
        // x_,xi and x_,eta of the bilinear map with corners at (-1,-1),
        // (1,-1), (1,1), (-1,1).
        const Eigen::Vector3d g1 = ((1 - eta) * (x[1] - x[0]) + (1 + eta) * (x[2] - x[3])) / 4;
        const Eigen::Vector3d g2 = ((1 - xi) * (x[3] - x[0]) + (1 + xi) * (x[2] - x[1])) / 4;
        area += g1.cross(g2).norm();
      }
    }
  }
  return area;
}

std::vector<std::array<int, 2>> FaceElements(const Mesh& mesh, const FaceSet& set) {
  // Sorted triangle -> its index in the set, then one pass over the elements.
  struct Hash {
    std::size_t operator()(const std::array<int, 3>& k) const {
      return (static_cast<std::size_t>(k[0]) * 73856093u) ^
             (static_cast<std::size_t>(k[1]) * 19349663u) ^
             (static_cast<std::size_t>(k[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<int, 3>, int, Hash> index;
  index.reserve(set.triangles.size());
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    std::array<int, 3> key = set.triangles[i];
    std::sort(key.begin(), key.end());
    index.emplace(key, static_cast<int>(i));
  }
  std::vector<std::array<int, 2>> owner(set.triangles.size(), {-1, -1});
  if (index.empty()) return owner;
  for (int e = 0; e < static_cast<int>(mesh.tets.size()); ++e) {
    const auto& tet = mesh.tets[e];
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> key;
      for (int k = 0, n = 0; k < 4; ++k) {
        if (k != skip) key[n++] = tet[k];
      }
      std::sort(key.begin(), key.end());
      const auto it = index.find(key);
      if (it != index.end()) owner[it->second] = {e, skip};
    }
  }
  return owner;
}

std::vector<std::array<int, 2>> QuadFaceElements(const Mesh& mesh, const FaceSet& set) {
  // As FaceElements: sorted quad -> its index in the set, then one pass over
  // the bricks' faces.
  std::map<std::array<int, 4>, int> index;
  for (std::size_t i = 0; i < set.quads.size(); ++i) {
    std::array<int, 4> key = set.quads[i];
    std::sort(key.begin(), key.end());
    index.emplace(key, static_cast<int>(i));
  }
  std::vector<std::array<int, 2>> owner(set.quads.size(), {-1, -1});
  if (index.empty()) return owner;
  for (int e = 0; e < static_cast<int>(mesh.hexes.size()); ++e) {
    for (int face = 0; face < 6; ++face) {
      std::array<int, 4> key;
      for (int k = 0; k < 4; ++k) key[k] = mesh.hexes[e][kHex8Faces[face][k]];
      std::sort(key.begin(), key.end());
      const auto it = index.find(key);
      if (it != index.end()) owner[it->second] = {e, face};
    }
  }
  return owner;
}

void CollectFaceSetNodes(FaceSet* set) {
  auto& nodes = set->nodes;
  nodes.clear();
  for (const auto& t : set->triangles) nodes.insert(nodes.end(), t.begin(), t.end());
  for (const auto& t : set->triangle_midside) nodes.insert(nodes.end(), t.begin(), t.end());
  for (const auto& q : set->quads) nodes.insert(nodes.end(), q.begin(), q.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
}

FaceSet FacesWhere(const Mesh& mesh, const FaceSet& set,
                   const std::function<bool(const Eigen::Vector3d& x)>& keep, bool complement) {
  const auto kept = [&](const auto& face) {
    return complement != std::all_of(face.begin(), face.end(), [&](int node) {
             return keep(mesh.nodes.row(node).transpose());
           });
  };
  FaceSet patch;
  for (std::size_t t = 0; t < set.triangles.size(); ++t) {
    if (!kept(set.triangles[t])) continue;
    patch.triangles.push_back(set.triangles[t]);
    if (!set.triangle_midside.empty()) patch.triangle_midside.push_back(set.triangle_midside[t]);
  }
  for (const auto& q : set.quads) {
    if (kept(q)) patch.quads.push_back(q);
  }
  CollectFaceSetNodes(&patch);
  return patch;
}

FaceSet FacesWithin(const Mesh& mesh, const FaceSet& set, const Eigen::Vector3d& centre,
                    double radius) {
  return FacesWhere(mesh, set,
                    [&](const Eigen::Vector3d& x) { return (x - centre).norm() <= radius; });
}

std::vector<int> MeshPieces(const Mesh& mesh, int* pieces) {
  const int ne = mesh.num_elements();
  std::vector<std::vector<int>> around(mesh.num_nodes());
  for (int e = 0; e < ne; ++e) {
    for (int a : mesh.ElementCorners(e)) around[a].push_back(e);
  }
  std::vector<int> parent(ne);
  for (int e = 0; e < ne; ++e) parent[e] = e;
  const auto root = [&](int e) {
    while (parent[e] != e) e = parent[e] = parent[parent[e]];
    return e;
  };
  std::vector<int> candidates;
  for (int e = 0; e < ne; ++e) {
    // An element met through three of e's corners shares a face with it.
    candidates.clear();
    for (int a : mesh.ElementCorners(e)) {
      for (int f : around[a]) {
        if (f > e) candidates.push_back(f);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    for (std::size_t i = 0; i < candidates.size();) {
      std::size_t j = i;
      while (j < candidates.size() && candidates[j] == candidates[i]) ++j;
      if (j - i >= 3) parent[root(candidates[i])] = root(e);
      i = j;
    }
  }
  std::vector<int> piece(ne, -1), number(ne, -1);
  *pieces = 0;
  for (int e = 0; e < ne; ++e) {
    const int r = root(e);
    if (number[r] < 0) number[r] = (*pieces)++;
    piece[e] = number[r];
  }
  return piece;
}

}  // namespace pba
