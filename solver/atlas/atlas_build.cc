#include "atlas/atlas_build.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <memory>
#include <numbers>
#include <string>

#include "atlas/label_table.h"
#include "atlas/label_volume_io.h"
#include "atlas/loft.h"
#include "atlas/midside_projection.h"
#include "atlas/structure_set.h"
#include "atlas/synthetic_atlas.h"
#include "core/format.h"
#include "mesh/improve.h"
#include "mesh/quadratic.h"
#include "mesh/region_faces.h"

namespace pba {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The labels the mesh keeps, in label order: those present in the volume
// and, when the options name structures, among them.
Status ChooseLabels(const AtlasBuildOptions& options, const ColourTable& colours,
                    const LabelVolume& volume, std::vector<uint16_t>* labels,
                    std::vector<std::string>* left_out, std::vector<std::string>* absent) {
  const std::vector<int64_t> counts = CountLabels(volume);
  std::vector<bool> wanted(counts.size(), options.structures.empty());
  for (size_t i = 0; i < options.structures.size(); ++i) {
    const std::string& name = options.structures[i];
    // A structure, or a group: "Thalamus" for every "Thalamus: ..." entry.
    std::vector<const ColourEntry*> entries;
    PBA_RETURN_IF_ERROR(
        EntriesNamed(colours, name, "structures[" + std::to_string(i) + "]", &entries));
    bool present = false;
    for (const ColourEntry* e : entries) {
      present |= counts[e->label] > 0;
      wanted[e->label] = true;
    }
    if (!present) {
      return Status::InvalidArgument("structures[" + std::to_string(i) + "]",
                                     "\"" + name + "\" is not in the label volume");
    }
  }
  labels->clear();
  left_out->clear();
  absent->clear();
  for (const ColourEntry& e : colours.entries()) {
    if (counts[e.label] == 0) absent->push_back(e.name);
  }
  for (size_t label = 1; label < counts.size(); ++label) {
    if (counts[label] == 0) continue;
    const ColourEntry* entry = colours.FindByLabel(static_cast<uint16_t>(label));
    if (entry == nullptr) {
      return Status::InvalidArgument(
          "colour_table", "label " + std::to_string(label) + " of the label volume has no entry");
    }
    if (wanted[label]) {
      labels->push_back(static_cast<uint16_t>(label));
    } else {
      left_out->push_back(entry->name);
    }
  }
  if (labels->empty()) return Status::InvalidArgument("input", "the label volume has no structure");
  return Status::Ok();
}

// Per region, the facet size bound of its surfaces (LabelMeshOptions::
// region_facet_size_mm; 0 for none): its mean section perimeter over
// options.facets_per_section, the perimeter estimated as that of a disc of
// the structure's mean axial section area (voxel volume over the height
// between its lowest and highest voxel layer). The disc has the smallest
// perimeter of any section of that area, so the estimate errs towards
// smaller facets.
std::vector<double> StructureFacetSizes(const AtlasBuildOptions& options, const LabelVolume& volume,
                                        const std::vector<uint16_t>& labels) {
  if (options.facets_per_section <= 0) return {};
  std::vector<int64_t> count(65536, 0);
  std::vector<int> lowest(65536, volume.nz()), highest(65536, -1);
  for (int k = 0; k < volume.nz(); ++k) {
    for (int j = 0; j < volume.ny(); ++j) {
      for (int i = 0; i < volume.nx(); ++i) {
        const uint16_t l = volume.at(i, j, k);
        ++count[l];
        lowest[l] = std::min(lowest[l], k);
        highest[l] = std::max(highest[l], k);
      }
    }
  }
  std::vector<double> sizes;
  for (uint16_t label : labels) {
    if (label == 0 || count[label] == 0) {  // the surrounding tissue: the global size
      sizes.push_back(0);
      continue;
    }
    const double height = (highest[label] - lowest[label] + 1) * volume.spacing_mm().z();
    const double mean_area = count[label] * volume.voxel_volume_mm3() / height;
    const double perimeter = 2 * std::sqrt(std::numbers::pi * mean_area);
    sizes.push_back(perimeter / options.facets_per_section);
  }
  return sizes;
}

// A point inside each connected piece (6-connected voxels of one region) of
// at least kMinPieceVoxels voxels: the centre of its voxel nearest to the
// piece's centroid, which samples to the piece's own label and, for a
// compact piece, lies well inside it. `region_of` maps labels to
// regions (0: not meshed). Lets the mesher seed a piece smaller than its
// seeding grid (LabelMeshOptions::interior_points_mm); a smaller speck is
// left to the grid.
std::vector<Eigen::Vector3d> PieceInteriorPoints(const LabelVolume& volume,
                                                 const std::vector<int>& region_of) {
  constexpr int64_t kMinPieceVoxels = 8;
  std::vector<Eigen::Vector3d> points;
  std::vector<char> seen(volume.num_voxels(), 0);
  std::vector<int64_t> stack, piece;
  const std::array<int, 3> dims = volume.dims();
  const int64_t stride[3] = {1, dims[0], static_cast<int64_t>(dims[0]) * dims[1]};
  for (int64_t first = 0; first < volume.num_voxels(); ++first) {
    const int region = region_of[volume.labels()[first]];
    if (seen[first] || region == 0) continue;
    seen[first] = 1;
    stack.assign(1, first);
    piece.clear();
    while (!stack.empty()) {
      const int64_t v = stack.back();
      stack.pop_back();
      piece.push_back(v);
      const int64_t ijk[3] = {v % dims[0], (v / dims[0]) % dims[1], v / stride[2]};
      for (int axis = 0; axis < 3; ++axis) {
        for (const int d : {-1, 1}) {
          const int64_t c = ijk[axis] + d;
          if (c < 0 || c >= dims[axis]) continue;
          const int64_t w = v + d * stride[axis];
          if (seen[w] || region_of[volume.labels()[w]] != region) continue;
          seen[w] = 1;
          stack.push_back(w);
        }
      }
    }
    if (static_cast<int64_t>(piece.size()) < kMinPieceVoxels) continue;
    const auto centre = [&](int64_t v) {
      return volume.VoxelCentreMm(static_cast<int>(v % dims[0]),
                                  static_cast<int>((v / dims[0]) % dims[1]),
                                  static_cast<int>(v / stride[2]));
    };
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const int64_t v : piece) centroid += centre(v);
    centroid /= static_cast<double>(piece.size());
    const int64_t nearest =
        *std::min_element(piece.begin(), piece.end(), [&](int64_t a, int64_t b) {
          return (centre(a) - centroid).squaredNorm() < (centre(b) - centroid).squaredNorm();
        });
    points.push_back(centre(nearest));
  }
  return points;
}

// An atlas spans millimetres to decimetres (a mouse brain about 10 mm, a
// human one about 170 mm); a largest extent outside [kMinExtentMm,
// kMaxExtentMm] means a wrong pixel or voxel size (metres for millimetres,
// say), which would otherwise surface as an empty mesh or a grid too large
// to loft.
constexpr double kMinExtentMm = 5, kMaxExtentMm = 1000;

Status CheckExtent(const Eigen::Vector3d& extent_mm, const std::string& field,
                   const std::string& what, const std::string& size) {
  const double largest = extent_mm.maxCoeff();
  if (largest >= kMinExtentMm && largest <= kMaxExtentMm) return Status::Ok();
  return Status::InvalidArgument(
      field, Format("%s spans %.3g x %.3g x %.3g mm with %s: an atlas spans %g to %g mm; check "
                    "that the size is in millimetres",
                    what.c_str(), extent_mm.x(), extent_mm.y(), extent_mm.z(), size.c_str(),
                    kMinExtentMm, kMaxExtentMm));
}

// `labels` are the regions kept; label 0 among them (merge_rest) stands for
// every other label of the volume.
// Per region: the quality rounds' bounds on its cells and facets [mm], 0
// for none (AtlasBuildOptions::quality_rounds).
struct RegionSizes {
  std::vector<double> cell_mm, facet_mm;
};

Status MeshVolume(const AtlasBuildOptions& options, const LabelVolume& volume,
                  const ColourTable& colours, const std::vector<uint16_t>& labels,
                  const RegionSizes& sizes, Mesh* mesh, LabelMeshReport* report) {
  // Region index + 1 of each label, 0 for the labels left out.
  std::vector<int> region_of(65536, 0);
  std::vector<std::string> names;
  for (size_t r = 0; r < labels.size(); ++r) {
    if (labels[r] == 0) {
      std::fill(region_of.begin(), region_of.end(), static_cast<int>(r) + 1);
      names.push_back(kSurroundingTissue);
    } else {
      names.push_back(colours.FindByLabel(labels[r])->name);
    }
  }
  region_of[0] = 0;
  for (size_t r = 0; r < labels.size(); ++r) {
    if (labels[r] != 0) region_of[labels[r]] = static_cast<int>(r) + 1;
  }
  LabelMeshOptions mesh_options;
  // The grid's outer voxel faces, widened by a voxel so that no structure
  // touches the box (the mesher cuts a region off at the box).
  const Eigen::Vector3d half = 0.5 * volume.spacing_mm();
  const Eigen::Vector3d last =
      volume.VoxelCentreMm(volume.nx() - 1, volume.ny() - 1, volume.nz() - 1);
  mesh_options.box_min_mm = volume.origin_mm() - half - volume.spacing_mm();
  mesh_options.box_max_mm = last + half + volume.spacing_mm();
  mesh_options.cell_size_mm = options.cell_size_mm;
  mesh_options.facet_size_mm = options.facet_size_mm;
  mesh_options.facet_distance_mm =
      options.facet_distance_mm > 0 ? options.facet_distance_mm : options.facet_size_mm / 4;
  mesh_options.roi_centre_mm = options.roi_centre_mm;
  mesh_options.roi_radius_mm = options.roi_radius_mm;
  mesh_options.roi_size_mm = options.roi_size_mm;
  mesh_options.region_facet_size_mm = StructureFacetSizes(options, volume, labels);
  if (!sizes.facet_mm.empty()) {
    std::vector<double>& facet = mesh_options.region_facet_size_mm;
    facet.resize(labels.size(), 0);
    for (size_t r = 0; r < labels.size(); ++r) {
      if (sizes.facet_mm[r] > 0) {
        facet[r] = facet[r] > 0 ? std::min(facet[r], sizes.facet_mm[r]) : sizes.facet_mm[r];
      }
    }
    mesh_options.region_cell_size_mm = sizes.cell_mm;
  }
  mesh_options.odt_iterations = options.odt_iterations;
  mesh_options.perturb = options.remove_slivers;
  mesh_options.exude = options.remove_slivers;
  mesh_options.optimisation_time_limit_s = options.optimisation_time_limit_s;
  mesh_options.interior_points_mm = PieceInteriorPoints(volume, region_of);
  const LabelFunction label = [&](const Eigen::Vector3d& x_mm) {
    return region_of[volume.SampleNearest(x_mm)];
  };
  return MeshLabels(label, names, mesh_options, mesh, report);
}

// The loft labels each region stands for: its own, or for the merged
// region (label 0) every label of the loft not kept.
std::vector<std::vector<int>> RegionLabelSets(const LoftField& loft,
                                              const std::vector<uint16_t>& region_labels) {
  std::vector<char> kept(65536, 0);
  for (uint16_t label : region_labels) kept[label] = 1;
  std::vector<std::vector<int>> sets;
  for (uint16_t label : region_labels) {
    sets.emplace_back();
    if (label != 0) {
      sets.back().push_back(label);
      continue;
    }
    for (int l : loft.labels()) {
      if (!kept[l]) sets.back().push_back(l);
    }
  }
  return sets;
}

// A label volume's table: the file at `path` in whichever format it is,
// its notes into the result's; without one, the built-in table, for the
// synthetic atlas's own volume only (LabelVolumeNeedsATable).
Status ReadVolumeTable(const std::filesystem::path& path, AtlasBuildResult* result) {
  if (path.empty()) {
    PBA_RETURN_IF_ERROR(LabelVolumeNeedsATable(result->volume, "colour_table"));
    result->colours = ColourTable::Builtin();
    return Status::Ok();
  }
  LabelTableRead read;
  PBA_RETURN_IF_ERROR(ReadLabelTable(path, &result->colours, &read));
  result->notes.insert(result->notes.end(), read.notes.begin(), read.notes.end());
  return Status::Ok();
}

// A label volume source: the volume (unless a structure set composed it),
// its extent checked, its table, and the label algebra on both.
Status ReadVolumeSource(const AtlasBuildOptions& options, bool composed_volume,
                        AtlasBuildResult* result) {
  if (!composed_volume) {
    PBA_RETURN_IF_ERROR(ReadLabelVolume(options.input, "input", &result->volume));
  }
  const LabelVolume& v = result->volume;
  PBA_RETURN_IF_ERROR(
      CheckExtent(Eigen::Vector3d(v.nx(), v.ny(), v.nz()).cwiseProduct(v.spacing_mm()), "input",
                  options.input.string(),
                  Format("voxels of %g x %g x %g mm", v.spacing_mm().x(), v.spacing_mm().y(),
                         v.spacing_mm().z())));
  // A composed volume's colours came with the structures.
  if (!composed_volume) PBA_RETURN_IF_ERROR(ReadVolumeTable(options.colour_table, result));
  if (!options.label_steps.empty()) {
    LabelAtlas atlas{std::move(result->volume), std::move(result->colours)};
    const Status applied = ApplyLabelSteps(options.label_steps, &atlas, &result->notes);
    result->volume = std::move(atlas.volume);
    result->colours = std::move(atlas.table);
    PBA_RETURN_IF_ERROR(applied);
  }
  if (options.source == AtlasBuildOptions::Source::kLabelVolume && options.island_share > 0) {
    LabelAtlas atlas{std::move(result->volume), std::move(result->colours)};
    if (DropIslands(options.island_share, &atlas, &result->islands)) {
      result->notes.push_back(result->islands);
    }
    result->volume = std::move(atlas.volume);
    result->colours = std::move(atlas.table);
  }
  return Status::Ok();
}

// Rounds of moving slivers across interfaces, each followed by an
// improvement pass.
constexpr int kRelabelRounds = 3;

// The longest edge collapsed that moves a surface or interface node, as a
// share of the facet distance: the mesher leaves the surfaces up to that far
// from the voxels' boundaries, and a collapse moves a node by at most half
// of it, most often along a surface or along the line where three meet.
constexpr double kCollapseShareOfFacetDistance = 0.5;

// Rounds of collapsing short edges and peeling slivers off the outer
// surface: peeling lays bare tetrahedra that were inside, some of them
// slivers around a short edge now on the surface.
constexpr int kCollapseRounds = 2;

// Short edges of the slivers collapsed (mesh/collapse.h): the edges of a
// few hundredths of a millimetre a mesher leaves where an interface meets
// the outer surface, whose slivers no flip or node move inside a structure
// can reach. A short improvement pass follows when any went.
Status CollapseAtlasEdges(const AtlasBuildOptions& options, const ImproveOptions& improve,
                          AtlasBuildResult* result) {
  CollapseOptions collapse;
  collapse.target_min_dihedral_deg = improve.target_min_dihedral_deg;
  collapse.target_aspect_ratio = improve.target_aspect_ratio;
  const double facet_distance_mm =
      options.facet_distance_mm > 0 ? options.facet_distance_mm : options.facet_size_mm / 4;
  collapse.max_edge_m = kCollapseShareOfFacetDistance * facet_distance_mm * 1e-3;
  CollapseStats stats;
  PBA_RETURN_IF_ERROR(CollapseShortEdges(collapse, &result->mesh, &stats));
  CollapseStats& total = result->collapsed;
  if (total.min_dihedral_before_deg == 0)
    total.min_dihedral_before_deg = stats.min_dihedral_before_deg;
  total.min_dihedral_after_deg = stats.min_dihedral_after_deg;
  total.edges += stats.edges;
  total.removed_tetrahedra += stats.removed_tetrahedra;
  total.longest_m = std::max(total.longest_m, stats.longest_m);
  total.longest_surface_m = std::max(total.longest_surface_m, stats.longest_surface_m);
  if (stats.edges == 0) return Status::Ok();
  ImproveStats later;
  PBA_RETURN_IF_ERROR(ImproveTetMesh(improve, &result->mesh, &later));
  AddLaterPass(later, &result->improvement);
  return Status::Ok();
}

void AddRemoved(const RemovedTetrahedra& more, RemovedTetrahedra* total) {
  total->tetrahedra += more.tetrahedra;
  total->volume_m3 += more.volume_m3;
  std::vector<std::string> regions;
  std::set_union(total->regions.begin(), total->regions.end(), more.regions.begin(),
                 more.regions.end(), std::back_inserter(regions));
  total->regions = std::move(regions);
}

// The improvement pass (mesh/improve.h), the slivers moved across
// interfaces with short passes after, then rounds of short edges of the
// slivers left collapsed and the slivers still on the outer surface peeled.
Status ImproveAtlasMesh(const AtlasBuildOptions& options, AtlasBuildResult* result) {
  ImproveOptions improve;
  improve.target_min_dihedral_deg = options.improve_target_deg;
  improve.target_aspect_ratio = options.improve_aspect_ratio;
  improve.max_passes = 10;
  // (A pass on the angle alone first, then one with the aspect ratio, left
  // AAL at 3 mm with 7 structures over the aspect-ratio bound instead of 1,
  // and 1 under the angle bound instead of 2.)
  PBA_RETURN_IF_ERROR(ImproveTetMesh(improve, &result->mesh, &result->improvement));
  // What flips cannot reach: slivers pinned between two faces of one
  // interface. Moved across it, they get neighbours of their own region,
  // and a later pass removes them; that pass can pin others. The later
  // passes are short: the rest of the mesh has had its full improvement.
  // (On the angle alone they would be shorter still, but they then undo
  // the aspect ratios of small structures: on AAL at 6 mm, 21 structures
  // with an aspect-ratio p99 of 5 or more instead of 1.)
  improve.max_passes = 1;
  for (int round = 0; round < kRelabelRounds; ++round) {
    const RelabelStats moved =
        RelabelInterfaceSlivers(improve.target_min_dihedral_deg, &result->mesh);
    if (moved.tetrahedra == 0) break;
    result->relabelled.tetrahedra += moved.tetrahedra;
    result->relabelled.volume_m3 += moved.volume_m3;
    ImproveStats later;
    PBA_RETURN_IF_ERROR(ImproveTetMesh(improve, &result->mesh, &later));
    AddLaterPass(later, &result->improvement);
  }
  for (int round = 0; round < kCollapseRounds; ++round) {
    const int collapsed = result->collapsed.edges;
    PBA_RETURN_IF_ERROR(CollapseAtlasEdges(options, improve, result));
    const RemovedTetrahedra peeled =
        PeelBoundarySlivers(improve.target_min_dihedral_deg, &result->mesh);
    AddRemoved(peeled, &result->peeled);
    if (peeled.tetrahedra == 0 && result->collapsed.edges == collapsed) break;
  }
  return Status::Ok();
}

std::string Counted(int n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The notes of what was taken out of the mesh after meshing.
void NoteRemoved(const AtlasBuildResult& result, std::vector<std::string>* notes) {
  const auto regions = [](const RemovedTetrahedra& removed) {
    std::string text;
    for (std::size_t i = 0; i < removed.regions.size() && i < 8; ++i)
      text += (i > 0 ? ", " : "") + removed.regions[i];
    if (removed.regions.size() > 8) text += Format(" and %zu more", removed.regions.size() - 8);
    return text;
  };
  if (const CollapseStats& c = result.collapsed; c.edges > 0) {
    const std::string moved = c.longest_surface_m > 0
                                  ? Format("surface and interface nodes moved by at most %.3g mm",
                                           c.longest_surface_m * 1e3)
                                  : std::string("only nodes inside structures moved");
    notes->push_back(
        Format("%s collapsed (%s around them taken out, %s): no flip or node move "
               "could lift the slivers around them",
               Counted(c.edges, "short edge", "short edges").c_str(),
               Counted(c.removed_tetrahedra, "sliver", "slivers").c_str(), moved.c_str()));
  }
  if (const RemovedTetrahedra& p = result.peeled; p.tetrahedra > 0) {
    notes->push_back(Format(
        "%s on the outer surface taken out (%.3g mm^3, in %s): no flip or node move could "
        "lift them",
        Counted(p.tetrahedra, "sliver", "slivers").c_str(), p.volume_m3 * 1e9, regions(p).c_str()));
  }
  if (const RemovedTetrahedra& f = result.dropped_fragments; f.tetrahedra > 0) {
    notes->push_back(
        Format("%s of the mesh joined to the rest by no face taken out (%s, %.3g mm^3, in %s): "
               "nothing could hold them",
               Counted(result.fragments, "fragment", "fragments").c_str(),
               Counted(f.tetrahedra, "tetrahedron", "tetrahedra").c_str(), f.volume_m3 * 1e9,
               regions(f).c_str()));
  }
}

// Whether a structure's tetrahedra miss the quality bounds.
bool MissesBounds(const QualityStats& q) {
  return q.count > 0 &&
         (q.p99_aspect_ratio >= kAspectRatioP99Bound || q.min_dihedral_deg <= kMinDihedralBoundDeg);
}

// The structures that miss the quality bounds, named with what they miss.
void NoteQualityMisses(AtlasBuildResult* result) {
  std::vector<std::string> misses;
  const std::vector<QualityStats>& regions = result->quality.regions;
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const QualityStats& q = regions[r];
    if (!MissesBounds(q)) continue;
    std::string what;
    if (q.p99_aspect_ratio >= kAspectRatioP99Bound)
      what = Format("aspect-ratio p99 %.2f", q.p99_aspect_ratio);
    if (q.min_dihedral_deg <= kMinDihedralBoundDeg) {
      what += Format("%ssmallest dihedral angle %.1f deg", what.empty() ? "" : ", ",
                     q.min_dihedral_deg);
    }
    if (!what.empty()) misses.push_back(result->mesh.region_names[r] + " (" + what + ")");
  }
  if (misses.empty()) return;
  std::string list;
  for (std::size_t i = 0; i < misses.size() && i < 10; ++i) list += (i > 0 ? ", " : "") + misses[i];
  if (misses.size() > 10) list += Format(" and %zu more", misses.size() - 10);
  result->notes.push_back(Format(
      "%zu of %zu structures miss the quality bounds (aspect-ratio p99 under %g, every dihedral "
      "angle over %g deg): %s. The quality report has every structure's figures; smaller "
      "elements there (a region of interest, smaller cell and facet sizes, or quality rounds: "
      "pba-atlas build --quality-rounds) may reach them",
      misses.size(), regions.size(), kAspectRatioP99Bound, kMinDihedralBoundDeg, list.c_str()));
}

// A mesh in several pieces joined by no face: each, in a note.
void NoteMeshPieces(AtlasBuildResult* result) {
  const std::vector<int> piece = MeshPieces(result->mesh, &result->pieces);
  if (result->pieces <= 1) return;
  std::vector<int> count(result->pieces, 0);
  for (int p : piece) ++count[p];
  std::sort(count.rbegin(), count.rend());
  std::string sizes;
  for (std::size_t i = 0; i < count.size() && i < 6; ++i) {
    sizes += (i > 0 ? ", " : "") + std::to_string(count[i]);
  }
  if (count.size() > 6) sizes += ", ...";
  result->notes.push_back(Format(
      "the mesh is in %d pieces joined by no face (%s tetrahedra): a scene must hold each of "
      "them, or its solve is refused naming those it does not",
      result->pieces, sizes.c_str()));
}

// One mesh of the chosen regions with `sizes`, improved, its fragments
// dropped: everything of `result` a mesh decides, made anew; the times add
// up over the rounds.
Status MeshAndImprove(const AtlasBuildOptions& options, const RegionSizes& sizes,
                      AtlasBuildResult* result) {
  result->improvement = ImproveStats();
  result->relabelled = RelabelStats();
  result->collapsed = CollapseStats();
  result->peeled = result->dropped_fragments = RemovedTetrahedra();
  result->fragments = 0;
  Clock::time_point start = Clock::now();
  PBA_RETURN_IF_ERROR(MeshVolume(options, result->volume, result->colours, result->region_labels,
                                 sizes, &result->mesh, &result->mesher));
  result->times.mesh_s += SecondsSince(start);
  if (options.improve_target_deg > 0) {
    start = Clock::now();
    PBA_RETURN_IF_ERROR(ImproveAtlasMesh(options, result));
    result->times.improve_s += SecondsSince(start);
  }
  if (options.island_share > 0) {
    result->dropped_fragments =
        DropMeshFragments(options.island_share, &result->mesh, &result->fragments);
  }
  return Status::Ok();
}

// Each structure's bounds of the round before, or the build's.
constexpr double kRoundShrink = 0.7;

// What a mesh of MeshAndImprove decides, kept aside while another is made.
struct MeshRound {
  Mesh mesh;
  LabelMeshReport mesher;
  ImproveStats improvement;
  RelabelStats relabelled;
  CollapseStats collapsed;
  RemovedTetrahedra peeled, dropped_fragments;
  int fragments = 0;
  RegionSizes sizes;
  std::vector<int> rounds;  // per region: the rounds it was refined in
  int misses = 0;           // structures missing the bounds
};

// The fields of one mesh, from a result into a round or back.
template <typename From, typename To>
void MoveMeshFields(From& from, To* to) {
  to->mesh = std::move(from.mesh);
  to->mesher = std::move(from.mesher);
  to->improvement = from.improvement;
  to->relabelled = from.relabelled;
  to->collapsed = from.collapsed;
  to->peeled = std::move(from.peeled);
  to->dropped_fragments = std::move(from.dropped_fragments);
  to->fragments = from.fragments;
}

// The first mesh, and up to options.quality_rounds more while structures
// miss the bounds, theirs at kRoundShrink of their sizes each round but
// never under the voxels' edge (finer, a mesh follows the voxels' steps).
// The mesh with the fewest structures missing is kept, the earliest of
// equals: a round remeshes the whole atlas, and can make a sliver where
// there was none.
Status MeshInRounds(const AtlasBuildOptions& options, AtlasBuildResult* result) {
  if (options.quality_rounds == 0) return MeshAndImprove(options, {}, result);
  const size_t n = result->region_labels.size();
  const double voxel_mm = result->volume.spacing_mm().minCoeff();
  // The facets small structures get anyway (facets_per_section).
  const std::vector<double> small =
      StructureFacetSizes(options, result->volume, result->region_labels);
  MeshRound best;
  RegionSizes sizes;
  std::vector<int> rounds(n, 0);
  for (int round = 0;; ++round) {
    PBA_RETURN_IF_ERROR(MeshAndImprove(options, sizes, result));
    result->meshes = round + 1;
    const QualitySummary quality = Summarise(result->mesh);
    std::vector<size_t> missing;
    for (size_t r = 0; r < n && r < quality.regions.size(); ++r) {
      if (MissesBounds(quality.regions[r])) missing.push_back(r);
    }
    const bool last = round == options.quality_rounds || missing.empty();
    if (round == 0 || static_cast<int>(missing.size()) < best.misses) {
      MoveMeshFields(*result, &best);
      best.sizes = sizes;
      best.rounds = rounds;
      best.misses = static_cast<int>(missing.size());
    }
    if (last) break;
    bool any = false;
    for (size_t r : missing) {
      if (sizes.cell_mm.empty()) {
        sizes.cell_mm.assign(n, 0);
        sizes.facet_mm.assign(n, 0);
      }
      const double cell = sizes.cell_mm[r] > 0 ? sizes.cell_mm[r] : options.cell_size_mm;
      double facet = sizes.facet_mm[r] > 0 ? sizes.facet_mm[r] : options.facet_size_mm;
      if (r < small.size() && small[r] > 0) facet = std::min(facet, small[r]);
      // As fine as it goes: a round would mesh it as before.
      if (cell <= voxel_mm && facet <= voxel_mm) continue;
      sizes.cell_mm[r] = std::max(voxel_mm, kRoundShrink * cell);
      sizes.facet_mm[r] = std::max(voxel_mm, kRoundShrink * facet);
      ++rounds[r];
      any = true;
    }
    if (!any) break;
  }
  if (best.rounds.empty() || best.rounds == std::vector<int>(n, 0)) {
    // The first mesh kept: say what was tried.
    std::string tried;
    for (size_t r = 0; r < n && result->meshes > 1; ++r) {
      if (rounds[r] == 0) continue;
      tried += Format("%s%s (cells %.3g mm, facets %.3g mm)", tried.empty() ? "" : ", ",
                      result->mesh.region_names[r].c_str(), sizes.cell_mm[r], sizes.facet_mm[r]);
    }
    if (!tried.empty()) {
      result->notes.push_back(
          Format("%d meshes: none with structures refined had fewer structures missing the quality "
                 "bounds than the first, which is kept; refined down to: %s",
                 result->meshes, tried.c_str()));
    }
  }
  MoveMeshFields(best, result);
  const QualitySummary quality = Summarise(result->mesh);
  for (size_t r = 0; r < n; ++r) {
    if (best.rounds.empty() || best.rounds[r] == 0) continue;
    result->refined.push_back({result->mesh.region_names[r], best.rounds[r], best.sizes.cell_mm[r],
                               best.sizes.facet_mm[r], !MissesBounds(quality.regions[r])});
  }
  return Status::Ok();
}

// The quality rounds' structures: the sizes that met the bounds, or did not.
void NoteRefined(AtlasBuildResult* result) {
  if (result->refined.empty()) return;  // MeshInRounds said why, if it tried
  std::string met, missed;
  for (const RefinedStructure& s : result->refined) {
    (s.met ? met : missed) +=
        Format("%s%s (cells %.3g mm, facets %.3g mm)", (s.met ? met : missed).empty() ? "" : ", ",
               s.name.c_str(), s.cell_size_mm, s.facet_size_mm);
  }
  result->notes.push_back(
      Format("%d meshes: the one kept has %zu structure%s refined where the quality bounds "
             "were missed; met at: %s; still missed at: %s",
             result->meshes, result->refined.size(), result->refined.size() == 1 ? "" : "s",
             met.empty() ? "none" : met.c_str(), missed.empty() ? "none" : missed.c_str()));
}

}  // namespace

std::optional<MidsideProjectionReport> CurveAtlasMidsideNodes(const AtlasBuildResult& result,
                                                              Mesh* mesh) {
  if (!result.loft) return std::nullopt;
  return ProjectMidsideNodes(*result.loft, RegionLabelSets(*result.loft, result.region_labels),
                             MidsideProjectionOptions(), mesh);
}

Status AtlasBuildOptions::Validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (source != Source::kSynthetic && input.empty()) {
    return Status::InvalidArgument("input", "a plate directory or label volume file is required");
  }
  if (source == Source::kSynthetic && plates_dir.empty()) {
    return Status::InvalidArgument("plates_dir",
                                   "the synthetic atlas needs a directory for its plates");
  }
  if (!(island_share >= 0 && island_share < 1)) {
    return Status::InvalidArgument("island_share", "must lie in [0, 1)");
  }
  if (!label_steps.empty() && source != Source::kLabelVolume) {
    return Status::InvalidArgument("label_steps", "label algebra works on a label volume source");
  }
  if (!positive(synthetic_voxel_mm)) {
    return Status::InvalidArgument("synthetic_voxel_mm", "must be positive");
  }
  if (!positive(loft_voxel_mm) && !(source == Source::kStructures && loft_voxel_mm == 0)) {
    return Status::InvalidArgument("loft_voxel_mm",
                                   "must be positive (or, for a structure set, 0: its masks' own)");
  }
  if (!positive(cell_size_mm)) return Status::InvalidArgument("cell_size_mm", "must be positive");
  if (!positive(facet_size_mm)) return Status::InvalidArgument("facet_size_mm", "must be positive");
  if (!std::isfinite(facets_per_section) || facets_per_section < 0) {
    return Status::InvalidArgument("facets_per_section",
                                   "must be 0 (the facet size everywhere) or positive");
  }
  if (odt_iterations < 0) return Status::InvalidArgument("odt_iterations", "must be >= 0");
  if (!(improve_aspect_ratio == 0 ||
        (improve_aspect_ratio >= 1.5 && std::isfinite(improve_aspect_ratio)))) {
    return Status::InvalidArgument("improve_aspect_ratio",
                                   "must be 0 (the dihedral angle alone) or at least 1.5");
  }
  if (!(improve_target_deg >= 0 && improve_target_deg < 70.5)) {
    return Status::InvalidArgument("improve_target_deg",
                                   "must lie in [0, 70.5) degrees (0: no improvement pass)");
  }
  if (!(optimisation_time_limit_s >= 0)) {
    return Status::InvalidArgument("optimisation_time_limit_s", "must be >= 0 (0: no limit)");
  }
  if (!std::isfinite(facet_distance_mm) || facet_distance_mm < 0) {
    return Status::InvalidArgument("facet_distance_mm",
                                   "must be 0 (a quarter of the facet size) or positive");
  }
  if (quality_rounds < 0 || quality_rounds > 5) {
    return Status::InvalidArgument("quality_rounds", "must be 0 (one mesh) to 5");
  }
  return Status::Ok();
}

Status BuildAtlas(const AtlasBuildOptions& options, AtlasBuildResult* result) {
  if (Status s = options.Validate(); !s.ok()) return s;
  *result = AtlasBuildResult();
  Clock::time_point start = Clock::now();

  result->synthetic = options.source == AtlasBuildOptions::Source::kSynthetic;
  std::filesystem::path plates_dir = options.input;
  if (options.source == AtlasBuildOptions::Source::kSynthetic) {
    SyntheticAtlasOptions synthetic;
    synthetic.voxel_size_mm = options.synthetic_voxel_mm;
    if (Status s = synthetic.Validate(); !s.ok()) {
      return Status::InvalidArgument("synthetic_voxel_mm", s.message());
    }
    const LabelVolume painted = MakeSyntheticAtlas(synthetic);
    if (Status s = WritePlates(painted, ColourTable::Builtin(), PlateOptions(), options.plates_dir);
        !s.ok()) {
      return s;
    }
    plates_dir = options.plates_dir;
  }
  // A structure set is composed into plates (every structure contours) or a
  // label volume, and goes on as that source would.
  std::optional<PlateStack> composed_plates;
  bool composed_volume = false;
  if (options.source == AtlasBuildOptions::Source::kStructures) {
    StructureSet set;
    PBA_RETURN_IF_ERROR(ReadStructureSet(options.input, &set));
    ComposeOptions compose;
    compose.voxel_size_mm = options.loft_voxel_mm;
    ComposedAtlas atlas;
    PBA_RETURN_IF_ERROR(ComposeStructureSet(options.input, set, compose, &atlas));
    result->notes = std::move(atlas.notes);
    if (atlas.plates) {
      composed_plates = std::move(atlas.plates);
    } else {
      result->volume = std::move(*atlas.volume);
      result->colours = std::move(atlas.colours);
      composed_volume = true;
    }
  }
  if (options.source == AtlasBuildOptions::Source::kLabelVolume || composed_volume) {
    PBA_RETURN_IF_ERROR(ReadVolumeSource(options, composed_volume, result));
    result->times.source_s = SecondsSince(start);
  } else {
    PlateStack stack;
    if (composed_plates) {
      stack = std::move(*composed_plates);
    } else if (Status s = ReadPlates(plates_dir, &stack); !s.ok()) {
      return s;
    }
    PBA_RETURN_IF_ERROR(CheckExtent(
        Eigen::Vector3d(stack.width * stack.pixel_size_mm, stack.height * stack.pixel_size_mm,
                        stack.z_mm.back() - stack.z_mm.front()),
        "pixel_size_mm",
        (composed_plates ? options.input / kStructureSetManifest : plates_dir / "plates.json")
            .string(),
        Format("%d x %d pixels of %g mm", stack.width, stack.height, stack.pixel_size_mm)));
    result->times.source_s = SecondsSince(start);
    start = Clock::now();
    LoftOptions loft_options;
    loft_options.voxel_size_mm = options.loft_voxel_mm > 0 ? options.loft_voxel_mm : 1.5;
    auto loft = std::make_shared<LoftField>();
    if (Status s = loft->Build(stack, loft_options); !s.ok()) return s;
    result->volume = loft->volume();
    result->loft = std::move(loft);
    result->colours = stack.colours;
    result->plates = std::move(stack);
    result->times.loft_s = SecondsSince(start);
  }

  std::vector<std::string> left_out;
  PBA_RETURN_IF_ERROR(ChooseLabels(options, result->colours, result->volume, &result->region_labels,
                                   &left_out, &result->absent));
  if (options.merge_rest && !left_out.empty()) {
    result->region_labels.push_back(0);
    result->merged = std::move(left_out);
  } else {
    result->dropped = std::move(left_out);
  }
  PBA_RETURN_IF_ERROR(MeshInRounds(options, result));
  NoteRemoved(*result, &result->notes);
  NoteMeshPieces(result);
  if (options.quadratic) {
    start = Clock::now();
    result->mesh = MakeQuadratic(result->mesh);
    result->projection = CurveAtlasMidsideNodes(*result, &result->mesh);
    result->times.quadratic_s = SecondsSince(start);
  }
  start = Clock::now();
  result->quality = Summarise(result->mesh);
  NoteRefined(result);
  NoteQualityMisses(result);
  result->times.quality_s = SecondsSince(start);
  if (result->plates && options.validate) {
    start = Clock::now();
    // Only the structures kept are judged: the plates without the others
    // (merged or dropped ones would otherwise count as missing).
    PlateStack kept = *result->plates;
    if (!options.structures.empty()) {
      std::vector<bool> keep(65536, false);
      for (uint16_t label : result->region_labels) keep[label] = label != 0;
      for (std::vector<uint16_t>& plate : kept.labels) {
        for (uint16_t& label : plate) label = keep[label] ? label : 0;
      }
    }
    GeometricValidation validation;
    if (Status s = ValidateAgainstPlates(result->mesh, result->region_labels, kept, options.threads,
                                         &validation);
        !s.ok()) {
      return s;
    }
    result->validation = std::move(validation);
    result->times.validation_s = SecondsSince(start);
  }
  return Status::Ok();
}

ReportTable QualityReportTable(const AtlasBuildResult& result) {
  ReportTable table;
  table.title = "Mesh quality per structure";
  table.columns = {{"structure", "structure", 0},
                   {"label", "label", 0},
                   {"elements", "elements", 0},
                   {"nodes", "nodes", 0},
                   {"volume [mm^3]", "volume_mm3", 1},
                   {"AR min", "aspect_ratio_min", 2},
                   {"AR median", "aspect_ratio_median", 2},
                   {"AR p99", "aspect_ratio_p99", 2},
                   {"AR max", "aspect_ratio_max", 2},
                   {"min dihedral [deg]", "min_dihedral_deg", 1},
                   {"max Jacobian ratio", "max_jacobian_ratio", 3}};
  // Nodes of each region's elements (corner and mid-edge; a node on an
  // interface counts for both sides).
  const Mesh& mesh = result.mesh;
  std::vector<std::vector<bool>> touches(result.quality.regions.size(),
                                         std::vector<bool>(mesh.num_nodes(), false));
  std::vector<int64_t> nodes(touches.size(), 0);
  for (int e = 0; e < mesh.num_elements() && !mesh.element_region.empty(); ++e) {
    std::vector<bool>& seen = touches[mesh.element_region[e]];
    const auto count = [&](int node) {
      if (!seen[node]) nodes[mesh.element_region[e]] += 1;
      seen[node] = true;
    };
    for (int node : mesh.ElementNodes(e)) count(node);
  }
  const auto row = [](const std::string& name, std::optional<int64_t> label, int64_t node_count,
                      const QualityStats& q) {
    return std::vector<ReportCell>{ReportCell::Text(name),
                                   label ? ReportCell::Integer(*label) : ReportCell::Text(""),
                                   ReportCell::Integer(q.count),
                                   ReportCell::Integer(node_count),
                                   ReportCell::Real(q.volume * 1e9),
                                   ReportCell::Real(q.min_aspect_ratio),
                                   ReportCell::Real(q.median_aspect_ratio),
                                   ReportCell::Real(q.p99_aspect_ratio),
                                   ReportCell::Real(q.max_aspect_ratio),
                                   ReportCell::Real(q.min_dihedral_deg),
                                   ReportCell::Real(q.max_jacobian_ratio)};
  };
  for (size_t r = 0; r < result.quality.regions.size(); ++r) {
    const uint16_t label = result.region_labels.at(r);
    table.rows.push_back(row(result.mesh.region_names[r],
                             label != 0 ? std::optional<int64_t>(label) : std::nullopt, nodes[r],
                             result.quality.regions[r]));
  }
  table.footer = row("overall", std::nullopt, mesh.num_nodes(), result.quality.overall);
  return table;
}

}  // namespace pba
