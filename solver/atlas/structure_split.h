// Splitting an atlas into a structure set (structure_set.h): the import of
// plates or a label volume into the atlas store, one structure at a time.
//   plates (or the synthetic atlas, through its plates) -> each structure
//     as its plate contours (TraceContours), one <name>.json per structure;
//   label volume + colour table -> each structure as a label mask: a
//     gzip-compressed NIfTI-1 file of 0/1 voxels, cropped to the
//     structure's bounding box with one voxel of background around it,
//     spacing and position kept (<name>.nii.gz).
// Colours and names come from the colour table. Structures with no pixel
// or voxel are left out and listed in `absent`. <name> is the structure's
// name with every character other than [A-Za-z0-9._-] made '_' and leading
// dots dropped, made unique regardless of case with "_2", "_3", ... and
// never the manifest's name (StructureFileNames: a structure "manifest"
// from plates is manifest_2.json); a name of nothing but dots is refused.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "atlas/atlas_build.h"
#include "atlas/structure_set.h"
#include "pba/status.h"

namespace pba {

struct SplitOptions {
  // Which atlas: source, input, colour_table (and synthetic_voxel_mm for
  // the synthetic atlas) as for BuildAtlas; the other fields are unused.
  AtlasBuildOptions source;
  // Keep only these structures (names as in AtlasBuildOptions::structures,
  // group prefixes allowed); empty: all.
  std::vector<std::string> structures;
};

struct SplitResult {
  StructureSet set;  // as written into manifest.json
  // Colour-table names (of those asked for, when `structures` names some)
  // with no pixel or voxel.
  std::vector<std::string> absent;
};

// Writes the structure set into `dir`, which must not exist or be empty:
// every file and manifest.json, into a temporary directory beside it that
// is renamed into place, so it appears whole or not at all. A structure
// name that cannot be a file name is refused (kInvalidArgument naming it).
Status SplitAtlas(const SplitOptions& options, const std::filesystem::path& dir,
                  SplitResult* result);

}  // namespace pba
