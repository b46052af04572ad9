// MeshAtlasSurfaces (pba/solve.h): a structure set's surfaces for a view.
#include <cstdint>
#include <vector>

#include "atlas/atlas_build.h"
#include "pba/solve.h"
#include "results/surface_gltf.h"

namespace pba {

Status MeshAtlasSurfaces(const std::filesystem::path& set_dir, double facet_mm,
                         AtlasSurfaces* surfaces) {
  *surfaces = AtlasSurfaces();
  AtlasBuildOptions options;
  options.source = AtlasBuildOptions::Source::kStructures;
  options.input = set_dir;
  options.facet_size_mm = facet_mm;
  // Cells only fill the volume between the surfaces: large ones are fewer.
  options.cell_size_mm = 4 * facet_mm;
  options.odt_iterations = 0;
  options.improve_target_deg = 0;
  options.remove_slivers = false;
  options.validate = false;
  options.threads = ThreadContext(1);
  PBA_RETURN_IF_ERROR(options.Validate());
  AtlasBuildResult built;
  PBA_RETURN_IF_ERROR(BuildAtlas(options, &built));
  const Mesh& mesh = built.mesh;
  std::vector<int64_t> elements, region(mesh.element_region.begin(), mesh.element_region.end());
  elements.reserve(4 * mesh.tets.size());
  for (const auto& tet : mesh.tets) elements.insert(elements.end(), tet.begin(), tet.end());
  std::vector<double> nodes_mm(mesh.nodes.data(), mesh.nodes.data() + mesh.nodes.size());
  for (double& x : nodes_mm) x *= 1e3;
  const std::vector<RegionSurface> regions =
      ExtractRegionSurfaces(elements, 4, region, mesh.region_names);
  surfaces->glb = SurfacesGlb(regions, nodes_mm, {});
  surfaces->structures = static_cast<int>(mesh.region_names.size());
  for (const RegionSurface& s : regions) {
    surfaces->triangles += static_cast<int64_t>(s.triangles.size() / 3);
  }
  return Status::Ok();
}

}  // namespace pba
