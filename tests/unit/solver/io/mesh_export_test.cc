// ExportMesh: each format is written, read back by a small reader here, and
// compared with the mesh: coordinates in mm, connectivity mapped back to the
// mesh's order, regions and their names. For the 10-node tetrahedron each
// mid-edge node is also checked to lie at the midpoint of the two corners
// its position in that format names, which is what pins the node orders.
#include "io/mesh_export.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <stdlib.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "io/abaqus_format.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {
namespace fs = std::filesystem;

enum class Kind { kTet4, kTet10, kHex8 };

const char* kRegionNames[2] = {"left hemisphere", "right/hemisphere"};

// A 4 x 4 x 8 mm box cut at x = 0 into two regions by element centroid.
Mesh TwoRegionBox(Kind kind) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {4, 4, 8};
  MeshSpec options;
  options.element_size_mm = 2;
  if (kind == Kind::kHex8) options.element = ElementType::kHex8;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  if (kind == Kind::kTet10) mesh = MakeQuadratic(mesh);
  const double x_mid = 0.5 * (mesh.nodes.col(0).minCoeff() + mesh.nodes.col(0).maxCoeff());
  mesh.region_names = {kRegionNames[0], kRegionNames[1]};
  for (int e = 0; e < mesh.num_elements(); ++e) {
    double x = 0;
    if (kind == Kind::kHex8) {
      for (int node : mesh.hexes[e]) x += mesh.nodes(node, 0) / 8;
    } else {
      for (int node : mesh.tets[e]) x += mesh.nodes(node, 0) / 4;
    }
    mesh.element_region.push_back(x < x_mid ? 0 : 1);
  }
  return mesh;
}

// The mesh's nodes of element e in its own order (C3D10 for 10 nodes).
std::vector<int> MeshElement(const Mesh& mesh, int e) {
  if (mesh.hexahedral()) return {mesh.hexes[e].begin(), mesh.hexes[e].end()};
  if (mesh.quadratic()) {
    const auto nodes = Tet10NodeIndices(mesh, e);
    return {nodes.begin(), nodes.end()};
  }
  return {mesh.tets[e].begin(), mesh.tets[e].end()};
}

// Mid-edge node k (4..9) of a 10-node tet lies on edge kEdges[k - 4].
using EdgeTable = std::array<std::array<int, 2>, 6>;
// VTK_QUADRATIC_TETRA, XDMF Tetrahedron_10 and Abaqus C3D10.
constexpr EdgeTable kVtkEdges = {{{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}}};
// Gmsh 11 (Gmsh reference manual, node ordering of the 10-node tetrahedron).
constexpr EdgeTable kGmshEdges = {{{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}};

// What a reader recovers from a file: nodes in the file's unit, elements
// (0-based node indices, the file's node order), the mesh element each one
// is, its region index, and the region names.
struct ReadBack {
  std::vector<std::array<double, 3>> nodes;
  std::vector<std::vector<int>> elements;
  std::vector<int> element_ids;
  std::vector<int> regions;
  std::map<int, std::string> region_names;
};

// Compares `read` with `mesh`: coordinates in mm, connectivity after
// `file_to_mesh` (file position -> mesh position), the TET10 midpoints by
// `edges`, regions and names.
void ExpectMatches(const Mesh& mesh, const ReadBack& read, const std::vector<int>& file_to_mesh,
                   const EdgeTable& edges) {
  ASSERT_EQ(read.nodes.size(), static_cast<size_t>(mesh.num_nodes()));
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(read.nodes[i][k], 1000 * mesh.nodes(i, k), 1e-9);
  }
  ASSERT_EQ(read.elements.size(), static_cast<size_t>(mesh.num_elements()));
  std::vector<int> seen(mesh.num_elements(), 0);
  for (size_t j = 0; j < read.elements.size(); ++j) {
    const int e = read.element_ids[j];
    ASSERT_TRUE(e >= 0 && e < mesh.num_elements()) << e;
    ++seen[e];
    const std::vector<int>& file = read.elements[j];
    const std::vector<int> expected = MeshElement(mesh, e);
    ASSERT_EQ(file.size(), expected.size());
    std::vector<int> remapped(file.size());
    for (size_t p = 0; p < file.size(); ++p) remapped[file_to_mesh[p]] = file[p];
    EXPECT_EQ(remapped, expected) << "element " << e;
    if (file.size() == 10) {
      for (int k = 4; k < 10; ++k) {
        const auto& a = read.nodes[file[edges[k - 4][0]]];
        const auto& b = read.nodes[file[edges[k - 4][1]]];
        const auto& m = read.nodes[file[k]];
        for (int c = 0; c < 3; ++c) {
          ASSERT_NEAR(m[c], 0.5 * (a[c] + b[c]), 1e-9) << "element " << e << " node " << k;
        }
      }
    }
    EXPECT_EQ(read.regions[j], mesh.element_region[e]) << "element " << e;
  }
  for (int e = 0; e < mesh.num_elements(); ++e) EXPECT_EQ(seen[e], 1) << e;
  ASSERT_EQ(read.region_names.size(), 2u);
  EXPECT_EQ(read.region_names.at(0), kRegionNames[0]);
  EXPECT_EQ(read.region_names.at(1), kRegionNames[1]);
}

std::vector<int> Identity(int n) {
  std::vector<int> p(n);
  for (int i = 0; i < n; ++i) p[i] = i;
  return p;
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The numbers of VTU DataArray `name`.
std::vector<double> VtuArray(const std::string& text, const std::string& name) {
  const size_t at = text.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const size_t begin = text.find('>', at) + 1;
  std::istringstream in(text.substr(begin, text.find("</DataArray>", begin) - begin));
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

ReadBack ReadVtu(const std::string& text, int* cell_type) {
  ReadBack read;
  const std::vector<double> points = VtuArray(text, "Points");
  for (size_t i = 0; i + 2 < points.size(); i += 3) {
    read.nodes.push_back({points[i], points[i + 1], points[i + 2]});
  }
  const std::vector<double> connectivity = VtuArray(text, "connectivity");
  const std::vector<double> offsets = VtuArray(text, "offsets");
  const std::vector<double> types = VtuArray(text, "types");
  const std::vector<double> regions = VtuArray(text, "region");
  size_t start = 0;
  for (size_t e = 0; e < offsets.size(); ++e) {
    const size_t end = static_cast<size_t>(offsets[e]);
    read.elements.emplace_back(connectivity.begin() + start, connectivity.begin() + end);
    read.element_ids.push_back(static_cast<int>(e));
    read.regions.push_back(static_cast<int>(regions.at(e)));
    if (e == 0 || types[e] != types[0]) *cell_type = static_cast<int>(types[e]);
    start = end;
  }
  for (size_t at = text.find("<!-- region "); at != std::string::npos;
       at = text.find("<!-- region ", at + 1)) {
    const size_t colon = text.find(": ", at), end = text.find(" -->", at);
    read.region_names[std::stoi(text.substr(at + 12, colon - at - 12))] =
        text.substr(colon + 2, end - colon - 2);
  }
  return read;
}

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "pba-mesh-export.XXXXXX").string();
    if (mkdtemp(pattern.data()) != nullptr) path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  // File names in the directory, hidden temporary files included.
  std::vector<std::string> Listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(path_)) {
      names.push_back(entry.path().filename().string());
    }
    return names;
  }

 private:
  fs::path path_;
};

class MeshExportTest : public ::testing::TestWithParam<Kind> {
 protected:
  Mesh mesh_ = TwoRegionBox(GetParam());
  TempDir dir_;
  MeshExportOptions options_{true, "synthetic atlas - not for clinical use"};
  int npe_ = GetParam() == Kind::kTet10 ? 10 : GetParam() == Kind::kHex8 ? 8 : 4;
};

TEST_P(MeshExportTest, Vtu) {
  const fs::path file = dir_.path() / "atlas.vtu";
  ASSERT_TRUE(ExportMesh(mesh_, file, options_).ok());
  const std::string text = ReadText(file);
  EXPECT_NE(text.find("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                      "byte_order=\"LittleEndian\" header_type=\"UInt64\">"),
            std::string::npos);
  EXPECT_NE(text.find("<!-- synthetic atlas - not for clinical use -->"), std::string::npos);
  EXPECT_NE(text.find("</VTKFile>"), std::string::npos);
  int cell_type = -1;
  const ReadBack read = ReadVtu(text, &cell_type);
  EXPECT_EQ(cell_type, npe_ == 10 ? 24 : npe_ == 8 ? 12 : 10);
  ExpectMatches(mesh_, read, Identity(npe_), kVtkEdges);
  EXPECT_EQ(dir_.Listing(), std::vector<std::string>{"atlas.vtu"});  // no temporary left
}

// An HDF5 dataset as doubles (HDF5 converts int64 on reading), and its
// dimensions.
std::vector<double> ReadDataset(hid_t file, const char* path, std::vector<hsize_t>* dims) {
  const hid_t dataset = H5Dopen2(file, path, H5P_DEFAULT);
  if (dataset < 0) return {};
  const hid_t space = H5Dget_space(dataset);
  dims->assign(H5Sget_simple_extent_ndims(space), 0);
  H5Sget_simple_extent_dims(space, dims->data(), nullptr);
  hsize_t count = 1;
  for (hsize_t d : *dims) count *= d;
  std::vector<double> values(count);
  H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(dataset);
  return values;
}

TEST_P(MeshExportTest, XdmfWithHdf5) {
  const fs::path file = dir_.path() / "atlas.xdmf";
  ASSERT_TRUE(ExportMesh(mesh_, file, options_).ok());
  const std::string text = ReadText(file);
  const char* topology = npe_ == 10  ? "TopologyType=\"Tetrahedron_10\""
                         : npe_ == 8 ? "TopologyType=\"Hexahedron\""
                                     : "TopologyType=\"Tetrahedron\"";
  EXPECT_NE(text.find(topology), std::string::npos);
  for (const char* path :
       {"atlas.h5:/mesh/nodes<", "atlas.h5:/mesh/topology<", "atlas.h5:/mesh/region<",
        "<Xdmf Version=\"3.0\">", "synthetic atlas - not for clinical use", "Center=\"Cell\""}) {
    EXPECT_NE(text.find(path), std::string::npos) << path;
  }
  ReadBack read;
  for (int r = 0; r < 2; ++r) {
    // meshio's field-data map: <map key="NAME" dim="3">r</map>.
    const std::string value = "\" dim=\"3\">" + std::to_string(r) + "</map>";
    const size_t end = text.find(value);
    ASSERT_NE(end, std::string::npos);
    const size_t begin = text.rfind("key=\"", end) + 5;
    read.region_names[r] = text.substr(begin, end - begin);
  }
  const hid_t h5 = H5Fopen((dir_.path() / "atlas.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(h5, 0);
  std::vector<hsize_t> dims;
  const std::vector<double> nodes = ReadDataset(h5, "/mesh/nodes", &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{static_cast<hsize_t>(mesh_.num_nodes()), 3}));
  for (size_t i = 0; i + 2 < nodes.size(); i += 3) {
    read.nodes.push_back({nodes[i], nodes[i + 1], nodes[i + 2]});
  }
  const std::vector<double> topology_data = ReadDataset(h5, "/mesh/topology", &dims);
  EXPECT_EQ(dims, (std::vector<hsize_t>{static_cast<hsize_t>(mesh_.num_elements()),
                                        static_cast<hsize_t>(npe_)}));
  const std::vector<double> regions = ReadDataset(h5, "/mesh/region", &dims);
  H5Fclose(h5);
  for (int e = 0; e < mesh_.num_elements(); ++e) {
    read.elements.emplace_back(topology_data.begin() + e * npe_,
                               topology_data.begin() + (e + 1) * npe_);
    read.element_ids.push_back(e);
    read.regions.push_back(static_cast<int>(regions.at(e)));
  }
  ExpectMatches(mesh_, read, Identity(npe_), kVtkEdges);
  EXPECT_EQ(dir_.Listing().size(), 2u);  // the .xdmf and the .h5, no temporaries
}

// Lines of `text` between "$<section>" and "$End<section>".
std::vector<std::string> GmshSection(const std::string& text, const std::string& section) {
  std::istringstream in(text);
  std::vector<std::string> lines;
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    if (line == "$End" + section) break;
    if (inside) lines.push_back(line);
    if (line == "$" + section) inside = true;
  }
  return lines;
}

TEST_P(MeshExportTest, Gmsh) {
  const fs::path file = dir_.path() / "atlas.msh";
  ASSERT_TRUE(ExportMesh(mesh_, file, options_).ok());
  const std::string text = ReadText(file);
  EXPECT_EQ(GmshSection(text, "MeshFormat"), std::vector<std::string>{"4.1 0 8"});
  EXPECT_EQ(GmshSection(text, "Comments").at(0), options_.title);
  ReadBack read;
  const std::vector<std::string> names = GmshSection(text, "PhysicalNames");
  ASSERT_EQ(names.at(0), "2");
  for (size_t i = 1; i < names.size(); ++i) {
    std::istringstream line(names[i]);
    int dim, tag;
    line >> dim >> tag;
    EXPECT_EQ(dim, 3);
    std::string name;
    std::getline(line >> std::ws, name);
    read.region_names[tag - 1] = name.substr(1, name.size() - 2);  // unquoted
  }
  // Volume entity tag -> physical tag.
  std::map<int, int> physical;
  const std::vector<std::string> entities = GmshSection(text, "Entities");
  ASSERT_EQ(entities.at(0), "0 0 0 2");
  for (size_t i = 1; i < entities.size(); ++i) {
    std::istringstream line(entities[i]);
    int tag, count, group;
    double box[6];
    line >> tag;
    for (double& b : box) line >> b;
    line >> count >> group;
    ASSERT_EQ(count, 1);
    physical[tag] = group;
  }
  std::istringstream nodes(text.substr(text.find("$Nodes\n") + 7));
  size_t blocks, count, min_tag, max_tag;
  nodes >> blocks >> count >> min_tag >> max_tag;
  ASSERT_EQ(count, static_cast<size_t>(mesh_.num_nodes()));
  std::map<int, std::array<double, 3>> by_tag;
  for (size_t b = 0; b < blocks; ++b) {
    int dim, entity, parametric;
    size_t n;
    nodes >> dim >> entity >> parametric >> n;
    std::vector<int> tags(n);
    for (int& t : tags) nodes >> t;
    for (int t : tags) nodes >> by_tag[t][0] >> by_tag[t][1] >> by_tag[t][2];
  }
  for (const auto& [tag, x] : by_tag) {
    ASSERT_EQ(tag, static_cast<int>(read.nodes.size()) + 1);  // tags 1..n, node = tag - 1
    read.nodes.push_back(x);
  }
  std::istringstream elements(text.substr(text.find("$Elements\n") + 10));
  elements >> blocks >> count >> min_tag >> max_tag;
  ASSERT_EQ(count, static_cast<size_t>(mesh_.num_elements()));
  for (size_t b = 0; b < blocks; ++b) {
    int dim, entity, type;
    size_t n;
    elements >> dim >> entity >> type >> n;
    EXPECT_EQ(type, npe_ == 10 ? 11 : npe_ == 8 ? 5 : 4);
    for (size_t j = 0; j < n; ++j) {
      int tag;
      elements >> tag;
      std::vector<int> element(npe_);
      for (int& node : element) {
        elements >> node;
        --node;
      }
      read.elements.push_back(element);
      read.element_ids.push_back(tag - 1);
      read.regions.push_back(physical.at(entity) - 1);
    }
  }
  // Gmsh positions 8 and 9 hold the mesh's (C3D10) mid-edge nodes 9 and 8.
  std::vector<int> file_to_mesh = Identity(npe_);
  if (npe_ == 10) std::swap(file_to_mesh[8], file_to_mesh[9]);
  ExpectMatches(mesh_, read, file_to_mesh, kGmshEdges);
}

TEST_P(MeshExportTest, Abaqus) {
  const fs::path file = dir_.path() / "atlas.inp";
  ASSERT_TRUE(ExportMesh(mesh_, file, options_).ok());
  std::istringstream in(ReadText(file));
  ReadBack read;
  std::string keyword, line, heading;
  std::map<std::string, int> elset_region;  // from the mapping comment
  std::map<std::string, std::vector<int>> sets;
  std::vector<std::vector<int>> elements;
  while (std::getline(in, line)) {
    if (line.rfind("**   ", 0) == 0 && keyword != "") {
      // "**   index, SET, full name"
      std::istringstream fields(line.substr(5));
      std::string index, set, name;
      std::getline(fields, index, ',');
      std::getline(fields >> std::ws, set, ',');
      std::getline(fields >> std::ws, name);
      if (std::isdigit(static_cast<unsigned char>(index[0]))) {
        elset_region[set] = std::stoi(index);
        read.region_names[std::stoi(index)] = name;
      }
      continue;
    }
    if (line.rfind("**", 0) == 0) continue;
    if (line[0] == '*') {
      keyword = line;
      continue;
    }
    if (keyword == "*HEADING") {
      if (heading.empty()) heading = line;
      continue;
    }
    std::vector<double> v;
    std::string item;
    for (std::istringstream fields(line); std::getline(fields, item, ',');) {
      v.push_back(std::stod(item));
    }
    if (keyword == "*NODE, NSET=NALL") {
      ASSERT_EQ(static_cast<size_t>(v[0]), read.nodes.size() + 1);
      read.nodes.push_back({v[1], v[2], v[3]});
    } else if (keyword.rfind("*ELEMENT, TYPE=", 0) == 0) {
      EXPECT_EQ(keyword, std::string("*ELEMENT, TYPE=") +
                             (npe_ == 10  ? "C3D10"
                              : npe_ == 8 ? "C3D8"
                                          : "C3D4") +
                             ", ELSET=EALL");
      std::vector<int> element;
      for (size_t k = 1; k < v.size(); ++k) element.push_back(static_cast<int>(v[k]) - 1);
      read.elements.push_back(element);
      read.element_ids.push_back(static_cast<int>(v[0]) - 1);
    } else if (keyword.rfind("*ELSET, ELSET=", 0) == 0 || keyword.rfind("*NSET, NSET=", 0) == 0) {
      for (double id : v) sets[keyword.substr(keyword.find('=') + 1)].push_back(int(id) - 1);
    }
  }
  EXPECT_EQ(heading, options_.title);
  // Names sanitised: letters, digits, underscore.
  EXPECT_EQ(elset_region.at("left_hemisphere"), 0);
  EXPECT_EQ(elset_region.at("right_hemisphere"), 1);
  read.regions.assign(read.elements.size(), -1);
  for (const auto& [set, region] : elset_region) {
    for (int e : sets.at(set)) read.regions.at(e) = region;  // ids are in element order
  }
  ExpectMatches(mesh_, read, Identity(npe_), kVtkEdges);
  // Face sets as node sets with the same nodes.
  for (const auto& [name, set] : mesh_.face_sets) {
    ASSERT_EQ(sets.count(name), 1u) << name;
    EXPECT_EQ(sets.at(name), set.nodes) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(Elements, MeshExportTest,
                         ::testing::Values(Kind::kTet4, Kind::kTet10, Kind::kHex8),
                         [](const ::testing::TestParamInfo<Kind>& info) {
                           return info.param == Kind::kTet4    ? std::string("Tet4")
                                  : info.param == Kind::kTet10 ? std::string("Tet10")
                                                               : std::string("Hex8");
                         });

TEST(MeshExportErrorTest, UnknownExtensionIsNamed) {
  const Status status = ExportMesh(TwoRegionBox(Kind::kTet4), "atlas.stl");
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "file");
  EXPECT_NE(status.message().find(".stl"), std::string::npos) << status.message();
}

TEST(MeshExportErrorTest, MissingDirectoryFailsAndLeavesNothing) {
  TempDir dir;
  const Mesh mesh = TwoRegionBox(Kind::kTet4);
  for (const char* name : {"atlas.vtu", "atlas.xdmf", "atlas.msh", "atlas.inp"}) {
    const Status status = ExportMesh(mesh, dir.path() / "missing" / name);
    EXPECT_EQ(status.code(), Status::Code::kIo) << name;
  }
  EXPECT_TRUE(dir.Listing().empty());
}

TEST(MeshExportErrorTest, BadMeshNamesTheField) {
  TempDir dir;
  Mesh mesh = TwoRegionBox(Kind::kTet4);
  mesh.element_region.pop_back();
  Status status = ExportMesh(mesh, dir.path() / "a.vtu");
  EXPECT_EQ(status.field(), "mesh.element_region");
  mesh.element_region.push_back(2);  // no region 2
  EXPECT_EQ(ExportMesh(mesh, dir.path() / "a.vtu").field(), "mesh.element_region");
  EXPECT_EQ(ExportMesh(Mesh{}, dir.path() / "a.msh").field(), "mesh.nodes");
  Mesh no_elements;
  no_elements.nodes.setZero(4, 3);
  EXPECT_EQ(ExportMesh(no_elements, dir.path() / "a.inp").field(), "mesh.tets");
  EXPECT_TRUE(dir.Listing().empty());
}

TEST(MeshExportOptionsTest, MetresAndOneRegionBody) {
  TempDir dir;
  Mesh mesh = TwoRegionBox(Kind::kTet4);
  mesh.region_names.clear();
  mesh.element_region.clear();
  ASSERT_TRUE(ExportMesh(mesh, dir.path() / "a.vtu", {false, ""}).ok());
  int cell_type;
  const ReadBack read = ReadVtu(ReadText(dir.path() / "a.vtu"), &cell_type);
  ASSERT_EQ(read.nodes.size(), static_cast<size_t>(mesh.num_nodes()));
  for (int i = 0; i < mesh.num_nodes(); ++i) EXPECT_EQ(read.nodes[i][2], mesh.nodes(i, 2));
  for (int region : read.regions) EXPECT_EQ(region, 0);
  EXPECT_EQ(read.region_names.at(0), "body");
}

TEST(MeshExportOptionsTest, AbaqusSetNamesFollowTheRules) {
  TempDir dir;
  Mesh mesh = TwoRegionBox(Kind::kTet4);
  // A digit first, over 80 characters, and a clash ignoring case.
  mesh.region_names = {"3rd ventricle " + std::string(100, 'x'), "EALL"};
  ASSERT_TRUE(ExportMesh(mesh, dir.path() / "a.inp").ok());
  const std::string text = ReadText(dir.path() / "a.inp");
  const std::string first = "*ELSET, ELSET=R_3rd_ventricle_";
  const size_t at = text.find(first);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(text.find('\n', at) - (at + 14), 80u);  // the name alone
  EXPECT_NE(text.find("*ELSET, ELSET=EALL_2\n"), std::string::npos);
}

// CalculiX reads each number of a data line in at most 20 characters; a
// longer coordinate made it refuse atlas.inp (exit 201 on *NODE).
TEST(AbaqusNumberTest, FitsTwentyCharactersAndKeepsWhatFits) {
  const double extremes[] = {1e-300,
                             -1.2345678901234567e+200,
                             -1.2345678901234567e-200,
                             -2.2250738585072014e-308,
                             -4.9406564584124654e-324,
                             -1.7976931348623157e+308,
                             -0.00012345678901234567,
                             -123456789012345678.0,
                             -0.1 - 0.2,
                             1.0 / 3.0};
  for (double value : extremes) {
    const std::string text = AbaqusNumber(value);
    EXPECT_LE(text.size(), 20u) << text;
    // 13 significant digits always fit: sign, d.dddddddddddd, e-308.
    // strtod: std::stod refuses the subnormal ones.
    EXPECT_NEAR(std::strtod(text.c_str(), nullptr), value, 1e-12 * std::abs(value)) << text;
  }
  // The shortest form that reads back, when one fits.
  EXPECT_EQ(AbaqusNumber(0.45), "0.45");
  EXPECT_EQ(AbaqusNumber(0.4999999), "0.4999999");
  EXPECT_EQ(AbaqusNumber(3000), "3000");
  EXPECT_EQ(std::stod(AbaqusNumber(1.0 / 3.0)), 1.0 / 3.0);
  EXPECT_EQ(std::stod(AbaqusNumber(-0.1 - 0.2)), -0.1 - 0.2);
}

TEST(MeshExportOptionsTest, AbaqusFieldsFitTwentyCharactersAtExtremeCoordinates) {
  TempDir dir;
  Mesh mesh = TwoRegionBox(Kind::kTet10);
  const double extremes[] = {1e-300, -1.2345678901234567e+200, -1.2345678901234567e-200,
                             -0.12345678901234567, 1.0 / 3.0};
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    for (int k = 0; k < 3; ++k) mesh.nodes(i, k) = extremes[(3 * i + k) % 5] * (1 + i);
  }
  ASSERT_TRUE(ExportMesh(mesh, dir.path() / "a.inp").ok());
  std::istringstream in(ReadText(dir.path() / "a.inp"));
  std::string line;
  int node_lines = 0;
  bool nodes = false;
  while (std::getline(in, line)) {
    if (line.rfind("*", 0) == 0) {
      nodes = line == "*NODE, NSET=NALL";
      continue;
    }
    std::string item;
    std::vector<double> v;
    for (std::istringstream fields(line); std::getline(fields, item, ',');) {
      const std::string field = item.substr(item.find_first_not_of(' '));
      EXPECT_LE(field.size(), 20u) << line;
      if (nodes) v.push_back(std::strtod(field.c_str(), nullptr));
    }
    if (!nodes) continue;
    const int i = static_cast<int>(v[0]) - 1;
    ASSERT_EQ(i, node_lines++);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(v[1 + k], 1000 * mesh.nodes(i, k), 1e-12 * std::abs(1000 * mesh.nodes(i, k)));
    }
  }
  EXPECT_EQ(node_lines, mesh.num_nodes());
}

}  // namespace
}  // namespace pba
