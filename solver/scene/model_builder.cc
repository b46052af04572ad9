#include "scene/model_builder.h"

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "atlas/atlas_build.h"
#include "atlas/atlas_mesh_cache.h"
#include "atlas/derived_structure.h"
#include "atlas/label_table.h"
#include "atlas/plates.h"
#include "atlas/structure_set.h"
#include "core/format.h"
#include "core/yaml_guard.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"
#include "mesh/region_faces.h"

namespace pba {

namespace {

// Where the mid-edge nodes of a 10-node mesh go on the geometry's curved
// faces: radially onto the cylinder's side, onto the shell's spheres. Flat
// faces keep their edge midpoints, which lie in them.
MidsideProjection CurvedSurfaces(const GeometrySpec& g) {
  constexpr double kMm = 1e-3;
  if (g.kind == GeometrySpec::Kind::kEllipsoid) {
    const auto& a = g.ellipsoid.semi_axes_mm;
    const Eigen::Vector3d inverse(1 / (a[0] * kMm), 1 / (a[1] * kMm), 1 / (a[2] * kMm));
    // Along the ray from the centre: the point where it leaves the body.
    return [inverse](const Eigen::Vector3d& x, const std::string&) -> Eigen::Vector3d {
      return x / x.cwiseProduct(inverse).norm();
    };
  }
  if (g.kind == GeometrySpec::Kind::kCylinder) {
    const double r = g.cylinder.radius_mm * kMm;
    return [r](const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
      if (set != "side") return x;
      const Eigen::Vector2d radial = x.head<2>();
      return Eigen::Vector3d(r * radial.x() / radial.norm(), r * radial.y() / radial.norm(), x.z());
    };
  }
  if (g.kind == GeometrySpec::Kind::kSphericalShell) {
    const double a = g.spherical_shell.inner_radius_mm * kMm;
    const double b = g.spherical_shell.outer_radius_mm * kMm;
    return [a, b](const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
      if (set == "inner") return a * x.normalized();
      if (set == "outer") return b * x.normalized();
      return x;
    };
  }
  return {};
}

// A patch's mid-edge nodes go where its parent set's do.
MidsideProjection WithPatches(const GeometrySpec& g, MidsideProjection project) {
  if (!project || g.patches.empty()) return project;
  std::map<std::string, std::string> parent;
  for (const PatchSpec& p : g.patches) parent[p.name] = p.set;
  return [parent = std::move(parent), project = std::move(project)](
             const Eigen::Vector3d& x, const std::string& set) -> Eigen::Vector3d {
    const auto it = parent.find(set);
    return project(x, it == parent.end() ? set : it->second);
  };
}

// Cuts the geometry's patches out of their sets; a patch that holds no
// face is an error naming it and, for a ball, the radius that would hold
// one.
Status CutPatches(const GeometrySpec& g, Mesh* mesh) {
  constexpr double kMm = 1e-3;
  for (std::size_t i = 0; i < g.patches.size(); ++i) {
    const PatchSpec& p = g.patches[i];
    const std::string path = "geometry.patches[" + std::to_string(i) + "]";
    const auto parent_it = mesh->face_sets.find(p.set);
    if (parent_it == mesh->face_sets.end()) {
      return Status::InvalidArgument(path + ".set", "the mesh has no face set '" + p.set + "'");
    }
    const FaceSet& parent = parent_it->second;
    const Eigen::Vector3d centre =
        Eigen::Vector3d(p.centre_mm[0], p.centre_mm[1], p.centre_mm[2]) * kMm;
    const Eigen::Vector3d point =
        Eigen::Vector3d(p.plane_point_mm[0], p.plane_point_mm[1], p.plane_point_mm[2]) * kMm;
    const Eigen::Vector3d normal(p.plane_normal[0], p.plane_normal[1], p.plane_normal[2]);
    // A node within a nanometre of the plane counts as on the kept side.
    const double on_plane = 1e-9 * normal.norm();
    FaceSet patch = FacesWhere(
        *mesh, parent,
        [&](const Eigen::Vector3d& x) {
          return (!p.ball || (x - centre).norm() <= p.radius_mm * kMm) &&
                 (!p.half_space || (x - point).dot(normal) >= -on_plane);
        },
        p.invert);
    if (!patch.triangles.empty() || !patch.quads.empty()) {
      mesh->face_sets[p.name] = std::move(patch);
      continue;
    }
    if (p.invert) {
      return Status::InvalidArgument(
          path + ".invert", Format("patch '%s' holds no face of '%s': its ball or half-space "
                                   "covers the whole set",
                                   p.name.c_str(), p.set.c_str()));
    }
    if (!p.ball) {
      return Status::InvalidArgument(
          path + ".plane_point_mm",
          Format("patch '%s' holds no face of '%s': no face has all its nodes on the side of the "
                 "plane through (%g, %g, %g) mm that (%g, %g, %g) points to",
                 p.name.c_str(), p.set.c_str(), p.plane_point_mm[0], p.plane_point_mm[1],
                 p.plane_point_mm[2], p.plane_normal[0], p.plane_normal[1], p.plane_normal[2]));
    }
    // The smallest radius about this centre that would hold a face.
    double needed = INFINITY;
    const auto reach = [&](const auto& face) {
      double r = 0;
      for (int node : face) r = std::max(r, (mesh->nodes.row(node).transpose() - centre).norm());
      needed = std::min(needed, r);
    };
    for (const auto& t : parent.triangles) reach(t);
    for (const auto& q : parent.quads) reach(q);
    return Status::InvalidArgument(
        path + ".radius_mm",
        Format("patch '%s' holds no face of '%s': no face has all its nodes within %g mm of "
               "(%g, %g, %g) mm%s; about this centre the radius must be at least %.3g mm at "
               "this element size (or move the centre onto the surface)",
               p.name.c_str(), p.set.c_str(), p.radius_mm, p.centre_mm[0], p.centre_mm[1],
               p.centre_mm[2], p.half_space ? " and on the kept side of its plane" : "",
               needed / kMm));
  }
  return Status::Ok();
}

// The atlas face sets the scene names ("surface:<structure>",
// "interface:<a>|<b>", validated in form by ValidateScene) must exist in
// the mesh built. An interface named in the other order than the mesh's
// (lower label first) is made from it, its triangles turned over so that
// the normal points from the first structure named into the second. A
// missing one is an error naming the scene field and the structure's sets
// the mesh has.
Status ProvideAtlasSets(const SceneSpec& scene, Mesh* mesh) {
  std::vector<std::pair<std::string, std::string>> wanted;  // (field, set)
  for (std::size_t i = 0; i < scene.geometry.patches.size(); ++i) {
    wanted.emplace_back("geometry.patches[" + std::to_string(i) + "].set",
                        scene.geometry.patches[i].set);
  }
  for (std::size_t i = 0; i < scene.boundary_conditions.size(); ++i) {
    wanted.emplace_back("boundary_conditions[" + std::to_string(i) + "].set",
                        scene.boundary_conditions[i].set);
  }
  for (std::size_t i = 0; i < scene.outputs.reaction_sets.size(); ++i) {
    wanted.emplace_back("outputs.reaction_sets[" + std::to_string(i) + "]",
                        scene.outputs.reaction_sets[i]);
  }
  for (const auto& [field, name] : wanted) {
    if (mesh->face_sets.count(name) != 0) continue;
    const std::optional<RegionSetName> wanted_set = ParseRegionSetName(name);
    if (!wanted_set) continue;  // a patch, made later
    const bool surface = !wanted_set->interface;
    const std::string& first = wanted_set->first;
    const std::string& second = wanted_set->second;
    if (!surface) {
      const auto reversed = mesh->face_sets.find(InterfaceSetName(second, first));
      if (reversed != mesh->face_sets.end()) {
        FaceSet turned = reversed->second;
        for (auto& t : turned.triangles) std::swap(t[1], t[2]);
        for (auto& m : turned.triangle_midside) std::swap(m[0], m[2]);
        mesh->face_sets[name] = std::move(turned);
        continue;
      }
    }
    // What the mesh has for the structure(s) named.
    std::vector<std::string> related;
    for (const auto& [set_name, set] : mesh->face_sets) {
      const std::optional<RegionSetName> has = ParseRegionSetName(set_name);
      if (!has) continue;
      const auto names = [&](const std::string& structure) {
        return !structure.empty() && (has->first == structure || has->second == structure);
      };
      if (names(first) || names(second)) related.push_back("'" + set_name + "'");
    }
    std::string listed;
    for (const std::string& r : related) listed += (listed.empty() ? "" : ", ") + r;
    return Status::InvalidArgument(
        field, Format("the atlas mesh has no face set '%s'%s; %s", name.c_str(),
                      surface ? " (the structure got no elements at this size)"
                              : " (the two structures do not touch in this mesh)",
                      related.empty() ? "it has none for these structures"
                                      : ("it has " + listed).c_str()));
  }
  return Status::Ok();
}

// A temporary directory for the synthetic atlas's plates, removed with it.
class TempPlatesDir {
 public:
  TempPlatesDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "pba-atlas-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) path_ = pattern;
  }
  ~TempPlatesDir() {
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove_all(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// How a build used the atlas mesh cache.
struct AtlasCacheUse {
  std::string key;  // empty: not cached (no cache, a 10-node mesh, no key)
  bool hit = false;
  std::string description;  // on a hit: the note of the build that made it
};

// BuildAtlas through the cache: on a hit only result->mesh is set (the
// mesh BuildAtlas made, before any patch or set was added) and
// use->description is what that build said of it; on a miss it builds, and
// StoreAtlasMesh keeps the mesh once its description is known. A cache
// that cannot be read is a miss: the cache saves time, it never fails a
// build.
Status BuildAtlasThroughCache(const AtlasBuildOptions& options, const BuildModelOptions& cache,
                              bool cacheable, AtlasBuildResult* result, AtlasCacheUse* use) {
  if (!cache.atlas_cache_dir.empty() && cacheable) {
    // A source that cannot be read has no key; BuildAtlas then says why.
    if (AtlasMeshCacheKey(options, &use->key).ok()) {
      CachedAtlasMesh entry;
      const Status loaded = LoadCachedAtlasMesh(cache.atlas_cache_dir, use->key, &entry, &use->hit);
      if (loaded.ok() && use->hit) {
        result->mesh = std::move(entry.mesh);
        use->description = std::move(entry.description);
        return Status::Ok();
      }
    } else {
      use->key.clear();
    }
  }
  return BuildAtlas(options, result);
}

// Keeps a mesh BuildAtlasThroughCache built, and says so in `description`.
void StoreAtlasMesh(const BuildModelOptions& cache, const AtlasCacheUse& use, const Mesh& mesh,
                    std::string* description) {
  if (use.key.empty()) return;
  const std::string key = use.key.substr(0, 12);
  const Status stored =
      StoreCachedAtlasMesh(cache.atlas_cache_dir, use.key, CachedAtlasMesh{mesh, *description},
                           cache.atlas_cache_max_bytes);
  description->append(stored.ok() ? "; atlas mesh (built, cached as " + key + ")"
                                  : "; atlas mesh built, not cached: " + stored.message());
}

// The atlas of the scene, meshed (BuildAtlas), and a description of what
// was kept, merged or dropped and at what size, for the summary.
// `built` keeps what a 10-node pass needs later (the loft, the regions'
// labels); its mesh is moved into `mesh`. With a cache directory a 4-node
// mesh may come from the cache, and then `built` holds nothing else.
}  // namespace

std::vector<std::string> KnownAtlasStructures(const AtlasSpec& a) {
  std::vector<std::string> names;
  if (a.source.empty() || a.source == "synthetic") return names;
  std::error_code ec;
  if (IsStructureSetDir(a.source)) {
    StructureSet set;
    if (!ReadStructureSet(a.source, &set).ok()) return {};
    // Derived structures are made from the others: a merge takes its
    // structures away.
    std::vector<DerivedStructure> derived;
    for (const StructureEntry& entry : set.structures) {
      if (entry.format != StructureFormat::kDerived) {
        names.push_back(entry.name);
        continue;
      }
      std::string text;
      if (!ReadYamlFileText(std::filesystem::path(a.source) / entry.file, entry.name, &text).ok() ||
          !ParseDerivedStructure(text, entry.name, entry.name, &derived.emplace_back()).ok()) {
        return {};  // the build says what is wrong
      }
    }
    if (!OrderDerivedStructures(names, &derived).ok()) return {};
    for (const DerivedStructure& d : derived) names = NamesAfterStep(d.step, std::move(names));
  } else if (std::filesystem::is_directory(a.source, ec)) {
    ColourTable colours;  // a plate directory: its colour table
    if (!ReadPlateColours(a.source, &colours).ok()) return {};
    for (const ColourEntry& entry : colours.entries()) names.push_back(entry.name);
  } else if (!a.colour_table.empty()) {
    ColourTable table;
    LabelTableRead read;
    if (!ReadLabelTable(a.colour_table, &table, &read).ok()) return {};
    for (const ColourEntry& entry : table.entries()) names.push_back(entry.name);
  }
  // The names label algebra leaves: those it adds, less those it takes
  // (keep, drop, merge, rename).
  std::vector<LabelStep> steps;
  if (names.empty() || a.label_steps_json.empty() ||
      !ParseLabelSteps(a.label_steps_json, "labels", {}, &steps).ok()) {
    return names;
  }
  for (const LabelStep& step : steps) {
    names = NamesAfterStep(step, std::move(names));
    if (step.kind != LabelStep::Kind::kOverlay) continue;
    ColourTable table;
    LabelTableRead read;
    if (!ReadLabelTable(step.table, &table, &read).ok()) return {};
    for (const ColourEntry& entry : table.entries()) {
      const bool laid =
          step.structures.empty() ||
          std::any_of(step.structures.begin(), step.structures.end(), [&](const std::string& s) {
            return s == entry.name || InStructureGroup(entry.name, s);
          });
      if (laid && std::find(names.begin(), names.end(), entry.name) == names.end()) {
        names.push_back(entry.name);
      }
    }
  }
  return names;
}

namespace {

Status BuildAtlasMesh(const SceneSpec& scene, const BuildModelOptions& cache, Mesh* mesh,
                      std::string* description, AtlasBuildResult* built) {
  const AtlasSpec& a = scene.geometry.atlas;
  AtlasBuildOptions options;
  TempPlatesDir temp;
  if (a.source.empty() || a.source == "synthetic") {
    if (temp.path().empty()) return Status::Io("cannot create a temporary directory for plates");
    options.source = AtlasBuildOptions::Source::kSynthetic;
    options.plates_dir = temp.path() / "plates";
  } else if (IsStructureSetDir(a.source)) {
    options.source = AtlasBuildOptions::Source::kStructures;
    options.input = a.source;
  } else if (std::filesystem::is_directory(a.source)) {
    options.source = AtlasBuildOptions::Source::kPlates;
    options.input = a.source;
  } else {
    options.source = AtlasBuildOptions::Source::kLabelVolume;
    options.input = a.source;
    options.colour_table = a.colour_table;
  }
  const double h = EffectiveElementSize(scene.geometry, scene.mesh);
  options.synthetic_voxel_mm = options.loft_voxel_mm = a.voxel_size_mm > 0 ? a.voxel_size_mm : 1.5;
  // A structure set's masks (a snapshot of an imported label volume) keep
  // their own voxels unless the scene asks for others: resampled, a 1 mm
  // atlas would lose its thin parts and its mesh quality.
  if (options.source == AtlasBuildOptions::Source::kStructures && a.voxel_size_mm == 0) {
    options.loft_voxel_mm = 0;
  }
  options.cell_size_mm = h;
  options.facet_size_mm = a.facet_size_mm > 0 ? a.facet_size_mm : h / 2;
  // The scene's sizes everywhere: a structure too small for them is named in
  // the note, not refined (pba-atlas refines small structures and smooths).
  options.facets_per_section = 0;
  options.odt_iterations = 0;
  options.optimisation_time_limit_s = 20;
  options.structures = a.structures;
  options.merge_rest = a.merge_rest;
  if (!a.label_steps_json.empty()) {
    PBA_RETURN_IF_ERROR(
        ParseLabelSteps(a.label_steps_json, "geometry.atlas.labels", {}, &options.label_steps));
  }
  options.roi_centre_mm =
      Eigen::Vector3d(a.roi_centre_mm[0], a.roi_centre_mm[1], a.roi_centre_mm[2]);
  options.roi_radius_mm = a.roi_radius_mm;
  options.roi_size_mm = std::min(a.roi_element_size_mm, h);
  AtlasBuildResult& result = *built;
  AtlasCacheUse cached;
  if (Status s = BuildAtlasThroughCache(options, cache, !IsQuadratic(scene.mesh.element), &result,
                                        &cached);
      !s.ok()) {
    // The build's fields, as the scene names them.
    const std::string field = s.field() == "structures" || s.field().rfind("structures[", 0) == 0 ||
                                      s.field().rfind("labels[", 0) == 0
                                  ? "geometry.atlas." + s.field()
                              : s.field() == "input" ? "geometry.atlas.source"
                              : s.field().empty()    ? ""
                                                     : "geometry.atlas";
    if (s.code() == Status::Code::kInvalidArgument) {
      // A field with no counterpart in the scene keeps its own name.
      return Status::InvalidArgument(field, field == "geometry.atlas" ? s.ToString() : s.message());
    }
    return s;
  }
  *mesh = std::move(result.mesh);
  if (cached.hit) {
    *description =
        cached.description + "; atlas mesh from the cache (key " + cached.key.substr(0, 12) + ")";
    return Status::Ok();
  }
  const int kept = static_cast<int>(result.region_labels.size()) - (result.merged.empty() ? 0 : 1);
  *description = Format("%s atlas, %d structure%s", result.synthetic ? "synthetic" : "user", kept,
                        kept == 1 ? "" : "s");
  if (!a.structures.empty()) description->append(" (as asked)");
  if (!result.merged.empty()) {
    description->append(Format(", %d more merged into \"%s\"",
                               static_cast<int>(result.merged.size()), kSurroundingTissue));
  }
  if (!result.dropped.empty()) {
    description->append(
        Format(", %d dropped (not asked for)", static_cast<int>(result.dropped.size())));
  }
  // The voxels the mesh was made from: the label volume's own, the loft's,
  // or the structure set's composition.
  const Eigen::Vector3d& v = result.volume.spacing_mm();
  const std::string voxels = v.maxCoeff() - v.minCoeff() <= 1e-9 * v.maxCoeff()
                                 ? Format("%.3g mm", v.x())
                                 : Format("%.3g x %.3g x %.3g mm", v.x(), v.y(), v.z());
  description->append(Format("; CGAL Mesh_3 from %s voxels, %.3g mm elements, %.3g mm on surfaces",
                             voxels.c_str(), options.cell_size_mm, options.facet_size_mm));
  for (const std::string& step : result.mesher.time_limit_reached) {
    description->append(
        Format(" (its %s step stopped at its time limit: the mesh depends on the "
               "machine's load)",
               step.c_str()));
  }
  if (a.roi_radius_mm > 0) {
    description->append(Format(", %.3g mm within %.3g mm of (%g, %g, %g) mm", options.roi_size_mm,
                               a.roi_radius_mm, a.roi_centre_mm[0], a.roi_centre_mm[1],
                               a.roi_centre_mm[2]));
  }
  if (!result.islands.empty()) description->append("; " + result.islands);
  std::string empty;
  for (size_t r = 0; r < result.quality.regions.size(); ++r) {
    if (result.quality.regions[r].count > 0) continue;
    empty += (empty.empty() ? "" : ", ") + mesh->region_names[r];
  }
  if (!empty.empty()) {
    description->append("; smaller than these elements, so without any: " + empty);
  }
  description->append(Format("; %d tetrahedra, smallest dihedral angle %.1f deg",
                             mesh->num_elements(), result.quality.overall.min_dihedral_deg));
  if (result.validation) {
    description->append(
        Format("; against its plates %.2g %% (thesis eq. 4.3, limit 0.65 %%) over "
               "%d sections",
               result.validation->overall_percentage_error, result.validation->total_sections));
  }
  // A structure set's overlaps: who kept what is worth knowing in a result.
  for (const std::string& note : result.notes) description->append("; " + note);
  StoreAtlasMesh(cache, cached, *mesh, description);
  return Status::Ok();
}

// The structures whose displacement is reported, checked against the
// regions the mesh has (a label volume's names are known only once it is
// read).
Status CheckStructureNames(const SceneSpec& scene, const Mesh& mesh) {
  const auto& names = scene.outputs.structure_displacements;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "*") continue;
    if (std::find(mesh.region_names.begin(), mesh.region_names.end(), names[i]) ==
        mesh.region_names.end()) {
      return Status::FailedPrecondition(
          Format("outputs.structure_displacements[%zu]", i),
          "the model has no structure named \"" + names[i] +
              "\" (names as in the atlas's colour table or an inclusion's name)");
    }
  }
  return Status::Ok();
}

}  // namespace

Status BuildBaseMesh(const SceneSpec& scene, const BuildModelOptions& options, BaseMesh* out) {
  BaseMesh& base = *out;
  base = BaseMesh();
  if (scene.geometry.kind == GeometrySpec::Kind::kAtlas) {
    auto atlas = std::make_shared<AtlasBuildResult>();
    PBA_RETURN_IF_ERROR(BuildAtlasMesh(scene, options, &base.mesh, &base.description, atlas.get()));
    PBA_RETURN_IF_ERROR(ProvideAtlasSets(scene, &base.mesh));
    base.atlas = std::move(atlas);
  } else {
    MeshStats stats;
    base.mesh = BuildPrimitiveMesh(scene.geometry, scene.mesh, &stats);
    base.description = stats.description;
  }
  return Status::Ok();
}

Status BuildModel(const SceneSpec& scene, Model* out, const BuildModelOptions& options) {
  BaseMesh base;
  PBA_RETURN_IF_ERROR(BuildBaseMesh(scene, options, &base));
  return BuildModelOn(scene, std::move(base), out);
}

Status BuildModelOn(const SceneSpec& scene, BaseMesh base, Model* out) {
  constexpr double kMm = 1e-3;
  Model& model = *out;
  model = Model();
  model.mesh = std::move(base.mesh);
  model.mesh_description = std::move(base.description);
  PBA_RETURN_IF_ERROR(CutPatches(scene.geometry, &model.mesh));
  PBA_RETURN_IF_ERROR(CutInclusions(scene, &model.mesh));
  PBA_RETURN_IF_ERROR(ResolveMaterials(scene, model.mesh, &model.materials));
  PBA_RETURN_IF_ERROR(CheckStructureNames(scene, model.mesh));
  if (IsQuadratic(scene.mesh.element)) {
    model.mesh =
        MakeQuadratic(model.mesh, WithPatches(scene.geometry, CurvedSurfaces(scene.geometry)));
    if (scene.geometry.kind != GeometrySpec::Kind::kAtlas) {
      model.mesh_description +=
          "; 10-node: a node on every edge, on the true surface of curved faces";
    } else if (const std::optional<MidsideProjectionReport> p =
                   base.atlas ? CurveAtlasMidsideNodes(*base.atlas, &model.mesh) : std::nullopt) {
      model.mesh_description += Format(
          "; 10-node: %lld of %lld mid-edge nodes on surfaces and interfaces moved onto the "
          "loft's smooth surfaces (%lld of them part of the way, to keep the Jacobian ratio "
          "within %g), median distance from them %.2g mm (%.2g mm at the edges' midpoints)",
          static_cast<long long>(p->projected + p->shortened),
          static_cast<long long>(p->boundary_nodes), static_cast<long long>(p->shortened),
          MidsideProjectionOptions().max_jacobian_ratio, p->gap_mm.median_mm,
          p->gap_midpoints_mm.median_mm);
    } else {
      model.mesh_description +=
          "; 10-node: a node at the middle of every edge (a label volume has no smooth surface "
          "to move them to)";
    }
  }
  model.dofs = DofMap(model.mesh.num_nodes());
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    if (bc.is_load()) continue;  // see BuildLoads
    const int normal = bc.kind == BoundaryConditionSpec::Kind::kSymmetry
                           ? PlaneNormalAxis(scene.geometry, bc.set)
                           : -1;
    for (int node : model.mesh.face_sets.at(bc.set).nodes) {
      if (normal >= 0) {
        model.dofs.Prescribe(node, normal, 0.0);
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        if (bc.kind == BoundaryConditionSpec::Kind::kFixed) {
          model.dofs.Prescribe(node, c, 0.0);
        } else if (bc.displacement_mm[c]) {
          model.dofs.Prescribe(node, c, *bc.displacement_mm[c] * kMm);
        }
      }
    }
  }
  model.dofs.Finalize();
  return Status::Ok();
}

ExternalLoads BuildLoads(const SceneSpec& scene, const Model& model) {
  const Mesh& mesh = model.mesh;
  ExternalLoads loads(mesh);
  const bool follower = scene.analysis.type != AnalysisSpec::Type::kLinearStatic;
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    const FaceSet& set = mesh.face_sets.at(bc.set);
    if (bc.kind == BoundaryConditionSpec::Kind::kPressure && bc.pressure_pa != 0) {
      loads.AddPressure(set, bc.pressure_pa, follower);
    } else if (bc.kind == BoundaryConditionSpec::Kind::kTraction) {
      loads.AddTraction(set, Eigen::Vector3d(bc.traction_pa.data()));
    }
  }
  if (scene.gravity.enabled) {
    const GravitySpec& gravity = scene.gravity;
    const Eigen::Vector3d g(gravity.acceleration_m_per_s2.data());
    const SceneMaterials& materials = model.materials;
    if (materials.uniform() && gravity.fluid_density_kg_per_m3 == 0) {
      loads.AddBodyForce(scene.material.density_kg_per_m3 * g);
    } else {
      // Buoyancy: the fluid's weight pushes up on whatever it surrounds,
      // below its level (a height along -g).
      const Eigen::Vector3d up =
          g.norm() > 0 ? Eigen::Vector3d(-g.normalized()) : Eigen::Vector3d::Zero();
      loads.AddElementBodyForceField([&](const Eigen::Vector3d& x, int e) -> Eigen::Vector3d {
        double density = materials.density(e);
        if (!gravity.fluid_level_mm || up.dot(x) <= *gravity.fluid_level_mm * 1e-3) {
          density -= gravity.fluid_density_kg_per_m3;
        }
        return density * g;
      });
    }
  }
  return loads;
}

std::vector<std::string> ReactionSetNames(const SceneSpec& scene) {
  if (!scene.outputs.reaction_sets.empty()) return scene.outputs.reaction_sets;
  std::vector<std::string> out;
  for (const auto& bc : scene.boundary_conditions) {
    if (bc.is_load()) continue;
    if (std::find(out.begin(), out.end(), bc.set) == out.end()) out.push_back(bc.set);
  }
  return out;
}

}  // namespace pba
