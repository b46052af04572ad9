// The regions' surfaces and their glTF binary (results/surface_gltf.h):
// each region's surface is closed, faces out of it and encloses its
// volume; an interface is in both regions, facing opposite ways; the file
// has glTF 2.0's binary layout with the positions and displacements read
// back as written.
#include "results/surface_gltf.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstring>
#include <map>
#include <regex>

namespace pba {
namespace {

// A row of `cubes` unit cubes along x [mm], each split into six Kuhn
// tetrahedra (positively oriented); cube i in region i % regions.
struct Block {
  std::vector<double> nodes;
  std::vector<int64_t> tets, region;
};

Block KuhnRow(int cubes, int regions) {
  Block b;
  const auto node = [&](int x, int y, int z) { return int64_t{(x * 2 + y) * 2 + z}; };
  for (int x = 0; x <= cubes; ++x)
    for (int y = 0; y <= 1; ++y)
      for (int z = 0; z <= 1; ++z) b.nodes.insert(b.nodes.end(), {double(x), double(y), double(z)});
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int c = 0; c < cubes; ++c) {
    for (const auto& p : perms) {
      int at[3] = {c, 0, 0};
      std::array<int64_t, 4> t;
      t[0] = node(at[0], at[1], at[2]);
      for (int k = 0; k < 3; ++k) {
        ++at[p[k]];
        t[k + 1] = node(at[0], at[1], at[2]);
      }
      const auto x = [&](int64_t n) {
        return Eigen::Vector3d(b.nodes[3 * n], b.nodes[3 * n + 1], b.nodes[3 * n + 2]);
      };
      Eigen::Matrix3d m;
      m << x(t[1]) - x(t[0]), x(t[2]) - x(t[0]), x(t[3]) - x(t[0]);
      if (m.determinant() < 0) std::swap(t[2], t[3]);
      b.tets.insert(b.tets.end(), t.begin(), t.end());
      b.region.push_back(c % regions);
    }
  }
  return b;
}

Eigen::Vector3d At(const std::vector<double>& nodes, int64_t n) {
  return {nodes[3 * n], nodes[3 * n + 1], nodes[3 * n + 2]};
}

// The volume the surface encloses (divergence theorem; positive when its
// triangles face out).
double Enclosed(const RegionSurface& s, const std::vector<double>& nodes) {
  double volume = 0;
  for (std::size_t t = 0; t < s.triangles.size(); t += 3) {
    const Eigen::Vector3d a = At(nodes, s.nodes[s.triangles[t]]);
    const Eigen::Vector3d b = At(nodes, s.nodes[s.triangles[t + 1]]);
    const Eigen::Vector3d c = At(nodes, s.nodes[s.triangles[t + 2]]);
    volume += a.dot(b.cross(c)) / 6;
  }
  return volume;
}

// Every edge of a closed, consistently oriented surface is used once in
// each direction.
bool ClosedAndOriented(const RegionSurface& s) {
  std::map<std::pair<int64_t, int64_t>, int> directed;
  for (std::size_t t = 0; t < s.triangles.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      ++directed[{s.nodes[s.triangles[t + k]], s.nodes[s.triangles[t + (k + 1) % 3]]}];
    }
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1 || directed.count({edge.second, edge.first}) != 1) return false;
  }
  return true;
}

TEST(SurfaceGltfTest, EachRegionsSurfaceIsClosedFacesOutAndHoldsItsVolume) {
  const Block b = KuhnRow(3, 2);  // regions A B A: A in two pieces
  const auto surfaces = ExtractRegionSurfaces(b.tets, 4, b.region, {"A", "B"});
  ASSERT_EQ(surfaces.size(), 2u);
  EXPECT_EQ(surfaces[0].name, "A");
  EXPECT_EQ(surfaces[0].elements, 12);
  EXPECT_EQ(surfaces[1].elements, 6);
  for (const RegionSurface& s : surfaces) {
    EXPECT_TRUE(ClosedAndOriented(s)) << s.name;
    // Each cube's six faces, two triangles each.
    EXPECT_EQ(s.triangles.size() / 3, static_cast<std::size_t>(12 * s.elements / 6)) << s.name;
    EXPECT_NEAR(Enclosed(s, b.nodes), s.elements / 6.0, 1e-12) << s.name;
  }
  // The interface x = 1 is in both, facing opposite ways.
  const auto on_plane = [&](const RegionSurface& s, double x) {
    std::vector<std::array<int64_t, 3>> found;
    for (std::size_t t = 0; t < s.triangles.size(); t += 3) {
      std::array<int64_t, 3> tri;
      bool all = true;
      for (int k = 0; k < 3; ++k) {
        tri[k] = s.nodes[s.triangles[t + k]];
        all = all && b.nodes[3 * tri[k]] == x;
      }
      if (all) found.push_back(tri);
    }
    return found;
  };
  const auto a_side = on_plane(surfaces[0], 1), b_side = on_plane(surfaces[1], 1);
  ASSERT_EQ(a_side.size(), 2u);
  ASSERT_EQ(b_side.size(), 2u);
  for (const auto& t : a_side) {
    const std::array<int64_t, 3> reversed = {t[0], t[2], t[1]};
    bool matched = false;
    for (const auto& u : b_side) {
      for (int r = 0; r < 3; ++r) {
        matched = matched || (u[r] == reversed[0] && u[(r + 1) % 3] == reversed[1] &&
                              u[(r + 2) % 3] == reversed[2]);
      }
    }
    EXPECT_TRUE(matched);
  }
}

TEST(SurfaceGltfTest, OneBodyQuadraticTetrahedraAndHexahedra) {
  const Block b = KuhnRow(2, 1);
  const auto body = ExtractRegionSurfaces(b.tets, 4, {}, {});
  ASSERT_EQ(body.size(), 1u);
  EXPECT_EQ(body[0].name, "body");
  EXPECT_EQ(body[0].triangles.size() / 3, 20u);  // a 2 x 1 x 1 box: 10 squares
  EXPECT_NEAR(Enclosed(body[0], b.nodes), 2.0, 1e-12);
  // TET10: the corners' triangles (mid-edge nodes past the corners).
  std::vector<int64_t> quadratic;
  for (std::size_t e = 0; e < b.tets.size() / 4; ++e) {
    quadratic.insert(quadratic.end(), b.tets.begin() + 4 * e, b.tets.begin() + 4 * e + 4);
    for (int k = 0; k < 6; ++k) quadratic.push_back(1000 + static_cast<int64_t>(6 * e + k));
  }
  const auto corner = ExtractRegionSurfaces(quadratic, 10, {}, {});
  EXPECT_EQ(corner[0].nodes, body[0].nodes);
  EXPECT_EQ(corner[0].triangles, body[0].triangles);
  // One unit hexahedron in VTK order: 12 triangles enclosing 1.
  const std::vector<double> cube = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                    0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  const auto hex = ExtractRegionSurfaces({0, 1, 2, 3, 4, 5, 6, 7}, 8, {}, {});
  EXPECT_EQ(hex[0].triangles.size(), 36u);
  EXPECT_TRUE(ClosedAndOriented(hex[0]));
  EXPECT_NEAR(Enclosed(hex[0], cube), 1.0, 1e-12);
  // Regions that do not match the elements: one body, not a wrong split.
  EXPECT_EQ(ExtractRegionSurfaces(b.tets, 4, {0, 1}, {"A", "B"}).size(), 1u);
}

uint32_t Word(const std::string& bytes, std::size_t at) {
  uint32_t w = 0;
  std::memcpy(&w, bytes.data() + at, 4);
  return w;
}

TEST(SurfaceGltfTest, TheGlbHasGltfsLayoutAndTheValuesWritten) {
  const Block b = KuhnRow(2, 2);
  std::vector<double> displacement(b.nodes.size());
  for (std::size_t i = 0; i < displacement.size(); ++i) displacement[i] = 0.5 * b.nodes[i];
  const auto surfaces = ExtractRegionSurfaces(b.tets, 4, b.region, {"Left \"x\"", "Right"});
  const std::string glb = SurfacesGlb(surfaces, b.nodes, displacement);
  ASSERT_GE(glb.size(), 28u);
  EXPECT_EQ(Word(glb, 0), 0x46546C67u);  // "glTF"
  EXPECT_EQ(Word(glb, 4), 2u);
  EXPECT_EQ(Word(glb, 8), glb.size());
  const uint32_t json_length = Word(glb, 12);
  EXPECT_EQ(Word(glb, 16), 0x4E4F534Au);  // JSON
  EXPECT_EQ(json_length % 4, 0u);
  const std::string json = glb.substr(20, json_length);
  const std::size_t bin_at = 20 + json_length;
  const uint32_t bin_length = Word(glb, bin_at);
  EXPECT_EQ(Word(glb, bin_at + 4), 0x004E4942u);  // BIN
  EXPECT_EQ(bin_at + 8 + bin_length, glb.size());
  EXPECT_NE(json.find("\"version\":\"2.0\""), std::string::npos);
  EXPECT_NE(json.find("\"name\":\"Left \\\"x\\\"\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"_DISPLACEMENT\""), std::string::npos);
  EXPECT_NE(json.find("\"byteLength\":" + std::to_string(bin_length)), std::string::npos) << json;

  // The first accessor: region 0's positions [m], then its displacement.
  std::smatch view;
  ASSERT_TRUE(std::regex_search(
      json, view,
      std::regex("\"bufferViews\":\\[\\{\"buffer\":0,\"byteOffset\":0,\"byteLength\":"
                 "([0-9]+)")));
  const std::size_t n = surfaces[0].nodes.size();
  ASSERT_EQ(std::stoul(view[1].str()), 12 * n);
  const char* bin = glb.data() + bin_at + 8;
  for (std::size_t v = 0; v < n; ++v) {
    for (int c = 0; c < 3; ++c) {
      float position = 0, moved = 0;
      std::memcpy(&position, bin + 12 * v + 4 * c, 4);
      std::memcpy(&moved, bin + 12 * n + 12 * v + 4 * c, 4);
      EXPECT_FLOAT_EQ(position, static_cast<float>(b.nodes[3 * surfaces[0].nodes[v] + c] * 1e-3));
      EXPECT_FLOAT_EQ(moved, static_cast<float>(0.5e-3 * b.nodes[3 * surfaces[0].nodes[v] + c]));
    }
  }
  // Without a displacement there is no such attribute; colours differ.
  EXPECT_EQ(SurfacesGlb(surfaces, b.nodes, {}).find("_DISPLACEMENT"), std::string::npos);
  EXPECT_NE(RegionColour(0), RegionColour(1));
}

// Steps through time: the GLB names their times and file; the file holds
// each step's displacement of the GLB's vertices, meshes in order.
TEST(SurfaceGltfTest, StepsHoldEachStepsDisplacementOfTheDrawnVertices) {
  const Block b = KuhnRow(2, 2);
  const std::size_t nodes = b.nodes.size() / 3;
  std::vector<double> steps;
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < 3 * nodes; ++i) steps.push_back((k + 1) * 0.1 * b.nodes[i]);
  }
  const auto surfaces = ExtractRegionSurfaces(b.tets, 4, b.region, {"A", "B"});
  SurfaceSteps stepped;
  stepped.times = {0.5, 1.0, 1.0 / 3};
  const std::string glb = SurfacesGlb(surfaces, b.nodes, {}, stepped);
  EXPECT_NE(glb.find("\"step_file\":\"surface_steps.bin\""), std::string::npos);
  EXPECT_NE(glb.find("\"step_times\":[0.5,1,0.33333333333333331]"), std::string::npos);
  const std::size_t vertices = surfaces[0].nodes.size() + surfaces[1].nodes.size();
  EXPECT_NE(glb.find("\"vertices\":" + std::to_string(vertices)), std::string::npos);

  const std::string bin = SurfaceStepsBin(surfaces, b.nodes, steps);
  ASSERT_EQ(bin.size(), 3 * vertices * 3 * sizeof(float));
  std::size_t at = 0;
  for (int k = 0; k < 3; ++k) {
    for (const RegionSurface& s : surfaces) {
      for (const int64_t node : s.nodes) {
        for (int c = 0; c < 3; ++c, at += 4) {
          float value = 0;
          std::memcpy(&value, bin.data() + at, 4);
          EXPECT_FLOAT_EQ(value, static_cast<float>((k + 1) * 0.1e-3 * b.nodes[3 * node + c]));
        }
      }
    }
  }
  // Steps that do not fit the nodes: no file rather than a wrong one.
  steps.pop_back();
  EXPECT_TRUE(SurfaceStepsBin(surfaces, b.nodes, steps).empty());
}

// Element values drawn on the surfaces: a vertex takes the mean over its
// own region's elements at its node, never the neighbouring region's; the
// file carries them as SCALAR attributes with their range; values that do
// not fit the surfaces are left out, not drawn wrong.
TEST(SurfaceGltfTest, ElementValuesAreMeansOverTheirOwnRegionAtEachVertex) {
  const Block b = KuhnRow(2, 2);  // cube 0 region A, cube 1 region B
  const auto surfaces = ExtractRegionSurfaces(b.tets, 4, b.region, {"A", "B"});
  std::vector<double> value(b.region.size());
  for (std::size_t e = 0; e < value.size(); ++e) {
    value[e] = (b.region[e] == 0 ? 100.0 : -50.0) + static_cast<double>(e % 6);
  }
  const auto means = VertexMeans(surfaces, b.tets, 4, b.region, value);
  ASSERT_EQ(means.size(), 2u);
  for (std::size_t r = 0; r < 2; ++r) {
    ASSERT_EQ(means[r].size(), surfaces[r].nodes.size());
    for (std::size_t v = 0; v < means[r].size(); ++v) {
      // The brute-force mean over region r's tetrahedra holding the node.
      double sum = 0;
      int count = 0;
      for (std::size_t e = 0; e < value.size(); ++e) {
        if (b.region[e] != static_cast<int64_t>(r)) continue;
        for (int c = 0; c < 4; ++c) {
          if (b.tets[4 * e + c] == surfaces[r].nodes[v]) {
            sum += value[e];
            ++count;
          }
        }
      }
      ASSERT_GT(count, 0);
      EXPECT_FLOAT_EQ(means[r][v], static_cast<float>(sum / count));
      EXPECT_EQ(means[r][v] > 0, r == 0) << "no value crosses the interface";
    }
  }
  const std::string glb =
      SurfacesGlb(surfaces, b.nodes, {}, {}, {{"_PRESSURE", "pressure", "Pa", means}});
  EXPECT_NE(glb.find("\"_PRESSURE\":"), std::string::npos);
  float lo = 1e30f, hi = -1e30f;
  for (const auto& m : means) {
    for (const float v : m) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  std::smatch range;
  ASSERT_TRUE(std::regex_search(
      glb, range,
      std::regex("\"scalars\":\\{\"_PRESSURE\":\\{\"label\":\"pressure\",\"unit\":\"Pa\","
                 "\"min\":([-0-9.e]+),\"max\":([-0-9.e]+)\\}\\}")))
      << glb.substr(20, 600);
  EXPECT_FLOAT_EQ(std::stof(range[1].str()), lo);
  EXPECT_FLOAT_EQ(std::stof(range[2].str()), hi);
  // One value short: left out of the file.
  value.pop_back();
  EXPECT_TRUE(VertexMeans(surfaces, b.tets, 4, b.region, value).empty());
  auto short_means = means;
  short_means[1].pop_back();
  EXPECT_EQ(SurfacesGlb(surfaces, b.nodes, {}, {}, {{"_STRAIN", "strain", "", short_means}})
                .find("_STRAIN"),
            std::string::npos);
}

}  // namespace
}  // namespace pba
