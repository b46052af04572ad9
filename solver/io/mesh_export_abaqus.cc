// Abaqus / CalculiX mesh export: *NODE, *ELEMENT, an *ELSET per region and
// an *NSET per face set.
#include <cctype>
#include <set>
#include <string>
#include <vector>

#include "io/abaqus_format.h"
#include "io/mesh_export_formats.h"

namespace pba::mesh_export {
namespace {

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// A set name Abaqus accepts (letters, digits, underscore; a letter first; at
// most 80 characters), made unique among `used` ignoring case (Abaqus does).
std::string AbaqusName(const std::string& name, const std::string& fallback,
                       std::set<std::string>* used) {
  std::string base;
  for (char c : name) base += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  if (base.empty()) base = fallback;
  if (!std::isalpha(static_cast<unsigned char>(base[0]))) base = "R_" + base;
  constexpr size_t kMaxLength = 80;
  std::string candidate = base.substr(0, kMaxLength);
  for (int n = 2; used->count(Upper(candidate)) > 0; ++n) {
    const std::string suffix = "_" + std::to_string(n);
    candidate = base.substr(0, kMaxLength - suffix.size()) + suffix;
  }
  used->insert(Upper(candidate));
  return candidate;
}

// Abaqus reads at most 16 entries per data line; ids are indices + 1.
std::string IdLines(const std::vector<int>& indices) {
  std::string text;
  for (size_t i = 0; i < indices.size(); ++i) {
    text +=
        std::to_string(indices[i] + 1) + ((i % 16 == 15 || i + 1 == indices.size()) ? "\n" : ", ");
  }
  return text;
}

}  // namespace

std::string AbaqusText(const Mesh& mesh, const MeshExportOptions& options) {
  const int elements = mesh.num_elements();
  const double scale = Scale(options);
  const std::vector<std::string> names = RegionNames(mesh);
  std::set<std::string> used = {"NALL", "EALL"};
  std::vector<std::string> elsets;
  for (size_t r = 0; r < names.size(); ++r) {
    elsets.push_back(AbaqusName(names[r], "REGION_" + std::to_string(r), &used));
  }

  std::string x = "*HEADING\n" + (options.title.empty() ? "PBA mesh" : OneLine(options.title)) +
                  "\n** PBA mesh export: coordinates in " + Unit(options) +
                  "; node and element numbers are PBA's indices + 1.\n"
                  "** Regions (index, element set, name):\n";
  for (size_t r = 0; r < names.size(); ++r) {
    x += "**   " + std::to_string(r) + ", " + elsets[r] + ", " + OneLine(names[r]) + "\n";
  }
  // Coordinates in CalculiX's 20-character fields (AbaqusNumber): the
  // 17 digits the other formats write would stop it reading *NODE.
  x += "*NODE, NSET=NALL\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    x += std::to_string(i + 1) + ", " + AbaqusNumber(scale * mesh.nodes(i, 0)) + ", " +
         AbaqusNumber(scale * mesh.nodes(i, 1)) + ", " + AbaqusNumber(scale * mesh.nodes(i, 2)) +
         "\n";
  }
  // C3D4, C3D10 and C3D8 take the mesh's own node orders (mesh.h).
  x += std::string("*ELEMENT, TYPE=") + ShapeInfo(mesh.shape()).abaqus_type + ", ELSET=EALL\n";
  std::vector<std::vector<int>> region_elements(names.size());
  for (int e = 0; e < elements; ++e) {
    x += std::to_string(e + 1);
    for (int node : mesh.ElementNodes(e)) x += ", " + std::to_string(node + 1);
    x += "\n";
    region_elements[ElementRegion(mesh, e)].push_back(e);
  }
  for (size_t r = 0; r < names.size(); ++r) {
    if (region_elements[r].empty()) continue;  // Abaqus rejects an empty set
    x += "*ELSET, ELSET=" + elsets[r] + "\n" + IdLines(region_elements[r]);
  }
  if (!mesh.face_sets.empty()) x += "** Face sets (node set, name):\n";
  std::vector<std::string> nsets;
  for (const auto& [name, set] : mesh.face_sets) {
    nsets.push_back(AbaqusName(name, "FACES", &used));
    x += "**   " + nsets.back() + ", " + OneLine(name) + "\n";
  }
  size_t k = 0;
  for (const auto& [name, set] : mesh.face_sets) {
    const std::string& nset = nsets[k++];
    if (set.nodes.empty()) continue;
    x += "*NSET, NSET=" + nset + "\n" + IdLines(set.nodes);
  }
  return x;
}

}  // namespace pba::mesh_export
