// A structure set: an atlas as separate structures, each in the form people
// edit it with (plate contours, a label mask, a closed surface). It is the
// form a snapshot of the atlas store takes on disk (`pba atlas snapshot
// export`, and the server's staging of a job against a snapshot), and the
// form an atlas import produces (structure_split.h). A scene's atlas source
// may name such a directory; BuildAtlas composes it into plates or a label
// volume and meshes that.
//
// A directory with manifest.json:
//   {"format": "pba-structure-set", "version": 1,      (optional on input)
//    "project": "...", "snapshot": 3, "snapshot_name": "...",   (optional)
//    "structures": [
//      {"name": "Putamen", "file": "Putamen.json",
//       "format": "contours_json" | "nifti" | "stl" | "obj" | "vtk" | "derived",
//       "colour": "r,g,b", "sha256": "<hex>",          (sha256 optional)
//       "revision": 4, "group_path": "...", "material_json": "{...}"},
//      ...]}
// `file` is relative to the directory, a plain file name. A nifti mask is
// every voxel with a non-zero value; a surface must be closed (its inside
// is where a ray crosses it an odd number of times). A derived structure's
// file is its recipe, a label step over the others (derived_structure.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "atlas/colour_table.h"
#include "atlas/label_volume.h"
#include "atlas/plates.h"
#include "atlas/structure_format.h"
#include "pba/status.h"

namespace pba {

struct StructureEntry {
  std::string name;  // non-empty; no '/', '\\', ',' or control characters
  std::string file;  // plain file name inside the set's directory
  StructureFormat format = StructureFormat::kContours;
  uint8_t r = 0, g = 0, b = 0;  // not 0,0,0 (background)
  std::string sha256;           // lowercase hex of the file; empty: not checked
  int64_t revision = 0;         // the store's revision number; 0: none
  std::string group_path;
  std::string material_json;
};

struct StructureSet {
  std::string project;
  int64_t snapshot = 0;
  std::string snapshot_name;
  std::vector<StructureEntry> structures;
};

inline constexpr char kStructureSetManifest[] = "manifest.json";

// Hands out the file names of a set's structures, for whoever writes a set
// (a job's staging of a snapshot, an export, a split): never the
// manifest's own name (a structure named "manifest" would otherwise be
// overwritten by the manifest, and its SHA-256 then fail), and never two
// names that differ only in ASCII case (one file on macOS and Windows).
// The manifest names each structure's file, so readers never derive it.
class StructureFileNames {
 public:
  // `stem` + `extension` when that is free, else `stem` + "_2" +
  // `extension`, "_3", ...: "manifest" + ".json" -> "manifest_2.json".
  std::string Take(const std::string& stem, const std::string& extension);

 private:
  std::set<std::string> taken_{kStructureSetManifest};  // case-folded
};

// Whether `dir` is a directory holding a manifest.json.
bool IsStructureSetDir(const std::filesystem::path& dir);

// Reads and checks manifest.json: at least one structure; names unique and
// well formed; files plain names, present, not manifest.json itself (and
// matching their sha256 when given); colours unique and not black. Errors are kInvalidArgument
// naming the entry, e.g. field "structures[3].colour", or kIo for an unreadable file.
Status ReadStructureSet(const std::filesystem::path& dir, StructureSet* set);

// Writes manifest.json into `dir` atomically (the structures' files are the
// caller's and must be there already). A structure whose file is
// manifest.json is refused (kInvalidArgument naming it): the manifest would
// overwrite it.
Status WriteStructureSet(const StructureSet& set, const std::filesystem::path& dir);

struct ComposeOptions {
  // Pixel edge of the plates composed from contours [mm]; 0: the finest
  // pixel_size_mm the contours carry, else 0.5.
  double pixel_size_mm = 0;
  // Voxel edge of the label volume composed when any structure is a mask
  // or a surface [mm]; 0: the masks' own (the smallest voxel edge any mask
  // has, so masks on one grid are taken voxel for voxel), 1 mm without
  // masks.
  double voxel_size_mm = 1.0;
  // A label volume even when every structure is contours (their lofts
  // voxelised): for measuring volumes and overlaps in mm^3.
  bool force_volume = false;
};

// The atlas a structure set makes, in the form BuildAtlas meshes:
//   every structure contours -> `plates`: one plate at each height any
//     structure has; a structure drawn at heights around one it is not
//     drawn at gets its section there interpolated from its own plates (as
//     the loft would), so it does not pinch at another's plate;
//   otherwise -> `volume`: a label volume on one grid of voxel_size_mm
//     covering every structure: masks sampled at the voxel centres (nearest
//     voxel), surfaces by their inside, contours by their loft.
// Labels are 1..n in byte-wise order of the names; `colours` maps them to
// the names and colours of the manifest. Where two structures claim a
// pixel or voxel, the one first in that order keeps it, and the overlap
// is reported in `notes` with its area or volume, e.g. "A and B overlap on
// 80 pixels (20 mm^2) at z = 3 mm; A keeps them" (one note per pair and
// plate; in a volume "... on N voxels (V mm^3)" per pair).
// The plate grid covers every polygon with three pixels to spare; its first
// pixel centre is half a pixel inside the leftmost and topmost points, so
// contours traced on a grid of the same pixel size come back onto it
// pixel for pixel. Contours drawn at a single height are refused when every
// structure is (a loft needs two plates); in a volume such a structure is
// lofted to nothing a voxel above and below its plate.
// Derived structures make it a volume: they are made on it once the others
// are in, in their order (OrderDerivedStructures), each under the lowest
// label it takes (a merge) or a free one, in its manifest colour, with a
// note saying what it made; they take part in no overlap.
struct ComposedOverlap {
  std::string kept, lost;  // the structure that keeps the voxels, and the other
  double mm3 = 0;
};

struct ComposedAtlas {
  ColourTable colours;
  std::optional<PlateStack> plates;
  std::optional<LabelVolume> volume;
  std::vector<std::string> notes;
  // With a volume: each structure's own volume before overlaps were
  // resolved (by name), and the overlaps [mm^3].
  std::map<std::string, double> structure_mm3;
  std::vector<ComposedOverlap> overlaps;
};

Status ComposeStructureSet(const std::filesystem::path& dir, const StructureSet& set,
                           const ComposeOptions& options, ComposedAtlas* atlas);

}  // namespace pba
