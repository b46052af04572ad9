// Label algebra: steps that change an atlas in its voxel form, before it is
// meshed. A label volume holds one label per voxel, so the operations are
// robust where the same on surfaces (the "anti-solids" of a CAD kernel) are
// not: every result is again a label volume with a table.
//
//   keep       only these structures; the others become background
//   drop       these structures become background
//   merge      the union of several structures as one, under a new name
//   rename     a structure takes a new name
//   fill       background enclosed by the atlas becomes a named structure
//              (AAL leaves its white matter at 0, a cavity the deep nuclei
//              hang in): after a morphological closing of closing_mm, the
//              background the closed atlas encloses; of it, the largest
//              connected piece and every piece of at least min_piece_mm3
//   overlay    a second atlas (its volume and table) on this one's grid:
//              its structures take their voxels (over), or only the
//              background (under) - JHU white matter over AAL
//   resample   to a voxel edge of voxel_mm: each new voxel takes the label
//              most of its samples have (nearest neighbour when refining)
//   islands    pieces of the atlas (voxels joined by faces) smaller than
//              min_piece_mm3, the largest always kept, become background:
//              fragments that would mesh as parts touching nothing, or
//              joined to the rest by an edge or a corner only
//   cut        a region - a sphere, a cylinder, a mask file, or structures
//              of this atlas grown by a margin - taken out of structures
//              (all, or those named): the difference of structures, and
//              a resection (the surgical cavity of a scene); the voxels
//              become background or, given a name, a structure of their own
//
// Names are the table's, or a group ("Thalamus" for "Thalamus: ..."); a
// name that is neither is an error naming the step and the name, and a
// step that fails leaves the atlas as it was (ApplyLabelSteps works on a
// copy). Every step says what it did in a note: voxels and cm^3 changed.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "atlas/colour_table.h"
#include "atlas/label_volume.h"
#include "pba/status.h"

namespace pba {

// An atlas in voxels: a label volume and the table naming its values.
struct LabelAtlas {
  LabelVolume volume;
  ColourTable table;
};

// A region of space a cut takes out.
struct LabelRegion {
  enum class Kind { kSphere, kCylinder, kMask, kStructures };
  Kind kind = Kind::kSphere;
  // kSphere: centre and radius; kCylinder: the axis from `centre_mm` to
  // `end_mm` and the radius [mm].
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d end_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0;
  // kMask: a label volume file (.nii, .nii.gz, .nrrd) whose nonzero voxels
  // are the region, sampled at this atlas's voxel centres (nearest).
  std::filesystem::path mask;
  // kStructures: these structures of the atlas, grown by margin_mm (0: the
  // structures themselves, which a cut of other structures leaves as they
  // are: a voxel has one label).
  std::vector<std::string> structures;
  double margin_mm = 0;
};

struct LabelStep {
  enum class Kind { kKeep, kDrop, kMerge, kRename, kFill, kOverlay, kResample, kCut, kIslands };
  Kind kind = Kind::kKeep;
  // keep, drop, merge: the structures; overlay: the second atlas's
  // structures laid on (empty: all); cut: the structures cut (empty: all).
  std::vector<std::string> structures;
  // merge, fill: the new structure's name; rename: the new name; cut: what
  // the cut voxels become (empty: background).
  std::string name;
  std::string from;  // rename: the structure renamed
  // fill: the closing radius [mm] (0: only background no path leads out
  // of) and the smallest piece kept besides the largest [mm^3]; islands:
  // the smallest piece of the atlas kept besides the largest [mm^3].
  double closing_mm = 0;
  double min_piece_mm3 = 1000;
  // overlay: the second atlas; under: only where this one is background.
  std::filesystem::path volume, table;
  bool under = false;
  double voxel_mm = 0;  // resample
  LabelRegion region;   // cut
};

const char* LabelStepName(LabelStep::Kind kind);

// The automatic form of the islands step, which BuildAtlas runs on every
// label volume: pieces under `share` of the largest piece's volume become
// background; false (and no note) when there is none.
bool DropIslands(double share, LabelAtlas* atlas, std::string* note);

// Reads a label volume and its table (label_table.h: any format); an empty
// `table` is the built-in one, for the synthetic atlas's own volume only.
// A volume label the table does not name is kInvalidArgument on
// `table_field`; the table's notes go to `notes`.
Status ReadLabelAtlas(const std::filesystem::path& volume, const std::filesystem::path& table,
                      const std::string& volume_field, const std::string& table_field,
                      LabelAtlas* atlas, std::vector<std::string>* notes);

// The values of `step` that need no atlas to be checked: closing radius and
// margin in [0, 50] mm, smallest piece >= 0, voxel edge and radii positive,
// a cylinder's ends two points. kInvalidArgument on "<field>.<key>". Both
// ParseLabelSteps (so a recipe is refused when it is written) and
// ApplyLabelSteps call it.
Status CheckLabelStep(const LabelStep& step, const std::string& field);

// Applies `steps` in order to `atlas`; `notes` gets one line per step. On
// an error nothing of `atlas` has changed; the message names the step
// ("labels[2] (merge)") and what is wrong with it.
Status ApplyLabelSteps(const std::vector<LabelStep>& steps, LabelAtlas* atlas,
                       std::vector<std::string>* notes);

// The steps of a YAML sequence (a file of them, or a scene's
// geometry.atlas.labels), each a map with one key, the step's kind:
//   - keep: [Caudate_L, Caudate_R]     (or keep: {structures: [...]})
//   - drop: [Cerebelum_3_L]
//   - merge: {structures: [Caudate_L, Caudate_R], name: Caudate}
//   - rename: {from: Caudate, to: Caudate nucleus}
//   - fill: {name: White matter, closing_mm: 4, min_piece_mm3: 1000}
//   - overlay: {volume: jhu.nii.gz, table: jhu.txt, structures: [...], under: false}
//   - resample: {voxel_mm: 2}
//   - islands: {min_piece_mm3: 100}
//   - cut: {sphere: {centre_mm: [x, y, z], radius_mm: 10}, structures: [...], name: Cavity}
//          {cylinder: {from_mm: [..], to_mm: [..], radius_mm: 5}}
//          {mask: cavity.nii.gz}
//          {around: {structures: [...], margin_mm: 2}}
// Relative file names are taken from `base_dir`. Unknown keys, a missing
// one, a wrong type: kInvalidArgument on "<field>[i].<key>".
Status ParseLabelSteps(std::string_view yaml, const std::string& field,
                       const std::filesystem::path& base_dir, std::vector<LabelStep>* steps);

// The steps as canonical text (for a cache key: the same steps, the same
// text), and the files they read (overlay volumes and tables, masks), whose
// contents a cache key must cover too.
std::string DescribeLabelSteps(const std::vector<LabelStep>& steps);
std::vector<std::filesystem::path> LabelStepFiles(const std::vector<LabelStep>& steps);

}  // namespace pba
