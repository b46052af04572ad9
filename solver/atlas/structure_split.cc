#include "atlas/structure_split.h"

#include <stdlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "atlas/contours.h"
#include "atlas/label_table.h"
#include "atlas/label_volume_io.h"
#include "atlas/synthetic_atlas.h"
#include "core/atomic_write.h"
#include "core/format.h"
#include "core/sha256.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

// Which colour-table entries to split: all, or those named (a name that is
// not an entry stands for its group, "Thalamus" for "Thalamus: ...").
// `present` is whether each label has a pixel or voxel; a structure asked
// for by name that has none is an error, as for BuildAtlas.
Status ChooseEntries(const std::vector<std::string>& structures, const ColourTable& colours,
                     const std::vector<char>& present, std::vector<const ColourEntry*>* chosen) {
  std::vector<char> wanted(65536, structures.empty());
  for (size_t i = 0; i < structures.size(); ++i) {
    const std::string& name = structures[i];
    const std::string field = "structures[" + std::to_string(i) + "]";
    std::vector<const ColourEntry*> entries;
    PBA_RETURN_IF_ERROR(EntriesNamed(colours, name, field, &entries));
    bool any = false;
    for (const ColourEntry* e : entries) {
      any |= present[e->label] != 0;
      wanted[e->label] = 1;
    }
    if (!any) return Status::InvalidArgument(field, "\"" + name + "\" is not in the atlas");
  }
  chosen->clear();
  for (const ColourEntry& e : colours.entries()) {
    if (wanted[e.label]) chosen->push_back(&e);
  }
  return Status::Ok();
}

// The file name stem of a structure: its name with every character other
// than [A-Za-z0-9._-] (a multi-byte UTF-8 character counting as one) made
// '_', and leading dots dropped so the file is neither hidden nor "." or
// "..". Empty when nothing is left.
std::string FileStem(const std::string& name) {
  std::string stem;
  for (size_t i = 0; i < name.size(); ++i) {
    const unsigned char ch = static_cast<unsigned char>(name[i]);
    if ((ch & 0xc0) == 0x80 && i > 0) continue;  // UTF-8 continuation byte
    const bool keep = std::isalnum(ch) != 0 || ch == '.' || ch == '_' || ch == '-';
    stem += ch < 0x80 && keep ? static_cast<char>(ch) : '_';
  }
  stem.erase(0, stem.find_first_not_of('.'));
  return stem;
}

// A structure's file: its stem (FileStem) given out by StructureFileNames,
// the rule every writer of a structure set follows (never the manifest's
// name, never two names differing only in case).
Status TakeFileName(const std::string& name, const std::string& extension,
                    StructureFileNames* names, std::string* file) {
  const std::string stem = FileStem(name);
  if (stem.empty()) {
    return Status::InvalidArgument(
        "structures", "structure \"" + name + "\" gives no file name (nothing but dots)");
  }
  *file = names->Take(stem, extension);
  return Status::Ok();
}

// The manifest refuses these in a name (structure_set.h); refusing them
// here names the structure before anything is written for it.
Status CheckStructureName(const std::string& name) {
  for (unsigned char ch : name) {
    if (ch == '/' || ch == '\\' || ch == ',' || ch < 0x20 || ch == 0x7f) {
      return Status::InvalidArgument("structures",
                                     "structure \"" + name +
                                         "\" has a character a structure set refuses ('/', "
                                         "'\\\\', ',' or a control character)");
    }
  }
  return Status::Ok();
}

StructureEntry EntryFor(const ColourEntry& colour, const std::string& file,
                        StructureFormat format) {
  StructureEntry entry;
  entry.name = colour.name;
  entry.file = file;
  entry.format = format;
  entry.r = colour.r;
  entry.g = colour.g;
  entry.b = colour.b;
  return entry;
}

// Each chosen structure's contours into <stem>.json under `dir`.
Status SplitPlates(const PlateStack& stack, const std::vector<std::string>& structures,
                   const fs::path& dir, SplitResult* result) {
  std::vector<char> present(65536, 0);
  for (const std::vector<uint16_t>& plate : stack.labels) {
    for (uint16_t label : plate) present[label] = 1;
  }
  std::vector<const ColourEntry*> chosen;
  PBA_RETURN_IF_ERROR(ChooseEntries(structures, stack.colours, present, &chosen));
  StructureFileNames names;
  for (const ColourEntry* colour : chosen) {
    if (!present[colour->label]) {
      result->absent.push_back(colour->name);
      continue;
    }
    PBA_RETURN_IF_ERROR(CheckStructureName(colour->name));
    std::string file;
    PBA_RETURN_IF_ERROR(TakeFileName(colour->name, ".json", &names, &file));
    const Contours contours = TraceContours(stack, colour->label);
    PBA_RETURN_IF_ERROR(AtomicWriteText(dir / file, FormatContoursJson(contours)));
    result->set.structures.push_back(EntryFor(*colour, file, StructureFormat::kContours));
  }
  return Status::Ok();
}

// Each chosen structure's voxels as a 0/1 mask into <stem>.nii.gz under
// `dir`: the structure's bounding box and one voxel more on every side (so
// the mask's surface is closed even where the structure meets the edge of
// the grid), on the same lattice as `volume`.
Status SplitVolume(const LabelVolume& volume, const ColourTable& colours,
                   const std::vector<std::string>& structures, const fs::path& dir,
                   SplitResult* result) {
  constexpr int kMax = std::numeric_limits<int>::max();
  std::vector<std::array<int, 6>> box(65536, {kMax, kMax, kMax, -1, -1, -1});
  std::vector<char> present(65536, 0);
  for (int k = 0; k < volume.nz(); ++k) {
    for (int j = 0; j < volume.ny(); ++j) {
      for (int i = 0; i < volume.nx(); ++i) {
        const uint16_t label = volume.at(i, j, k);
        if (label == 0) continue;
        present[label] = 1;
        std::array<int, 6>& b = box[label];
        b = {std::min(b[0], i), std::min(b[1], j), std::min(b[2], k),
             std::max(b[3], i), std::max(b[4], j), std::max(b[5], k)};
      }
    }
  }
  for (size_t label = 1; label < present.size(); ++label) {
    if (present[label] && colours.FindByLabel(static_cast<uint16_t>(label)) == nullptr) {
      return Status::InvalidArgument(
          "source.colour_table",
          "label " + std::to_string(label) + " of the label volume has no entry");
    }
  }
  std::vector<const ColourEntry*> chosen;
  PBA_RETURN_IF_ERROR(ChooseEntries(structures, colours, present, &chosen));
  StructureFileNames names;
  for (const ColourEntry* colour : chosen) {
    if (!present[colour->label]) {
      result->absent.push_back(colour->name);
      continue;
    }
    PBA_RETURN_IF_ERROR(CheckStructureName(colour->name));
    std::string file;
    PBA_RETURN_IF_ERROR(TakeFileName(colour->name, ".nii.gz", &names, &file));
    const std::array<int, 6>& b = box[colour->label];
    const std::array<int, 3> first = {b[0] - 1, b[1] - 1, b[2] - 1};
    const std::array<int, 3> dims = {b[3] - b[0] + 3, b[4] - b[1] + 3, b[5] - b[2] + 3};
    const Eigen::Vector3d origin =
        volume.origin_mm() +
        Eigen::Vector3d(first[0], first[1], first[2]).cwiseProduct(volume.spacing_mm());
    LabelVolume mask(dims, origin, volume.spacing_mm());
    for (int k = b[2]; k <= b[5]; ++k) {
      for (int j = b[1]; j <= b[4]; ++j) {
        for (int i = b[0]; i <= b[3]; ++i) {
          if (volume.at(i, j, k) == colour->label) {
            mask.set(i - first[0], j - first[1], k - first[2], 1);
          }
        }
      }
    }
    PBA_RETURN_IF_ERROR(WriteNifti(mask, dir / file));
    result->set.structures.push_back(EntryFor(*colour, file, StructureFormat::kNifti));
  }
  return Status::Ok();
}

// Everything SplitAtlas writes, into the empty directory `dir`.
Status WriteSplit(const SplitOptions& options, const fs::path& dir, SplitResult* result) {
  using Source = AtlasBuildOptions::Source;
  const AtlasBuildOptions& source = options.source;
  if (source.source == Source::kLabelVolume) {
    LabelVolume volume;
    PBA_RETURN_IF_ERROR(ReadLabelVolume(source.input, "source.input", &volume));
    ColourTable colours = ColourTable::Builtin();
    if (!source.colour_table.empty()) {
      LabelTableRead read;
      PBA_RETURN_IF_ERROR(ReadLabelTable(source.colour_table, &colours, &read));
    } else {
      PBA_RETURN_IF_ERROR(LabelVolumeNeedsATable(volume, "source.colour_table"));
    }
    PBA_RETURN_IF_ERROR(SplitVolume(volume, colours, options.structures, dir, result));
  } else {
    PlateStack stack;
    if (source.source == Source::kSynthetic) {
      // Through real plate files, as BuildAtlas does, so the contours are
      // those of the plates `pba-atlas plates` writes; they are rendered
      // inside the staging directory and removed before it is renamed.
      SyntheticAtlasOptions synthetic;
      synthetic.voxel_size_mm = source.synthetic_voxel_mm;
      if (Status s = synthetic.Validate(); !s.ok()) {
        return Status::InvalidArgument("source.synthetic_voxel_mm", s.message());
      }
      const fs::path plates = dir / ".synthetic-plates";
      PBA_RETURN_IF_ERROR(WritePlates(MakeSyntheticAtlas(synthetic), ColourTable::Builtin(),
                                      PlateOptions(), plates));
      const Status read = ReadPlates(plates, &stack);
      std::error_code ec;
      fs::remove_all(plates, ec);
      PBA_RETURN_IF_ERROR(read);
      if (ec) return Status::Io("cannot remove " + plates.string() + ": " + ec.message());
    } else {
      PBA_RETURN_IF_ERROR(ReadPlates(source.input, &stack));
    }
    PBA_RETURN_IF_ERROR(SplitPlates(stack, options.structures, dir, result));
  }
  if (result->set.structures.empty()) {
    return Status::InvalidArgument("source", "the atlas has no structure to split");
  }
  for (StructureEntry& entry : result->set.structures) {
    PBA_RETURN_IF_ERROR(FileSha256Hex(dir / entry.file, &entry.sha256));
  }
  return WriteStructureSet(result->set, dir);
}

}  // namespace

Status SplitAtlas(const SplitOptions& options, const fs::path& dir, SplitResult* result) {
  *result = SplitResult();
  if (options.source.source != AtlasBuildOptions::Source::kSynthetic &&
      options.source.input.empty()) {
    return Status::InvalidArgument("source.input",
                                   "a plate directory or label volume file is required");
  }
  const Status status = AtomicWriteDirectory(
      dir, [&](const fs::path& temporary) { return WriteSplit(options, temporary, result); });
  if (!status.ok()) *result = SplitResult();
  return status;
}

}  // namespace pba
