#include "results/surface_gltf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "core/format.h"

namespace pba {
namespace {

// Faces of each element type, outward for a positively oriented element
// (corners only; a quadratic tetrahedron's first four nodes are its corners).
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kHexFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                 {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

// A face by its sorted corners (the fourth -1 for a triangle).
using FaceKey = std::array<int64_t, 4>;
struct FaceKeyHash {
  std::size_t operator()(const FaceKey& k) const {
    std::size_t h = 1469598103934665603ull;
    for (const int64_t v : k) h = (h ^ static_cast<std::size_t>(v)) * 1099511628211ull;
    return h;
  }
};

// Which elements hold each face: the first and the second (-1: none yet).
using FaceOwners = std::unordered_map<FaceKey, std::array<int64_t, 2>, FaceKeyHash>;

// glTF's constants.
constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

void Append(std::string* bytes, const void* data, std::size_t size) {
  bytes->append(static_cast<const char*>(data), size);
}

std::string Number(double value, int digits = 9) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

}  // namespace

std::vector<RegionSurface> ExtractRegionSurfaces(const std::vector<int64_t>& elements,
                                                 int nodes_per_element,
                                                 const std::vector<int64_t>& element_region,
                                                 const std::vector<std::string>& region_names) {
  const bool hex = nodes_per_element == 8;
  const int faces_per_element = hex ? 6 : 4;
  const int corners = hex ? 4 : 3;
  const int64_t ne = static_cast<int64_t>(elements.size()) / std::max(1, nodes_per_element);
  const bool regions =
      !region_names.empty() && element_region.size() == static_cast<std::size_t>(ne);
  const auto region_of = [&](int64_t e) { return regions ? element_region[e] : int64_t{0}; };
  const auto face = [&](int64_t e, int f, int c) {
    const int local = hex ? kHexFaces[f][c] : kTetFaces[f][c];
    return elements[nodes_per_element * e + local];
  };
  // The face's corners in increasing order (an insertion sort of three or
  // four), the rest -1.
  const auto key_of = [&](int64_t e, int f) {
    FaceKey key{-1, -1, -1, -1};
    for (int c = 0; c < corners; ++c) {
      int64_t value = face(e, f, c);
      int at = c;
      for (; at > 0 && key[at - 1] > value; --at) key[at] = key[at - 1];
      key[at] = value;
    }
    return key;
  };
  FaceOwners owners;
  owners.reserve(static_cast<std::size_t>(ne) * 2 + 16);
  for (int64_t e = 0; e < ne; ++e) {
    for (int f = 0; f < faces_per_element; ++f) {
      auto [it, inserted] = owners.try_emplace(key_of(e, f), std::array<int64_t, 2>{e, -1});
      if (!inserted) it->second[1] = e;
    }
  }

  const int count = regions ? static_cast<int>(region_names.size()) : 1;
  std::vector<RegionSurface> surfaces(count);
  std::vector<std::unordered_map<int64_t, uint32_t>> vertex(count);
  for (int r = 0; r < count; ++r) {
    surfaces[r].name = regions ? region_names[r] : "body";
    surfaces[r].region = r;
  }
  const auto vertex_of = [&](int r, int64_t node) {
    auto [it, inserted] =
        vertex[r].try_emplace(node, static_cast<uint32_t>(surfaces[r].nodes.size()));
    if (inserted) surfaces[r].nodes.push_back(node);
    return it->second;
  };
  // In element order, so that the file is the same for the same mesh.
  for (int64_t e = 0; e < ne; ++e) {
    const int64_t r = region_of(e);
    if (r < 0 || r >= count) continue;
    ++surfaces[r].elements;
    for (int f = 0; f < faces_per_element; ++f) {
      const std::array<int64_t, 2>& held = owners.at(key_of(e, f));
      const int64_t other = held[0] == e ? held[1] : held[0];
      if (other >= 0 && region_of(other) == r) continue;
      uint32_t v[4];
      for (int c = 0; c < corners; ++c) v[c] = vertex_of(static_cast<int>(r), face(e, f, c));
      std::vector<uint32_t>& t = surfaces[r].triangles;
      t.insert(t.end(), {v[0], v[1], v[2]});
      if (hex) t.insert(t.end(), {v[0], v[2], v[3]});
    }
  }
  return surfaces;
}

std::array<float, 3> RegionColour(int index) {
  // HSV with the hue stepped by the golden angle, saturation 0.55, value 0.9.
  const double hue = std::fmod(index * 137.50776405, 360.0) / 60.0;
  const double v = 0.9, s = 0.55, c = v * s;
  const double x = c * (1 - std::fabs(std::fmod(hue, 2.0) - 1));
  double rgb[3] = {0, 0, 0};
  const int sector = static_cast<int>(hue) % 6;
  const int order[6][3] = {{0, 1, 2}, {1, 0, 2}, {2, 0, 1}, {2, 1, 0}, {1, 2, 0}, {0, 2, 1}};
  rgb[order[sector][0]] = c;
  rgb[order[sector][1]] = x;
  const double m = v - c;
  return {static_cast<float>(rgb[0] + m), static_cast<float>(rgb[1] + m),
          static_cast<float>(rgb[2] + m)};
}

namespace {

// Whether SurfacesGlb draws `s` (it has triangles, and every node has
// coordinates).
bool Drawn(const RegionSurface& s, std::size_t node_count) {
  return !s.triangles.empty() && std::none_of(s.nodes.begin(), s.nodes.end(), [&](int64_t n) {
    return n < 0 || static_cast<std::size_t>(n) >= node_count;
  });
}

// The scalars with a value for every vertex of every surface, and the
// range of each over the surfaces drawn.
std::vector<const VertexScalar*> FittingScalars(const std::vector<RegionSurface>& surfaces,
                                                std::size_t node_count,
                                                const std::vector<VertexScalar>& scalars,
                                                std::vector<std::pair<float, float>>* ranges) {
  std::vector<const VertexScalar*> fitting;
  for (const VertexScalar& scalar : scalars) {
    bool fits = scalar.values.size() == surfaces.size();
    std::pair<float, float> range{std::numeric_limits<float>::max(),
                                  std::numeric_limits<float>::lowest()};
    for (std::size_t i = 0; fits && i < surfaces.size(); ++i) {
      fits = scalar.values[i].size() == surfaces[i].nodes.size();
      if (!fits || !Drawn(surfaces[i], node_count)) continue;
      for (const float v : scalar.values[i]) {
        range.first = std::min(range.first, v);
        range.second = std::max(range.second, v);
      }
    }
    if (fits && range.first <= range.second) {
      fitting.push_back(&scalar);
      ranges->push_back(range);
    }
  }
  return fitting;
}

}  // namespace

std::string SurfaceStepsBin(const std::vector<RegionSurface>& surfaces,
                            const std::vector<double>& nodes_mm,
                            const std::vector<double>& step_displacement_mm) {
  const std::size_t nodes = nodes_mm.size() / 3;
  if (nodes == 0 || step_displacement_mm.size() % (3 * nodes) != 0) return "";
  const std::size_t steps = step_displacement_mm.size() / (3 * nodes);
  std::string bin;
  for (std::size_t k = 0; k < steps; ++k) {
    const double* step = step_displacement_mm.data() + 3 * nodes * k;
    for (const RegionSurface& s : surfaces) {
      if (!Drawn(s, nodes)) continue;
      std::vector<float> xyz(3 * s.nodes.size());
      for (std::size_t v = 0; v < s.nodes.size(); ++v) {
        for (int c = 0; c < 3; ++c) {
          xyz[3 * v + c] = static_cast<float>(step[3 * s.nodes[v] + c] * 1e-3);
        }
      }
      Append(&bin, xyz.data(), xyz.size() * sizeof(float));
    }
  }
  return bin;
}

std::vector<std::vector<float>> VertexMeans(const std::vector<RegionSurface>& surfaces,
                                            const std::vector<int64_t>& elements,
                                            int nodes_per_element,
                                            const std::vector<int64_t>& element_region,
                                            const std::vector<double>& element_values) {
  const int64_t ne = static_cast<int64_t>(elements.size()) / std::max(1, nodes_per_element);
  if (element_values.size() != static_cast<std::size_t>(ne)) return {};
  const bool regions = element_region.size() == static_cast<std::size_t>(ne);
  // A quadratic tetrahedron's corners are its first four nodes.
  const int corners = nodes_per_element == 10 ? 4 : nodes_per_element;
  std::unordered_map<int64_t, std::size_t> surface_of;  // region -> its surface
  for (std::size_t i = 0; i < surfaces.size(); ++i) surface_of[surfaces[i].region] = i;
  std::vector<std::unordered_map<int64_t, uint32_t>> vertex(surfaces.size());
  std::vector<std::vector<double>> sum(surfaces.size());
  std::vector<std::vector<int>> count(surfaces.size());
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    for (std::size_t v = 0; v < surfaces[i].nodes.size(); ++v) {
      vertex[i][surfaces[i].nodes[v]] = static_cast<uint32_t>(v);
    }
    sum[i].assign(surfaces[i].nodes.size(), 0.0);
    count[i].assign(surfaces[i].nodes.size(), 0);
  }
  for (int64_t e = 0; e < ne; ++e) {
    const auto found = surface_of.find(regions ? element_region[e] : 0);
    if (found == surface_of.end()) continue;
    const std::size_t i = found->second;
    for (int c = 0; c < corners; ++c) {
      const auto at = vertex[i].find(elements[nodes_per_element * e + c]);
      if (at == vertex[i].end()) continue;
      sum[i][at->second] += element_values[e];
      ++count[i][at->second];
    }
  }
  std::vector<std::vector<float>> means(surfaces.size());
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    means[i].resize(sum[i].size());
    for (std::size_t v = 0; v < sum[i].size(); ++v) {
      means[i][v] = count[i][v] > 0 ? static_cast<float>(sum[i][v] / count[i][v]) : 0.0f;
    }
  }
  return means;
}

std::string SurfacesGlb(const std::vector<RegionSurface>& surfaces,
                        const std::vector<double>& nodes_mm,
                        const std::vector<double>& displacement_mm, const SurfaceSteps& steps,
                        const std::vector<VertexScalar>& scalars) {
  const bool displaced = !displacement_mm.empty() && displacement_mm.size() == nodes_mm.size();
  std::vector<std::pair<float, float>> ranges;
  const std::vector<const VertexScalar*> drawn_scalars =
      FittingScalars(surfaces, nodes_mm.size() / 3, scalars, &ranges);
  std::string bin;
  std::string views, accessors, meshes, nodes, materials;
  int view = 0, accessor = 0, drawn = 0;
  const auto add_view = [&](std::size_t offset, std::size_t length, int target) {
    views +=
        std::string(view ? "," : "") + "{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
        ",\"byteLength\":" + std::to_string(length) + ",\"target\":" + std::to_string(target) + "}";
    return view++;
  };
  const auto add_accessor = [&](int buffer_view, int type, std::size_t count, const char* shape,
                                const std::string& bounds) {
    accessors +=
        std::string(accessor ? "," : "") + "{\"bufferView\":" + std::to_string(buffer_view) +
        ",\"componentType\":" + std::to_string(type) + ",\"count\":" + std::to_string(count) +
        ",\"type\":\"" + shape + "\"" + bounds + "}";
    return accessor++;
  };
  const std::size_t node_count = nodes_mm.size() / 3;
  std::size_t vertices = 0;
  for (const RegionSurface& s : surfaces) {
    // (A surface naming a node the coordinates lack is not drawn.)
    if (!Drawn(s, node_count)) continue;
    vertices += s.nodes.size();
    // Positions [m], with their bounds (glTF requires them).
    std::vector<float> xyz(3 * s.nodes.size());
    float lo[3], hi[3];
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::numeric_limits<float>::max();
      hi[c] = std::numeric_limits<float>::lowest();
    }
    for (std::size_t v = 0; v < s.nodes.size(); ++v) {
      for (int c = 0; c < 3; ++c) {
        const float value = static_cast<float>(nodes_mm[3 * s.nodes[v] + c] * 1e-3);
        xyz[3 * v + c] = value;
        lo[c] = std::min(lo[c], value);
        hi[c] = std::max(hi[c], value);
      }
    }
    const std::string bounds = ",\"min\":[" + Number(lo[0]) + "," + Number(lo[1]) + "," +
                               Number(lo[2]) + "],\"max\":[" + Number(hi[0]) + "," + Number(hi[1]) +
                               "," + Number(hi[2]) + "]";
    const std::size_t position_at = bin.size();
    Append(&bin, xyz.data(), xyz.size() * sizeof(float));
    const int position =
        add_accessor(add_view(position_at, xyz.size() * sizeof(float), kArrayBuffer), kFloat,
                     s.nodes.size(), "VEC3", bounds);
    std::string attributes = "\"POSITION\":" + std::to_string(position);
    if (displaced) {
      for (std::size_t v = 0; v < s.nodes.size(); ++v) {
        for (int c = 0; c < 3; ++c) {
          xyz[3 * v + c] = static_cast<float>(displacement_mm[3 * s.nodes[v] + c] * 1e-3);
        }
      }
      const std::size_t at = bin.size();
      Append(&bin, xyz.data(), xyz.size() * sizeof(float));
      const int moved = add_accessor(add_view(at, xyz.size() * sizeof(float), kArrayBuffer), kFloat,
                                     s.nodes.size(), "VEC3", "");
      attributes += ",\"_DISPLACEMENT\":" + std::to_string(moved);
    }
    const std::size_t surface = static_cast<std::size_t>(&s - surfaces.data());
    for (const VertexScalar* scalar : drawn_scalars) {
      const std::vector<float>& values = scalar->values[surface];
      const std::size_t at = bin.size();
      Append(&bin, values.data(), values.size() * sizeof(float));
      const int added = add_accessor(add_view(at, values.size() * sizeof(float), kArrayBuffer),
                                     kFloat, values.size(), "SCALAR", "");
      attributes += "," + JsonQuoted(scalar->attribute) + ":" + std::to_string(added);
    }
    const std::size_t index_at = bin.size();
    Append(&bin, s.triangles.data(), s.triangles.size() * sizeof(uint32_t));
    const int indices =
        add_accessor(add_view(index_at, s.triangles.size() * sizeof(uint32_t), kElementArrayBuffer),
                     kUnsignedInt, s.triangles.size(), "SCALAR", "");
    const std::array<float, 3> rgb = RegionColour(s.region);
    const std::string sep = drawn ? "," : "";
    materials += sep + "{\"name\":" + JsonQuoted(s.name) +
                 ",\"doubleSided\":true,\"pbrMetallicRoughness\":{\"baseColorFactor\":[" +
                 Number(rgb[0]) + "," + Number(rgb[1]) + "," + Number(rgb[2]) +
                 ",1],\"metallicFactor\":0,\"roughnessFactor\":0.8}}";
    meshes += sep + "{\"name\":" + JsonQuoted(s.name) + ",\"primitives\":[{\"attributes\":{" +
              attributes + "},\"indices\":" + std::to_string(indices) +
              ",\"material\":" + std::to_string(drawn) + "}]}";
    nodes += sep + "{\"name\":" + JsonQuoted(s.name) + ",\"mesh\":" + std::to_string(drawn) +
             ",\"extras\":{\"region\":" + std::to_string(s.region) +
             ",\"elements\":" + std::to_string(s.elements) + "}}";
    ++drawn;
  }
  std::string scene_nodes;
  for (int n = 0; n < drawn; ++n) scene_nodes += (n ? "," : "") + std::to_string(n);
  std::string extras = "\"pba_unit\":\"m\",\"vertices\":" + std::to_string(vertices);
  if (!steps.times.empty()) {
    extras += ",\"step_file\":" + JsonQuoted(kSurfaceStepsFile) + ",\"step_times\":[";
    for (std::size_t k = 0; k < steps.times.size(); ++k) {
      extras += (k ? "," : "") + Number(steps.times[k], 17);
    }
    extras += "]";
  }
  if (!drawn_scalars.empty()) {
    extras += ",\"scalars\":{";
    for (std::size_t k = 0; k < drawn_scalars.size(); ++k) {
      const VertexScalar& scalar = *drawn_scalars[k];
      extras += std::string(k ? "," : "") + JsonQuoted(scalar.attribute) +
                ":{\"label\":" + JsonQuoted(scalar.label) + ",\"unit\":" + JsonQuoted(scalar.unit) +
                ",\"min\":" + Number(ranges[k].first) + ",\"max\":" + Number(ranges[k].second) +
                "}";
    }
    extras += "}";
  }
  std::string json = "{\"asset\":{\"version\":\"2.0\",\"generator\":\"PBA\",\"extras\":{" + extras +
                     "}},\"scene\":0,\"scenes\":[{\"nodes\":[" + scene_nodes + "]}],\"nodes\":[" +
                     nodes + "],\"meshes\":[" + meshes + "],\"materials\":[" + materials + "]";
  if (drawn > 0) {
    json += ",\"accessors\":[" + accessors + "],\"bufferViews\":[" + views +
            "],\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) + "}]";
  }
  json += "}";
  while (json.size() % 4 != 0) json += ' ';
  while (bin.size() % 4 != 0) bin += '\0';

  std::string glb;
  const uint32_t total =
      static_cast<uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size()));
  const uint32_t header[3] = {kGlbMagic, 2, total};
  Append(&glb, header, sizeof header);
  const uint32_t json_chunk[2] = {static_cast<uint32_t>(json.size()), kChunkJson};
  Append(&glb, json_chunk, sizeof json_chunk);
  glb += json;
  if (!bin.empty()) {
    const uint32_t bin_chunk[2] = {static_cast<uint32_t>(bin.size()), kChunkBin};
    Append(&glb, bin_chunk, sizeof bin_chunk);
    glb += bin;
  }
  return glb;
}

}  // namespace pba
