// Building a physics-based atlas: from its source (the built-in synthetic
// atlas, a plate stack, a label volume, or a structure set) to one
// conforming multi-material
// tetrahedral mesh whose regions are the structures, with the reports it is
// judged by.
//
//   synthetic ─► WritePlates ─┐
//   plate stack ──────────────┴─► ReadPlates ─► LoftField ─┐
//   label volume (NIfTI / NRRD) + colour table ────────────┴─► label volume
//   structure set ─► ComposeStructureSet ─► plates (all contours: as a
//     plate stack above) or a label volume with its colour table
//     ─► MeshLabels (CGAL Mesh_3) ─► [MakeQuadratic ─► ProjectMidsideNodes]
//     ─► Mesh (regions = structures) ─► quality report; against the plates,
//        when there are plates, the geometric validation.
//
// The synthetic source goes through real plate files (written into
// `plates_dir`), so it exercises the same path as a user's own plates.
//
// The mesher follows the label volume (nearest voxel), from plates the
// loft's voxelisation (LoftField::volume): its surfaces and interfaces are
// within the facet distance of the voxel faces, so the corners of the
// surface triangles lie within about half a voxel of the loft's smooth
// level sets. The 10-node pass puts the mid-edge nodes on those smooth
// level sets (LoftField::SignedDistance at any point). Meshing the smooth
// field itself (LoftField::Label) was tried and is not the default: the
// loft is linear in z between plates, so its surfaces are creased at every
// plate height and sharpest where a structure ends (a structure on one
// plate is a lens with a knife edge); on the synthetic atlas at 3 mm the
// creases gave slivers the improvement pass could not lift above 5 degrees,
// and geometric errors that moved across the 0.65 % limit with the facet
// setting, where the voxelisation's are steady (docs/atlas.md).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atlas/colour_table.h"
#include "atlas/geometric_validation.h"
#include "atlas/label_algebra.h"
#include "atlas/label_mesher.h"
#include "atlas/label_volume.h"
#include "atlas/loft.h"
#include "atlas/midside_projection.h"
#include "atlas/plates.h"
#include "atlas/report_format.h"
#include "core/thread_context.h"
#include "mesh/collapse.h"
#include "mesh/improve.h"
#include "mesh/mesh.h"
#include "mesh/quality.h"
#include "mesh/region_faces.h"
#include "pba/status.h"

namespace pba {

// The bounds an atlas mesh is judged by, per structure (docs/atlas.md):
// 99 % of its tetrahedra with an aspect ratio under kAspectRatioP99Bound
// and every dihedral angle over kMinDihedralBoundDeg. A build names the
// structures that miss them in a note.
inline constexpr double kAspectRatioP99Bound = 5;
inline constexpr double kMinDihedralBoundDeg = 5;

struct AtlasBuildOptions {
  enum class Source { kSynthetic, kPlates, kLabelVolume, kStructures };
  Source source = Source::kSynthetic;
  // kPlates: the plate directory (plates.h). kLabelVolume: a .nii, .nii.gz
  // or .nrrd file. kStructures: a structure-set directory (structure_set.h),
  // composed with voxel_size_mm = loft_voxel_mm and the contours' own pixel
  // size; from contours alone it goes on as plates (loft, 10-node curving,
  // geometric validation), else as a label volume with the set's colours.
  std::filesystem::path input;
  // kLabelVolume: the label table (colour_table.h CSV); empty: the built-in
  // table. (kStructures: unused, the manifest has the colours.)
  std::filesystem::path colour_table;
  // kSynthetic: where the rendered plates are written (must not exist).
  std::filesystem::path plates_dir;
  // kSynthetic: voxel edge of the painted atlas [mm].
  double synthetic_voxel_mm = 1.0;
  // Plates: voxel edge of the lofted label volume [mm]; structure sets:
  // also of the label volume composed from masks and surfaces, where 0
  // takes the masks' own voxels (ComposeOptions) and lofts at 1.5 mm.
  double loft_voxel_mm = 1.0;
  // Tetrahedron size inside the structures and on their surfaces [mm]
  // (LabelMeshOptions::cell_size_mm and facet_size_mm; facet distance
  // facet_size / 4 unless given).
  double cell_size_mm = 3;
  double facet_size_mm = 3;
  double facet_distance_mm = 0;
  // Small structures get smaller facets: a structure's surfaces at most its
  // mean axial section perimeter over this number (the perimeter of a disc
  // of its mean section area: volume over height), so a nucleus a few
  // millimetres across keeps its shape where the bulk is meshed at
  // facet_size_mm; its interfaces take the smaller bound of their two
  // structures. 0: facet_size_mm everywhere. The default 25 brings every
  // structure of the synthetic atlas below the 0.65 % geometric error at
  // 3 mm (docs/atlas.md).
  double facets_per_section = 25;
  // Passes of ODT smoothing before sliver removal (LabelMeshOptions::
  // odt_iterations); 0: none.
  int odt_iterations = 2;
  // After meshing, flips and smoothing of interior nodes
  // (mesh/improve.h) work on every tetrahedron whose smallest dihedral
  // angle is below this [degrees], without changing any structure's
  // geometry; 0: none.
  double improve_target_deg = 15;
  // And on every tetrahedron whose aspect ratio is above this
  // (ImproveOptions::target_aspect_ratio): interior needles and caps that
  // keep good angles; 0: the angle alone.
  double improve_aspect_ratio = 4;
  // Bound on each of the mesher's optimisation steps [s]
  // (LabelMeshOptions::optimisation_time_limit_s): a safeguard, generous so
  // that the iteration count and the sliver bound end them, not the
  // machine's load; a step that reaches it is named in `mesher`.
  double optimisation_time_limit_s = 120;
  // Region of interest (radius 0: none): elements of at most roi_size_mm
  // within roi_radius_mm of roi_centre_mm, growing to the sizes above over
  // one radius outside it (LabelMeshOptions).
  Eigen::Vector3d roi_centre_mm = Eigen::Vector3d::Zero();
  double roi_radius_mm = 0;
  double roi_size_mm = 0;
  // 10-node tetrahedra. From plates, the mid-edge nodes of the surface and
  // interface triangles are moved onto the loft's smooth surfaces
  // (ProjectMidsideNodes, with its defaults: at most a quarter of the edge,
  // Jacobian ratio at most 40), the others stay at the midpoints of the
  // straight edges. From a label volume every mid-edge node stays at its
  // midpoint: voxels give no smooth surface to move them to.
  bool quadratic = false;
  // Keep only these structures (colour-table names; a name that is not one
  // but prefixes some as "<name>: ..." stands for all of them, e.g.
  // "Thalamus" for the thalamic nuclei); empty: all. The
  // others are dropped, or with `merge_rest` meshed as one region,
  // kSurroundingTissue (region label 0: it is on no plate).
  std::vector<std::string> structures;
  bool merge_rest = false;
  // kLabelVolume: label algebra on the volume and its table before
  // anything else (label_algebra.h): fill, merge, overlay, cut...; each
  // step's note goes into the result's notes.
  std::vector<LabelStep> label_steps;
  // kLabelVolume, after the label algebra: pieces of the atlas (voxels
  // joined by faces) under this share of the largest piece's volume become
  // background, named in a note and in `islands` (DropIslands): a
  // fragment that touches nothing, or hangs on an edge or a corner, would
  // leave the stiffness singular. The mesh's own pieces (joined by faces)
  // under this share are taken out of it too, from any source (the mesher
  // can leave a tetrahedron hanging by an edge where voxels meet at one).
  // 0: none.
  double island_share = 1e-3;
  // Up to this many meshes again (0..5) after the first, while structures
  // miss the quality bounds (aspect-ratio p99 under kAspectRatioP99Bound,
  // every dihedral angle over kMinDihedralBoundDeg): each round bounds the
  // cells and facets of every structure that misses them to 0.7 times its
  // sizes of the round before, and meshes the whole atlas again. The last
  // mesh is kept; `refined` says, per structure refined, the sizes of its
  // last round and whether it met the bounds there. 0: one mesh, and a
  // note names the structures that miss.
  int quality_rounds = 0;
  // The mesher's sliver removal (LabelMeshOptions::perturb and exude),
  // seconds of a build. Off only for a mesh no one solves on: the
  // structures' surfaces a view draws (pba-solve --atlas-surfaces), whose
  // triangles it does not change.
  bool remove_slivers = true;
  // From plates: check the mesh against them (geometric_validation.h).
  bool validate = true;

  Status Validate() const;
  // The threads the geometric validation runs on (the mesher runs on one):
  // pba-atlas --threads, the server's solver threads.
  ThreadContext threads;
};

// A structure the quality rounds refined (AtlasBuildOptions::quality_rounds).
struct RefinedStructure {
  std::string name;
  int rounds = 0;                              // rounds it was refined in
  double cell_size_mm = 0, facet_size_mm = 0;  // its bounds in the last of them
  bool met = false;                            // the bounds met in the mesh kept
};

// The region the structures a build does not keep become with merge_rest.
inline constexpr char kSurroundingTissue[] = "Surrounding tissue";

struct AtlasBuildTimes {
  // quadratic_s: MakeQuadratic and ProjectMidsideNodes.
  double source_s = 0, loft_s = 0, mesh_s = 0, improve_s = 0, quadratic_s = 0, quality_s = 0,
         validation_s = 0;
};

struct AtlasBuildResult {
  bool synthetic = false;  // built from the synthetic atlas (its notice goes into every file)
  ColourTable colours;
  LabelVolume volume;                // the label volume the mesh was made from
  std::optional<PlateStack> plates;  // the plates, when the source had them
  // From plates: the loft at every point (its smooth surfaces), for
  // curving a 10-node version of `mesh` made later (CurveAtlasMidsideNodes).
  std::shared_ptr<const LoftField> loft;
  Mesh mesh;  // region r is structure region_labels[r]
  std::vector<uint16_t> region_labels;
  // Colour-table names of the structures merged into kSurroundingTissue
  // and of those dropped.
  std::vector<std::string> merged, dropped;
  // Colour-table names with no voxel in the volume (a table may list more
  // structures than an atlas has): reported, not an error, unless asked for
  // in `structures`.
  std::vector<std::string> absent;
  QualitySummary quality;
  std::optional<GeometricValidation> validation;
  AtlasBuildTimes times;
  ImproveStats improvement;  // the improvement pass (all zero without it)
  RelabelStats relabelled;   // slivers moved across an interface by it
  // Short edges of the slivers it left collapsed (CollapseShortEdges;
  // `longest_m` the longest, so the largest node move).
  CollapseStats collapsed;
  LabelMeshReport mesher;  // the mesher's steps: their times, and any cut short by its time limit
  // 10-node from plates: the mid-edge nodes moved onto the loft's surfaces.
  std::optional<MidsideProjectionReport> projection;
  // kStructures: what composing the set found worth saying (overlaps of
  // structures, and who kept the disputed pixels or voxels).
  std::vector<std::string> notes;
  // What DropIslands made background (empty: nothing), also in `notes`.
  std::string islands;
  // After the improvement: slivers in folds of the outer surface taken out
  // (PeelBoundarySlivers), and the mesh's fragments under island_share of
  // the largest piece's volume (DropMeshFragments, `fragments` of them);
  // both in `notes` when not empty.
  RemovedTetrahedra peeled, dropped_fragments;
  int fragments = 0;
  // The mesh's pieces joined by faces (MeshPieces); more than one is in
  // `notes`.
  int pieces = 1;
  // With quality_rounds: the structures refined, in region order; also in
  // `notes`. `meshes` counts the meshes made (1 + the rounds run).
  std::vector<RefinedStructure> refined;
  int meshes = 1;
};

Status BuildAtlas(const AtlasBuildOptions& options, AtlasBuildResult* result);

// Moves the boundary mid-edge nodes of `mesh`, a 10-node version of
// result.mesh (same nodes first, same regions, more face sets allowed),
// onto the loft's smooth surfaces (ProjectMidsideNodes with its defaults).
// Without a loft (a label volume) nothing moves: nullopt. BuildAtlas calls
// it when asked for 10-node tetrahedra; a scene's model builder calls it
// after cutting its patches and making its mesh quadratic.
std::optional<MidsideProjectionReport> CurveAtlasMidsideNodes(const AtlasBuildResult& result,
                                                              Mesh* mesh);

// The quality report: one row per structure (elements, nodes, volume [mm^3],
// aspect ratio min / median / max, smallest dihedral angle, largest Jacobian
// ratio) and an overall footer.
ReportTable QualityReportTable(const AtlasBuildResult& result);

}  // namespace pba
