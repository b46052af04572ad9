#include "mesh/region_faces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <unordered_map>
#include <vector>

#include "mesh/quality.h"

namespace pba {
namespace {

// The faces of a positively oriented tetrahedron opposite its nodes 0..3,
// each anticlockwise seen from outside it.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
  std::array<int, 3> sorted;
  bool operator==(const FaceKey& o) const { return sorted == o.sorted; }
};
struct FaceKeyHash {
  std::size_t operator()(const FaceKey& k) const {
    std::size_t h = 0;
    for (int v : k.sorted) h = h * 1000003u ^ static_cast<std::size_t>(v);
    return h;
  }
};

std::array<int, 3> Face(const Mesh& mesh, int e, int f) {
  const std::array<int, 4>& t = mesh.tets[e];
  return {t[kTetFaces[f][0]], t[kTetFaces[f][1]], t[kTetFaces[f][2]]};
}

FaceKey Key(std::array<int, 3> face) {
  std::sort(face.begin(), face.end());
  return {face};
}

// neighbour[4 e + f]: the tetrahedron across face f of tetrahedron e, -1 on
// the boundary.
std::vector<int> FaceNeighbours(const Mesh& mesh) {
  const int n = static_cast<int>(mesh.tets.size());
  std::vector<int> neighbour(4 * static_cast<std::size_t>(n), -1);
  std::unordered_map<FaceKey, int, FaceKeyHash> open;  // face -> 4 e + f
  open.reserve(2 * static_cast<std::size_t>(n));
  for (int e = 0; e < n; ++e) {
    for (int f = 0; f < 4; ++f) {
      const FaceKey key = Key(Face(mesh, e, f));
      const auto [it, added] = open.emplace(key, 4 * e + f);
      if (added) continue;
      neighbour[4 * e + f] = it->second / 4;
      neighbour[it->second] = e;
      open.erase(it);
    }
  }
  return neighbour;
}

double Volume(const Mesh& mesh, int e) {
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
  return (x.row(1) - x.row(0)).cross(x.row(2) - x.row(0)).dot(x.row(3) - x.row(0)) / 6;
}

}  // namespace

std::string RegionSurfaceSetName(const std::string& region) { return "surface:" + region; }

std::string InterfaceSetName(const std::string& first, const std::string& second) {
  return "interface:" + first + "|" + second;
}

std::optional<RegionSetName> ParseRegionSetName(const std::string& name) {
  RegionSetName parsed;
  if (name.rfind("surface:", 0) == 0) {
    parsed.first = name.substr(8);
    return parsed;
  }
  if (name.rfind("interface:", 0) != 0) return std::nullopt;
  const std::string pair = name.substr(10);
  const std::size_t bar = pair.find('|');
  if (bar == std::string::npos) return std::nullopt;
  parsed.interface = true;
  parsed.first = pair.substr(0, bar);
  parsed.second = pair.substr(bar + 1);
  return parsed;
}

void RebuildRegionFaceSets(Mesh* mesh) {
  for (auto it = mesh->face_sets.begin(); it != mesh->face_sets.end();) {
    const std::string& name = it->first;
    const bool derived =
        name == "surface" || name.rfind("surface:", 0) == 0 || name.rfind("interface:", 0) == 0;
    it = derived ? mesh->face_sets.erase(it) : std::next(it);
  }
  const std::vector<int> neighbour = FaceNeighbours(*mesh);
  const bool regions = !mesh->element_region.empty();
  FaceSet surface;
  std::vector<FaceSet> region_surfaces(regions ? mesh->region_names.size() : 0);
  std::map<std::pair<int, int>, FaceSet> interfaces;
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) {
    const int mine = regions ? mesh->element_region[e] : 0;
    for (int f = 0; f < 4; ++f) {
      const int other = neighbour[4 * e + f];
      const std::array<int, 3> face = Face(*mesh, e, f);
      if (other < 0) {
        surface.triangles.push_back(face);
        if (regions) region_surfaces[mine].triangles.push_back(face);
        continue;
      }
      if (!regions) continue;
      const int theirs = mesh->element_region[other];
      if (mine == theirs) continue;
      region_surfaces[mine].triangles.push_back(face);
      if (mine < theirs) interfaces[{mine, theirs}].triangles.push_back(face);
    }
  }
  CollectFaceSetNodes(&surface);
  mesh->face_sets["surface"] = std::move(surface);
  for (std::size_t r = 0; r < region_surfaces.size(); ++r) {
    if (region_surfaces[r].triangles.empty()) continue;
    CollectFaceSetNodes(&region_surfaces[r]);
    mesh->face_sets[RegionSurfaceSetName(mesh->region_names[r])] = std::move(region_surfaces[r]);
  }
  for (auto& [pair, set] : interfaces) {
    CollectFaceSetNodes(&set);
    mesh->face_sets[InterfaceSetName(mesh->region_names[pair.first],
                                     mesh->region_names[pair.second])] = std::move(set);
  }
}

RelabelStats RelabelInterfaceSlivers(double target_deg, Mesh* mesh) {
  RelabelStats stats;
  // A linear tetrahedral mesh only (region_faces.h).
  if (mesh->element_region.empty() || mesh->shape() != ElementShape::kTet4) return stats;
  const std::vector<int> neighbour = FaceNeighbours(*mesh);
  std::vector<int> count(mesh->region_names.size(), 0);
  for (int r : mesh->element_region) ++count[r];
  // Candidates: (faces shared with the other region, element, that region).
  std::vector<std::array<int, 3>> moves;
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) {
    const Eigen::Matrix<double, 4, 3> x = TetCorners(*mesh, e);
    if (TetDihedralRangeDegrees(x)[0] >= target_deg) continue;
    std::map<int, int> against;  // other region -> faces
    for (int f = 0; f < 4; ++f) {
      const int other = neighbour[4 * e + f];
      if (other >= 0 && mesh->element_region[other] != mesh->element_region[e]) {
        ++against[mesh->element_region[other]];
      }
    }
    int best = -1, faces = 1;
    for (const auto& [region, n] : against) {
      if (n > faces) best = region, faces = n;
    }
    if (best >= 0) moves.push_back({faces, e, best});
  }
  std::sort(moves.begin(), moves.end(),
            [](const auto& a, const auto& b) { return a[0] != b[0] ? a[0] > b[0] : a[1] < b[1]; });
  std::vector<bool> moved(mesh->tets.size(), false);
  for (const auto& [faces, e, to] : moves) {
    // Each decided on the regions as they were: skip one whose neighbour
    // moved meanwhile, and never empty a region.
    bool neighbour_moved = false;
    for (int f = 0; f < 4; ++f) {
      const int other = neighbour[4 * e + f];
      neighbour_moved |= other >= 0 && moved[other];
    }
    int& own = count[mesh->element_region[e]];
    if (neighbour_moved || own <= 1) continue;
    --own;
    ++count[to];
    mesh->element_region[e] = to;
    moved[e] = true;
    ++stats.tetrahedra;
    stats.volume_m3 += Volume(*mesh, e);
  }
  if (stats.tetrahedra > 0) RebuildRegionFaceSets(mesh);
  return stats;
}

void DropUnusedNodes(Mesh* mesh) {
  std::vector<int> node_map(mesh->num_nodes(), -1);
  for (const auto& t : mesh->tets) {
    for (int n : t) node_map[n] = 0;
  }
  int kept = 0;
  for (int& n : node_map) n = n == 0 ? kept++ : -1;
  if (kept == mesh->num_nodes()) return;
  Eigen::MatrixX3d nodes(kept, 3);
  for (int n = 0; n < mesh->num_nodes(); ++n) {
    if (node_map[n] >= 0) nodes.row(node_map[n]) = mesh->nodes.row(n);
  }
  for (auto& t : mesh->tets) {
    for (int& n : t) n = node_map[n];
  }
  for (auto& [name, set] : mesh->face_sets) {
    std::vector<std::array<int, 3>> triangles;
    for (std::array<int, 3> t : set.triangles) {
      for (int& n : t) n = node_map[n];
      if (t[0] >= 0 && t[1] >= 0 && t[2] >= 0) triangles.push_back(t);
    }
    set.triangles = std::move(triangles);
    CollectFaceSetNodes(&set);
  }
  mesh->nodes = std::move(nodes);
}

RemovedTetrahedra RemoveTetrahedra(const std::vector<char>& remove, Mesh* mesh) {
  RemovedTetrahedra removed;
  if (mesh->shape() != ElementShape::kTet4) return removed;
  const bool regions = !mesh->element_region.empty();
  std::vector<char> region_hit(mesh->region_names.size(), 0);
  std::vector<std::array<int, 4>> tets;
  std::vector<int> element_region;
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) {
    if (remove[e] != 0) {
      ++removed.tetrahedra;
      removed.volume_m3 += Volume(*mesh, e);
      if (regions) region_hit[mesh->element_region[e]] = 1;
      continue;
    }
    tets.push_back(mesh->tets[e]);
    if (regions) element_region.push_back(mesh->element_region[e]);
  }
  if (removed.tetrahedra == 0) return removed;
  for (std::size_t r = 0; r < region_hit.size(); ++r) {
    if (region_hit[r] != 0) removed.regions.push_back(mesh->region_names[r]);
  }
  std::sort(removed.regions.begin(), removed.regions.end());
  mesh->tets = std::move(tets);
  mesh->element_region = std::move(element_region);
  DropUnusedNodes(mesh);
  RebuildRegionFaceSets(mesh);
  return removed;
}

RemovedTetrahedra PeelBoundarySlivers(double target_deg, Mesh* mesh) {
  if (mesh->shape() != ElementShape::kTet4) return {};
  const std::vector<int> neighbour = FaceNeighbours(*mesh);
  std::vector<int> count(mesh->region_names.size(), 0);
  for (int r : mesh->element_region) ++count[r];
  std::vector<char> remove(mesh->tets.size(), 0);
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) {
    int outer = 0;
    for (int f = 0; f < 4; ++f) outer += neighbour[4 * e + f] < 0;
    if (outer == 0 || TetDihedralRangeDegrees(TetCorners(*mesh, e))[0] >= target_deg) continue;
    if (!mesh->element_region.empty()) {
      int& own = count[mesh->element_region[e]];
      if (own <= 1) continue;
      --own;
    }
    remove[e] = 1;
  }
  return RemoveTetrahedra(remove, mesh);
}

RemovedTetrahedra DropMeshFragments(double share, Mesh* mesh, int* pieces) {
  if (pieces != nullptr) *pieces = 0;
  if (mesh->shape() != ElementShape::kTet4 || mesh->tets.empty()) return {};
  int num_pieces = 0;
  const std::vector<int> piece = MeshPieces(*mesh, &num_pieces);
  if (num_pieces <= 1) return {};
  std::vector<double> volume(num_pieces, 0);
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e)
    volume[piece[e]] += Volume(*mesh, e);
  const double bound = share * *std::max_element(volume.begin(), volume.end());
  std::vector<char> small(num_pieces, 0);
  for (int p = 0; p < num_pieces; ++p) small[p] = volume[p] < bound;
  // A fragment holding a region's last tetrahedra stays (and is reported
  // as a piece of its own by the callers).
  if (!mesh->element_region.empty()) {
    std::vector<int> left(mesh->region_names.size(), 0);
    for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e)
      left[mesh->element_region[e]] += small[piece[e]] == 0;
    for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) {
      if (left[mesh->element_region[e]] == 0) small[piece[e]] = 0;
    }
  }
  for (int p = 0; p < num_pieces; ++p) {
    if (pieces != nullptr) *pieces += small[p];
  }
  std::vector<char> remove(mesh->tets.size(), 0);
  for (int e = 0; e < static_cast<int>(mesh->tets.size()); ++e) remove[e] = small[piece[e]];
  return RemoveTetrahedra(remove, mesh);
}

}  // namespace pba
