// The surfaces of a result's regions as glTF 2.0 binary (surfaces.glb):
// what a browser draws of a mesh of hundreds of thousands of elements
// without its interior. Each region's surface is the faces of its elements
// not shared with another element of the same region: its outer surface
// and its interfaces with the regions beside it (an interface face is in
// both, each facing out of its own region). Quadratic tetrahedra give their
// corner triangles, hexahedra two triangles per face.
//
// The file (https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html):
// one mesh and one node per region, named as the region; each primitive has
// POSITION (float32, metres: glTF's unit), indices (uint32) and a material
// of its own colour, double-sided (an interface is seen from both sides);
// with a displacement, a vertex attribute _DISPLACEMENT (float32 VEC3,
// metres) of the same vertices. asset.extras carries "pba_unit": "m" and
// each node's extras its region's index in the result and its number of
// elements.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pba {

struct RegionSurface {
  std::string name;
  int region = 0;                   // its index in the result's region names
  int64_t elements = 0;             // the region's elements
  std::vector<int64_t> nodes;       // the mesh node of each vertex
  std::vector<uint32_t> triangles;  // 3 vertex indices each, counter-clockwise seen from outside
};

// The surface of each region of `elements` (nodes_per_element 4, 10 or 8,
// row-major), in region order; a region without elements has none. Without
// regions (element_region empty, or not one per element) the whole mesh is
// one region "body"; an element whose region is out of range is in none.
std::vector<RegionSurface> ExtractRegionSurfaces(const std::vector<int64_t>& elements,
                                                 int nodes_per_element,
                                                 const std::vector<int64_t>& element_region,
                                                 const std::vector<std::string>& region_names);

// A display colour for region `index` of `count` (RGB 0..1): hues spread
// by the golden angle, so that neighbours in the list differ.
std::array<float, 3> RegionColour(int index);

// The steps of a result through time (or load), for SurfacesGlb's
// asset.extras: "step_times" and "step_file" (kSurfaceStepsFile), which
// holds every step's displacement of the file's vertices.
struct SurfaceSteps {
  std::vector<double> times;  // of each step [s] (or the load factor)
};
inline constexpr char kSurfaceStepsFile[] = "surface_steps.bin";

// A value per vertex of every surface, drawn as a colour: a glTF custom
// attribute (`attribute`, float32 SCALAR), named with its unit in
// asset.extras.scalars with its range.
struct VertexScalar {
  std::string attribute;                   // "_PRESSURE"
  std::string label;                       // "pressure"
  std::string unit;                        // "Pa"
  std::vector<std::vector<float>> values;  // per surface, per vertex
};

// `element_values` (one per element) on `surfaces` (as ExtractRegionSurfaces
// made them from the same `elements`, `nodes_per_element` and
// `element_region`): each vertex of region r's surface takes the mean over
// r's elements at its node, so that a value does not bleed across an
// interface. Empty when the sizes do not agree.
std::vector<std::vector<float>> VertexMeans(const std::vector<RegionSurface>& surfaces,
                                            const std::vector<int64_t>& elements,
                                            int nodes_per_element,
                                            const std::vector<int64_t>& element_region,
                                            const std::vector<double>& element_values);

// surfaces.glb: `surfaces` over `nodes_mm` (nodes x 3), with the nodal
// `displacement_mm` (nodes x 3) as _DISPLACEMENT when not empty, naming
// `steps` when it has any, and each of `scalars` whose values fit the
// surfaces.
std::string SurfacesGlb(const std::vector<RegionSurface>& surfaces,
                        const std::vector<double>& nodes_mm,
                        const std::vector<double>& displacement_mm, const SurfaceSteps& steps = {},
                        const std::vector<VertexScalar>& scalars = {});

// surface_steps.bin: for each step in order, the displacement of every
// vertex SurfacesGlb writes (its meshes in order, each mesh's vertices in
// order) as float32 x y z in metres, little-endian; `step_displacement_mm`
// holds steps x nodes x 3 ([mm], step-major, as Solution keeps it). Empty
// when the sizes do not agree.
std::string SurfaceStepsBin(const std::vector<RegionSurface>& surfaces,
                            const std::vector<double>& nodes_mm,
                            const std::vector<double>& step_displacement_mm);

}  // namespace pba
