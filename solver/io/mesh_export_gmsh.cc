// Gmsh MSH 4.1 ASCII mesh export (Gmsh reference manual, "MSH file
// format" and "Node ordering").
#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "io/mesh_export_formats.h"

namespace pba::mesh_export {
namespace {

// Position in the mesh's order of each Gmsh node of an element. Gmsh's
// 10-node tetrahedron takes its mid-edge nodes on edges (0,1) (1,2) (2,0)
// (3,0) (3,2) (3,1): C3D10's last two, (1,3) and (2,3), swapped. The 4-node
// tetrahedron and the brick are as in the mesh.
constexpr std::array<int, 10> kGmshTet10FromMesh = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};

// Gmsh reads names between double quotes.
std::string Quoted(const std::string& name) {
  std::string text = OneLine(name);
  std::replace(text.begin(), text.end(), '"', '\'');
  return "\"" + text + "\"";
}

}  // namespace

std::string GmshText(const Mesh& mesh, const MeshExportOptions& options) {
  const ElementShapeInfo& shape = ShapeInfo(mesh.shape());
  const int npe = shape.nodes, elements = mesh.num_elements();
  const double scale = Scale(options);
  const std::vector<std::string> names = RegionNames(mesh);
  const int regions = static_cast<int>(names.size());
  std::vector<std::vector<int>> region_elements(regions);
  for (int e = 0; e < elements; ++e) region_elements[ElementRegion(mesh, e)].push_back(e);

  std::string x = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  // Gmsh skips sections it does not know, so the title and unit go in one.
  x += "$Comments\n";
  if (!options.title.empty()) x += OneLine(options.title) + "\n";
  x += std::string("PBA mesh export: coordinates in ") + Unit(options) +
       "; node and element tags are PBA's indices + 1; physical group and volume entity r + 1 "
       "hold region r\n$EndComments\n";
  x += "$PhysicalNames\n" + std::to_string(regions) + "\n";
  for (int r = 0; r < regions; ++r) {
    x += "3 " + std::to_string(r + 1) + " " + Quoted(names[r]) + "\n";
  }
  x += "$EndPhysicalNames\n";

  // One volume entity per region, with its bounding box and its physical
  // group; no points, curves or surfaces.
  x += "$Entities\n0 0 0 " + std::to_string(regions) + "\n";
  for (int r = 0; r < regions; ++r) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::array<double, 3> lo = {kInf, kInf, kInf}, hi = {-kInf, -kInf, -kInf};
    for (int e : region_elements[r]) {
      for (int node : mesh.ElementNodes(e)) {
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], scale * mesh.nodes(node, k));
          hi[k] = std::max(hi[k], scale * mesh.nodes(node, k));
        }
      }
    }
    if (region_elements[r].empty()) lo = hi = {0, 0, 0};
    x += std::to_string(r + 1);
    for (double v : lo) x += " " + RoundTripNumber(v);
    for (double v : hi) x += " " + RoundTripNumber(v);
    x += " 1 " + std::to_string(r + 1) + " 0\n";
  }
  x += "$EndEntities\n";

  // Every node in one block of volume entity 1: a node shared by regions
  // cannot belong to each of their entities, and Gmsh accepts elements of
  // an entity referring to nodes classified on another.
  const std::string nn = std::to_string(mesh.num_nodes());
  x += "$Nodes\n1 " + nn + " 1 " + nn + "\n3 1 0 " + nn + "\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) x += std::to_string(i + 1) + "\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    x += RoundTripNumber(scale * mesh.nodes(i, 0)) + " " +
         RoundTripNumber(scale * mesh.nodes(i, 1)) + " " +
         RoundTripNumber(scale * mesh.nodes(i, 2)) + "\n";
  }
  x += "$EndNodes\n";

  int blocks = 0;
  for (int r = 0; r < regions; ++r) blocks += region_elements[r].empty() ? 0 : 1;
  x += "$Elements\n" + std::to_string(blocks) + " " + std::to_string(elements) + " 1 " +
       std::to_string(elements) + "\n";
  const std::string type = std::to_string(shape.gmsh_type);
  const bool gmsh_tet10 = shape.shape == ElementShape::kTet10;  // its own node order
  for (int r = 0; r < regions; ++r) {
    if (region_elements[r].empty()) continue;
    x += "3 " + std::to_string(r + 1) + " " + type + " " +
         std::to_string(region_elements[r].size()) + "\n";
    for (int e : region_elements[r]) {
      const NodeList nodes = mesh.ElementNodes(e);
      x += std::to_string(e + 1);
      for (int k = 0; k < npe; ++k) {
        x += " " + std::to_string(nodes[gmsh_tet10 ? kGmshTet10FromMesh[k] : k] + 1);
      }
      x += "\n";
    }
  }
  x += "$EndElements\n";
  return x;
}

}  // namespace pba::mesh_export
